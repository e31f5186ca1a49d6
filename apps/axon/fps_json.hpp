// JSON of fps results shared by several `axon fps` subcommands (fps_layout.cpp, fps_plane.cpp).
#pragma once

#include "axon/fps/layout/layout_check_json.hpp"

namespace axon::app {

inline nlohmann::json layout_check_json(const fps::LayoutCheck& c) { return fps::to_json(c); }

}  // namespace axon::app
