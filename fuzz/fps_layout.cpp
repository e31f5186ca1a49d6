// Fuzzes the focal-plane layout loader (fps/layout/layout_file.hpp), the calibration tables
// (fps/layout/calibration_tables.hpp) and the target lists (fps/plan/targets.hpp). The input is a
// file's text. Loading gives a plane or an error with a message, never a crash or an exception; a
// plane that loads must write out (to_yaml) as text that loads again and writes out identically.
// The same text is also read as targets, YAML and CSV, and, cut at form feeds into up to four
// pieces, as the positioner, wok, fiducial and guide camera tables.
#include "axon/core/config.hpp"
#include "axon/fps/layout/calibration_tables.hpp"
#include "axon/fps/layout/layout_file.hpp"
#include "axon/fps/plan/targets.hpp"

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

using namespace axon;

namespace {

void require(bool ok) {
  if (!ok) __builtin_trap();
}

template <class R>
void check(const R& r) {
  require(r || !r.error().detail.empty());
}

// A plane must survive its own YAML: it loads again and writes out identically.
void check_round_trip(const fps::FocalPlane& plane) {
  const std::string yaml = fps::to_yaml(plane);
  auto again = core::ConfigNode::load_string(yaml, "<again>");
  require(static_cast<bool>(again));
  auto reloaded = fps::load_layout(again.value());
  require(static_cast<bool>(reloaded));
  require(fps::to_yaml(reloaded.value()) == yaml);
}

void check_tables(std::string_view text) {
  std::string_view piece[4];
  for (auto& p : piece) {
    const auto cut = text.find('\f');
    p = text.substr(0, cut);
    text = cut == std::string_view::npos ? std::string_view{} : text.substr(cut + 1);
  }
  fps::CalibrationText t;
  t.positioners = piece[0];
  t.wok = piece[1];
  t.fiducials = piece[2];
  t.guide_cameras = piece[3];
  auto plane = fps::parse_calibration_tables(t);
  check(plane);
  if (plane) check_round_trip(plane.value());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  check(fps::plan::parse_targets_yaml(text));
  check(fps::plan::parse_targets_csv(text));
  check_tables(text);
  auto root = core::ConfigNode::load_string(text, "<fuzz>");
  check(root);
  if (!root) return 0;
  auto plane = fps::load_layout(root.value());
  check(plane);
  if (plane) check_round_trip(plane.value());
  return 0;
}
