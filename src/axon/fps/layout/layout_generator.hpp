// The default focal-plane layout, generated: 500 robots on a hexagonal grid in six sextants of
// 84/83 robots, four daisy chains (buses) of 20/21 robots per sextant, one gateway per sextant, and
// fiducials on empty grid sites. Deterministic: the same options give the same file.
//
// How it is built (docs/fps-layout.md): grid sites are taken ring by ring from the centre; the
// six-fold symmetry of the grid about a site puts exactly one site of every orbit (six sites at
// the same radius, 60 degrees apart) into each 60-degree wedge, so every wedge (sextant) gets the
// same sites up to rotation. The centre site and `fiducials_per_sextant` sites spread over the radii
// of every wedge become fiducials; the robots fill the next sites, sextants with one robot fewer
// (83 of 500) leaving their outermost site empty.
// Within a sextant the robots are split by azimuth into four chains (buses 1..4), and numbered
// sextant by sextant, chain by chain, from the centre outwards. Every robot carries boss and
// metrology fibres; `apogee_per_sextant` of them, spread evenly, also carry an apogee fibre.
#pragma once

#include "axon/core/error.hpp"
#include "axon/fps/layout/focal_plane.hpp"

#include <string>

namespace axon::fps {

struct LayoutGeneratorOptions {
  std::string name = "default";
  double pitch_mm = kDefaultPitchMm;
  int robots = 500;                 // 6 * 84 - 6 .. 6 * 84
  int fiducials_per_sextant = 10;   // plus one at the centre
  int apogee_per_sextant = 50;
  int buses_per_sextant = 4;
  // Gateway addresses: fmt pattern with the sextant number, e.g. "10.25.1.1{}:19228".
  std::string gateway_address = "10.25.1.1{}:19228";
};

[[nodiscard]] Result<FocalPlane> generate_layout(const LayoutGeneratorOptions& options = {});

}  // namespace axon::fps
