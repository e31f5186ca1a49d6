#include "axon/c4g/sim/robot_file.hpp"

#include "axon/c4g/protocol/axis_map.hpp"
#include "axon/c4g/protocol/transform.hpp"
#include "axon/core/config.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <optional>
#include <type_traits>

#include <fstream>
#include <iterator>
#include <map>
#include <vector>

namespace axon::c4g::sim {
namespace {

namespace P = protocol;

Error limit_error(std::string text) { return Error(CoreErrc::invalid_argument, "robot: " + std::move(text)); }

// A field's values from the YAML node: one for a scalar, up to 10 for a per-arm list.
Result<std::vector<double>> values_of(const core::ConfigNode& n, bool list) {
  std::vector<double> out;
  if (!list) {
    AXON_TRY(v, n.as<double>());
    out.push_back(v);
    return out;
  }
  AXON_TRY(items, n.items());
  if (items.size() > P::kAxesPerArm) return n.error(CoreErrc::invalid_argument, "at most 10 values (one per logical axis)");
  for (const auto& item : items) {
    AXON_TRY(v, item.as<double>());
    out.push_back(v);
  }
  return out;
}

std::size_t listed_axes(const P::InitPacket& init) {
  std::size_t n = 0;
  for (const auto& arm : init.open_axis_list)
    for (auto a : arm) n += a != 0 ? 1 : 0;
  return n;
}

// `x` as a packet field of type T: a whole number within T's range for the integer fields, a finite
// number within float's range for the others; nullopt otherwise (a cast would be undefined).
template <class T>
std::optional<T> fits(double x) {
  if (!std::isfinite(x)) return std::nullopt;
  if constexpr (std::is_integral_v<T>) {
    if (x != std::floor(x) || x < static_cast<double>(std::numeric_limits<T>::min()) ||
        x > static_cast<double>(std::numeric_limits<T>::max()))
      return std::nullopt;
  } else if (std::abs(x) > static_cast<double>(std::numeric_limits<T>::max())) {
    return std::nullopt;
  }
  return static_cast<T>(x);
}

template <class T>
const char* type_name(const T&) {
  if constexpr (std::is_integral_v<T>) return std::is_signed_v<T> ? "a signed integer" : "an unsigned integer";
  return "a 32-bit float";
}

}  // namespace

Result<P::InitPacket> init_from_yaml(std::string_view yaml, std::string where) {
  AXON_TRY(root, core::ConfigNode::load_string(yaml, std::move(where)));
  if (!root.is_map()) return root.error(CoreErrc::invalid_argument, "expected a map of initialization-packet fields");
  P::InitPacket init;
  init.protocol_number = 10;
  init.period_ms = 2;  // the controllers' usual period unless the file gives one
  // Which names exist, and whether each is a per-arm list.
  std::map<std::string, bool, std::less<>> known;
  P::for_each_field(init, [&](std::string_view name, int index, const auto&) { known[std::string(name)] = index >= 0 && name.starts_with("arm"); });
  for (const auto& key : root.keys()) {
    if (key == "name") continue;
    const auto it = known.find(key);
    AXON_TRY(node, root.child(key));
    if (it == known.end()) return node.error(CoreErrc::invalid_argument, "not a field of the initialization packet");
    AXON_TRY(values, values_of(node, it->second));
    std::optional<Error> bad;
    P::for_each_field(init, [&](std::string_view name, int index, auto& v) {
      const std::size_t i = index < 0 ? 0 : static_cast<std::size_t>(index);
      if (name != key || bad || i >= values.size()) return;
      auto value = fits<std::decay_t<decltype(v)>>(values[i]);
      if (value) v = *value;
      else bad = node.error(CoreErrc::invalid_argument, fmt::format("{:g} does not fit the field's type ({})", values[i], type_name(v)));
    });
    if (bad) return *bad;
  }
  if (!root.has("nAxOpen")) init.open_axes = static_cast<std::int32_t>(listed_axes(init));
  return init;
}

Result<void> check_table_limits(const P::InitPacket& init) {
  std::size_t arms = 0, total = 0;
  for (std::size_t arm = 0; arm < P::kMaxArms; ++arm) {
    std::size_t n = 0, aux = 0;
    for (std::size_t k = 0; k < P::kAxesPerArm; ++k) {
      const auto a = init.open_axis_list[arm][k];
      if (a == 0) continue;
      ++n;
      if (a > 6) ++aux;  // logical axes 7..10 are an arm's auxiliary axes
    }
    if (n == 0) continue;
    ++arms;
    total += n;
    if (n > kTableMaxAxesPerArm)
      return limit_error(fmt::format("arm {} has {} open axes; the open interface allows {} per arm (table 5.1)", arm + 1, n, kTableMaxAxesPerArm));
    if (aux > kTableMaxAuxiliaryAxesPerArm)
      return limit_error(fmt::format("arm {} has {} auxiliary axes; at most {} (table 5.1)", arm + 1, aux, kTableMaxAuxiliaryAxesPerArm));
  }
  if (arms == 0) return limit_error("no open axis in arm1OpenAx..arm4OpenAx");
  if (arms > kTableMaxArms) return limit_error(fmt::format("{} arms; at most {} (table 5.1)", arms, kTableMaxArms));
  if (total > kTableMaxAxes) return limit_error(fmt::format("{} open axes; at most {} (table 5.1)", total, kTableMaxAxes));
  if (static_cast<std::size_t>(init.open_axes) != total)
    return limit_error(fmt::format("nAxOpen is {} but the open-axis lists name {} axes", init.open_axes, total));
  AXON_TRY(P::validate(init));
  AXON_TRY(map, P::AxisMap::from_init(init));
  for (std::size_t arm = 1; arm <= P::kMaxArms; ++arm) {
    if (map.arm_count(arm) == 0) continue;
    if (auto t = P::ArmTransform::from_init(init, arm); !t)
      return limit_error(fmt::format("{} (each axis of an arm up to its last open one needs a non-zero transmission ratio)", t.error().detail));
    for (std::size_t k = 1; k <= P::kAxesPerArm; ++k)
      if (map.open_index(arm, k) && init.transmission_ratio[arm - 1][k - 1] == 0.0f)
        return limit_error(fmt::format("arm {} axis {}: transmission ratio 0", arm, k));
  }
  return ok();
}

Result<RobotConfig> robot_from_init(P::InitPacket init, std::string name) {
  AXON_TRY(check_table_limits(init));
  RobotConfig r;
  r.name = std::move(name);
  r.init = init;
  for (std::size_t arm = 0; arm < P::kMaxArms; ++arm)
    for (std::size_t k = 0; k < P::kAxesPerArm; ++k) {
      r.axes[arm][k].current_limit = init.current_limit[arm][k];
      r.axes[arm][k].following_error = init.following_error[arm][k];
    }
  return r;
}

Result<RobotConfig> load_robot_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error(CoreErrc::invalid_argument, fmt::format("robot file {}: cannot be opened", path));
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  P::InitPacket init;
  std::string name = path;
  if (bytes.size() == P::kInitPacketSize) {
    auto decoded = P::decode_init(std::span<const std::byte>(reinterpret_cast<const std::byte*>(bytes.data()), bytes.size()));
    if (!decoded) return Error(decoded.error().code, fmt::format("robot file {}: {}", path, decoded.error().detail));
    init = decoded.value();
  } else {
    AXON_TRY(parsed, init_from_yaml(bytes, path));
    init = parsed;
    if (auto root = core::ConfigNode::load_string(bytes, path); root && root.value().has("name"))
      if (auto n = root.value().get<std::string>("name")) name = n.value();
  }
  auto robot = robot_from_init(init, name);
  if (!robot) return Error(robot.error().code, fmt::format("robot file {}: {}", path, robot.error().detail));
  return robot;
}

}  // namespace axon::c4g::sim
