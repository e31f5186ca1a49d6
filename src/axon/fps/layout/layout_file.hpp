// Layout files: the focal plane in YAML (format in docs/fps-layout.md).
//
//   name: default
//   pitch_mm: 22.4
//   neighbours: {robot_radius_mm: 48.26, adjacent_radius_mm: 24.64, fiducial_radius_mm: 30}  # optional
//   arms: {alpha_length_mm: 7.4, beta_tip_mm: 16.2, beta_collision_mm: 14.7276}  # optional
//   gateways:
//     - {id: 1, address: "10.25.1.11:19228", sextant: 1, channels: 4}
//   robots:
//     - {id: 1, x: 22.4, y: 0, sextant: 1, gateway: 1, bus: 1, fibres: [metrology, boss, apogee]}
//     - {id: 2, x: 44.8, y: 0, sextant: 1, gateway: 1, bus: 1, fibres: [boss], disabled: true,
//        offsets: {alpha: 0.12, beta: -0.05}, orientation_deg: -90, alpha_length_mm: 7.406,
//        beta_length_mm: 16.19, fibre_offsets: {metrology: [14.318, 0], boss: [14.964, -0.376]}}
//   fiducials:
//     - {id: 1, x: 0, y: 0}
//   guide_cameras:                                   # optional
//     - {id: 1, x1: -56.54, y1: 276.23, x2: 56.54, y2: 276.23, buffer_mm: 3}
//
// Every key added after the first version (arms, guide_cameras, the robots' orientation_deg,
// alpha_length_mm, beta_length_mm, fibre_offsets) is optional with the old fixed geometry as its
// default, and to_yaml() writes it only when it differs from that default.
//
// Every error names FILE:LINE:COL and the key: unknown keys, duplicate robot ids (with the line of
// the first), overlapping positions, a bus outside the gateway's channels, an undeclared gateway,
// a length not above 0, a guide camera of zero length or with a negative buffer.
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
