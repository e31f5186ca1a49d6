#include "axon/fps/layout/layout_name.hpp"

#include "axon/core/config.hpp"
#include "axon/fps/layout/calibration_tables.hpp"
#include "axon/fps/layout/layout_file.hpp"
#include "axon/fps/layout/layout_generator.hpp"

#include <fmt/format.h>

#include <filesystem>
#include <string_view>

namespace axon::fps {
namespace {

// data/layouts/benchtop.yaml (tests/fps/layout checks the two stay the same).
constexpr std::string_view kBenchtop = R"(name: benchtop
pitch_mm: 22.4
gateways:
  - {id: 1, address: "127.0.0.1:19228", sextant: 0, channels: 4}
robots:
  - {id: 1, x: 0, y: 0, sextant: 1, gateway: 1, bus: 1, fibres: [metrology, boss, apogee]}
  - {id: 2, x: 22.4, y: 0, sextant: 1, gateway: 1, bus: 1, fibres: [metrology, boss]}
  - {id: 3, x: 44.8, y: 0, sextant: 1, gateway: 1, bus: 1, fibres: [metrology, boss, apogee]}
  - {id: 4, x: 11.2, y: 19.399, sextant: 1, gateway: 1, bus: 1, fibres: [metrology, boss]}
  - {id: 5, x: 33.6, y: 19.399, sextant: 1, gateway: 1, bus: 1, fibres: [metrology, boss, apogee]}
  - {id: 6, x: 56, y: 19.399, sextant: 1, gateway: 1, bus: 1, fibres: [metrology, boss]}
fiducials:
  - {id: 1, x: -11.2, y: 19.399}
)";

}  // namespace

Result<FocalPlane> resolve_layout(const std::string& name, const std::string& data_dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_regular_file(name, ec)) return load_layout_file(name);
  if (is_calibration_dir(name)) return load_calibration_dir(name);
  if (name != "default" && name != "benchtop")
    return Error(CoreErrc::invalid_argument,
                 fmt::format("layout '{}': not a file, a directory of calibration tables, nor `default` or `benchtop`", name));
  if (!data_dir.empty()) {
    const fs::path shipped = fs::path(data_dir) / "layouts" / (name + ".yaml");
    if (fs::is_regular_file(shipped, ec)) return load_layout_file(shipped.string());
  }
  if (name == "default") return generate_layout({});
  auto root = core::ConfigNode::load_string(kBenchtop, "benchtop (built in)");
  if (!root) return root.error();
  return load_layout(root.value());
}

Result<FocalPlane> with_gateway_addresses(const FocalPlane& plane, const std::map<std::uint16_t, std::string>& addresses) {
  auto spec = plane.spec();
  for (auto& g : spec.gateways)
    if (const auto it = addresses.find(g.id); it != addresses.end()) g.address = it->second;
  return FocalPlane::build(std::move(spec));
}

}  // namespace axon::fps
