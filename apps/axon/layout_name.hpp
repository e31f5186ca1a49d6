// Layouts named on the command line (fps/layout/layout_name.hpp), `default` and `benchtop` taken
// from this source tree's data/layouts.
#pragma once

#include "axon/fps/layout/layout_name.hpp"

#include <string>

namespace axon::app {

inline Result<fps::FocalPlane> resolve_layout(const std::string& name) {
#ifdef AXON_DATA_DIR
  return fps::resolve_layout(name, AXON_DATA_DIR);
#else
  return fps::resolve_layout(name);
#endif
}

}  // namespace axon::app
