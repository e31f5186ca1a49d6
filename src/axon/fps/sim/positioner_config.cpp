#include "axon/fps/sim/positioner_config.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <utility>
#include <string>

namespace axon::fps::sim {

namespace {

Error bad(std::string_view field, std::string what) {
  return make_error(CoreErrc::invalid_argument, fmt::format("positioner config: {} {}", field, what));
}

bool finite_in(double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; }

// A per-arm value: one number for both arms or a two-element sequence [alpha, beta].
Result<PerArm<double>> per_arm(const core::ConfigNode& node, std::string_view key) {
  AXON_TRY(c, node.child(key));
  if (!c.is_sequence()) {
    AXON_TRY(v, c.as<double>());
    return PerArm<double>{{v, v}};
  }
  AXON_TRY(items, c.items());
  if (items.size() != 2) return c.error(CoreErrc::config_bad_value, "expected [alpha, beta]");
  AXON_TRY(a, items[0].as<double>());
  AXON_TRY(b, items[1].as<double>());
  return PerArm<double>{{a, b}};
}

Result<SimDuration> duration(const core::ConfigNode& node, std::string_view key) {
  AXON_TRY(c, node.child(key));
  AXON_TRY(v, c.as<double>());
  if (!std::isfinite(v) || v < 0) return c.error(CoreErrc::config_bad_value, "expected seconds >= 0");
  return seconds(v);
}

Result<protocol::FirmwareVersion> version(const core::ConfigNode& node, std::string_view key) {
  AXON_TRY(c, node.child(key));
  AXON_TRY(text, c.as<std::string>());
  auto v = protocol::FirmwareVersion::parse(text);
  if (!v) return c.error(CoreErrc::config_bad_value, v.error().message());
  return v.value();
}

template <class E>
Result<E> choice(const core::ConfigNode& node, std::string_view key,
                 std::initializer_list<std::pair<std::string_view, E>> names) {
  AXON_TRY(c, node.child(key));
  AXON_TRY(text, c.as<std::string>());
  std::string all;
  for (const auto& [name, value] : names) {
    if (text == name) return value;
    all += fmt::format("{}{}", all.empty() ? "" : " or ", name);
  }
  return c.error(CoreErrc::config_bad_value, fmt::format("expected {}", all));
}

}  // namespace

Result<void> PositionerConfig::validate() const {
  if (id < 1 || id > 2047) return bad("id", fmt::format("{} is not within 1..2047", id));
  if (firmware.is_bootloader()) return bad("firmware", "must not have the bootloader's middle number 80");
  if (firmware < kOldestModelledFirmware) {
    return bad("firmware", fmt::format("{} is older than {}: its status word layout is not modelled", firmware.to_string(),
                                       kOldestModelledFirmware.to_string()));
  }
  if (!bootloader.is_bootloader()) return bad("bootloader", "must have the middle number 80");
  if (!finite_in(gear_ratio, 1e-3, 1e6)) return bad("gear_ratio", "must be positive");
  for (Arm a : kArms) {
    if (!finite_in(hard_stop_lower_deg[a], 0, 90) || !finite_in(hard_stop_upper_deg[a], 0, 90)) {
      return bad("hard stops", "must be within 0..90 degrees");
    }
    if (!finite_in(start_position_deg[a], -hard_stop_lower_deg[a], 360 + hard_stop_upper_deg[a])) {
      return bad("start_position_deg", fmt::format("{} lies beyond the {} hard stops", start_position_deg[a],
                                                   arm_name(a)));
    }
  }
  if (min_speed_rpm < 1 || min_speed_rpm > max_speed_rpm) return bad("speed limits", "need 1 <= min <= max");
  if (default_speed_rpm < min_speed_rpm || default_speed_rpm > max_speed_rpm) {
    return bad("default_speed_rpm", "must lie within the speed limits");
  }
  if (max_current_percent > 100 || default_drive_current_percent > max_current_percent) {
    return bad("currents", "need default_drive_current_percent <= max_current_percent <= 100");
  }
  for (Arm a : kArms) {
    if (!finite_in(stiction_current_percent[a], 0, 100) || !finite_in(viscous_current_percent_per_krpm[a], 0, 100)) {
      return bad("friction currents", "stiction_current_percent and viscous_current_percent_per_krpm must be within 0..100");
    }
  }
  if (!finite_in(precise_approach_deg, 0, 10)) return bad("precise_approach_deg", "must be within 0..10");
  if (!finite_in(datum_backoff_deg, 0, 90)) return bad("datum_backoff_deg", "must be within 0..90");
  if (!finite_in(motor_calibration_turns, 0, 1000)) return bad("motor_calibration_turns", "must be within 0..1000");
  if (!finite_in(datum_spread_motor_deg, 0, 3600)) return bad("datum_spread_motor_deg", "must be within 0..3600");
  if (receive_buffer < 1 || receive_buffer > 65536) return bad("receive_buffer", "must be within 1..65536");
  if (cogging_vector_length < 1 || cogging_vector_length > 65536) {
    return bad("cogging_vector_length", "must be within 1..65536");
  }
  if (max_firmware_size < 1 || max_firmware_size > (64u << 20)) {
    return bad("max_firmware_size", "must be within 1 byte..64 MiB");
  }
  for (double v : {x_mm, y_mm, orientation_deg}) {
    if (!std::isfinite(v)) return bad("position on the plane", "must be finite");
  }
  if (!finite_in(arms.alpha_length_mm, 0, 1000) || !finite_in(arms.beta_collision_mm, 0, 1000) ||
      !finite_in(collision_buffer_mm, 0, 100)) {
    return bad("arm geometry", "must be finite and not negative");
  }
  return ok();
}

namespace {
constexpr std::string_view kKeys[] = {
    "id", "firmware", "bootloader", "get_holding_current_on_112", "firmware_history", "version_byte_order", "start_without_trajectory", "gear_ratio", "hard_stop_lower_deg",
    "hard_stop_upper_deg", "default_speed_rpm", "min_speed_rpm", "max_speed_rpm", "max_current_percent",
    "default_drive_current_percent", "stiction_current_percent", "viscous_current_percent_per_krpm", "precise_approach_deg", "datum_backoff_deg", "motor_calibration_turns",
    "datum_spread_motor_deg", "motors_calibrated", "datums_calibrated", "cogging_calibrated", "datums_initialized",
    "start_position_deg", "sync_line_low_at_power_on", "receive_buffer", "boot_time_s", "bootloader_timeout_s",
    "watchdog_timeout_s", "hall_wake_up_s", "led_blink_s", "motor_calibration_time_s", "cogging_calibration_time_s",
    "sync_recheck_s", "max_firmware_size", "cogging_vector_length", "raw_temperature", "x_mm", "y_mm", "orientation_deg",
    "alpha_arm_mm", "beta_arm_mm", "collision_buffer_mm", "seed"};
}  // namespace

Result<PositionerConfig> PositionerConfig::from_config(const core::ConfigNode& node, const PositionerConfig& base,
                                                       std::span<const std::string_view> also_allowed) {
  if (!node.is_map()) return node.error(CoreErrc::config_bad_value, "expected a map of positioner settings");
  for (const auto& k : node.keys()) {
    const auto known = [&](std::span<const std::string_view> list) {
      return std::find(list.begin(), list.end(), k) != list.end();
    };
    if (!known(kKeys) && !known(also_allowed)) {
      AXON_TRY(c, node.child(k));
      return c.error(CoreErrc::config_unknown_key, "unknown positioner setting (see docs/fps-simulator.md)");
    }
  }
  PositionerConfig c = base;
  auto num = [&](std::string_view key, auto& field) -> Result<void> {
    if (!node.has(key)) return ok();
    using T = std::remove_reference_t<decltype(field)>;
    AXON_TRY(v, node.get<T>(key));
    field = v;
    return ok();
  };
  auto dur = [&](std::string_view key, SimDuration& field) -> Result<void> {
    if (!node.has(key)) return ok();
    AXON_TRY(v, duration(node, key));
    field = v;
    return ok();
  };
  auto arms = [&](std::string_view key, PerArm<double>& field) -> Result<void> {
    if (!node.has(key)) return ok();
    AXON_TRY(v, per_arm(node, key));
    field = v;
    return ok();
  };
  AXON_TRY(num("id", c.id));
  if (node.has("firmware")) {
    AXON_TRY(v, version(node, "firmware"));
    c.firmware = v;
  }
  if (node.has("bootloader")) {
    AXON_TRY(v, version(node, "bootloader"));
    c.bootloader = v;
  }
  AXON_TRY(num("get_holding_current_on_112", c.device_options.get_holding_current_on_112));
  if (node.has("firmware_history")) {
    const auto v = choice<FirmwareHistory>(node, "firmware_history",
                                           {{"document", FirmwareHistory::document}, {"field", FirmwareHistory::field}});
    if (!v) return v.error();
    c.firmware_history = v.value();
  }
  if (node.has("version_byte_order")) {
    const auto v = choice<protocol::VersionByteOrder>(
        node, "version_byte_order", {{"field", protocol::VersionByteOrder::field}, {"document", protocol::VersionByteOrder::document}});
    if (!v) return v.error();
    c.version_byte_order = v.value();
  }
  if (node.has("start_without_trajectory")) {
    const auto v = choice<EmptyStart>(node, "start_without_trajectory",
                                      {{"accept", EmptyStart::accept}, {"refuse", EmptyStart::refuse}});
    if (!v) return v.error();
    c.start_without_trajectory = v.value();
  }
  AXON_TRY(num("gear_ratio", c.gear_ratio));
  AXON_TRY(arms("hard_stop_lower_deg", c.hard_stop_lower_deg));
  AXON_TRY(arms("hard_stop_upper_deg", c.hard_stop_upper_deg));
  AXON_TRY(num("default_speed_rpm", c.default_speed_rpm));
  AXON_TRY(num("min_speed_rpm", c.min_speed_rpm));
  AXON_TRY(num("max_speed_rpm", c.max_speed_rpm));
  AXON_TRY(num("max_current_percent", c.max_current_percent));
  AXON_TRY(num("default_drive_current_percent", c.default_drive_current_percent));
  AXON_TRY(arms("stiction_current_percent", c.stiction_current_percent));
  AXON_TRY(arms("viscous_current_percent_per_krpm", c.viscous_current_percent_per_krpm));
  AXON_TRY(num("precise_approach_deg", c.precise_approach_deg));
  AXON_TRY(num("datum_backoff_deg", c.datum_backoff_deg));
  AXON_TRY(num("motor_calibration_turns", c.motor_calibration_turns));
  AXON_TRY(num("datum_spread_motor_deg", c.datum_spread_motor_deg));
  AXON_TRY(num("motors_calibrated", c.motors_calibrated));
  AXON_TRY(num("datums_calibrated", c.datums_calibrated));
  AXON_TRY(num("cogging_calibrated", c.cogging_calibrated));
  AXON_TRY(num("datums_initialized", c.datums_initialized));
  AXON_TRY(arms("start_position_deg", c.start_position_deg));
  AXON_TRY(num("sync_line_low_at_power_on", c.sync_line_low_at_power_on));
  AXON_TRY(num("receive_buffer", c.receive_buffer));
  AXON_TRY(dur("boot_time_s", c.boot_time));
  AXON_TRY(dur("bootloader_timeout_s", c.bootloader_timeout));
  AXON_TRY(dur("watchdog_timeout_s", c.watchdog_timeout));
  AXON_TRY(dur("hall_wake_up_s", c.hall_wake_up));
  AXON_TRY(dur("led_blink_s", c.led_blink));
  AXON_TRY(dur("motor_calibration_time_s", c.motor_calibration_time));
  AXON_TRY(dur("cogging_calibration_time_s", c.cogging_calibration_time));
  AXON_TRY(dur("sync_recheck_s", c.sync_recheck));
  AXON_TRY(num("max_firmware_size", c.max_firmware_size));
  AXON_TRY(num("cogging_vector_length", c.cogging_vector_length));
  AXON_TRY(num("raw_temperature", c.raw_temperature));
  AXON_TRY(num("x_mm", c.x_mm));
  AXON_TRY(num("y_mm", c.y_mm));
  AXON_TRY(num("orientation_deg", c.orientation_deg));
  AXON_TRY(num("alpha_arm_mm", c.arms.alpha_length_mm));
  AXON_TRY(num("beta_arm_mm", c.arms.beta_collision_mm));
  AXON_TRY(num("collision_buffer_mm", c.collision_buffer_mm));
  AXON_TRY(num("seed", c.seed));
  if (auto v = c.validate(); !v) return node.error(CoreErrc::config_bad_value, v.error().detail);
  return c;
}

Result<PositionerConfig> PositionerConfig::from_config(const core::ConfigNode& node) {
  return from_config(node, PositionerConfig{});
}

}  // namespace axon::fps::sim
