// Layouts named on the command line: a file path, or `default` / `benchtop` (the layouts shipped in
// data/layouts; `default` is also generated when the data directory is not there).
#pragma once

#include "axon/fps/layout/focal_plane.hpp"
#include "axon/fps/layout/layout_file.hpp"
#include "axon/fps/layout/layout_generator.hpp"

#include <filesystem>
#include <string>

namespace axon::app {

inline Result<fps::FocalPlane> resolve_layout(const std::string& name) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_regular_file(name, ec)) return fps::load_layout_file(name);
  if (name == "default" || name == "benchtop") {
#ifdef AXON_DATA_DIR
    const fs::path shipped = fs::path(AXON_DATA_DIR) / "layouts" / (name + ".yaml");
    if (fs::is_regular_file(shipped, ec)) return fps::load_layout_file(shipped.string());
#endif
    if (name == "default") return fps::generate_layout({});
  }
  return Error(CoreErrc::invalid_argument,
               fmt::format("layout '{}': not a file, nor `default` or `benchtop`", name));
}

}  // namespace axon::app
