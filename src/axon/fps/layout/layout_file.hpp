// Layout files: the focal plane in YAML (format in docs/fps-layout.md).
//
//   name: default
//   pitch_mm: 22.4
//   neighbours: {robot_radius_mm: 48.26, adjacent_radius_mm: 24.64, fiducial_radius_mm: 30}  # optional
//   gateways:
//     - {id: 1, address: "10.25.1.11:19228", sextant: 1, channels: 4}
//   robots:
//     - {id: 1, x: 22.4, y: 0, sextant: 1, gateway: 1, bus: 1, fibres: [metrology, boss, apogee]}
//     - {id: 2, x: 44.8, y: 0, sextant: 1, gateway: 1, bus: 1, fibres: [boss], disabled: true,
//        offsets: {alpha: 0.12, beta: -0.05}}
//   fiducials:
//     - {id: 1, x: 0, y: 0}
//
// Every error names FILE:LINE:COL and the key: unknown keys, duplicate robot ids (with the line of
// the first), overlapping positions, a bus outside the gateway's channels, an undeclared gateway.
#pragma once

#include "axon/core/config.hpp"
#include "axon/core/error.hpp"
#include "axon/fps/layout/focal_plane.hpp"

#include <string>

namespace axon::fps {

[[nodiscard]] Result<FocalPlane> load_layout(const core::ConfigNode& root);
[[nodiscard]] Result<FocalPlane> load_layout_file(const std::string& path);

// The layout as a file load_layout() reads back to the same plane (one robot per line).
[[nodiscard]] std::string to_yaml(const FocalPlane& plane);

}  // namespace axon::fps
