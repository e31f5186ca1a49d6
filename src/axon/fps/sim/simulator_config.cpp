#include "axon/fps/sim/simulator_config.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace axon::fps::sim {

namespace {

template <class Rep, class Period>
Result<void> read_duration(const core::ConfigNode& node, std::string_view key, double unit_s,
                           std::chrono::duration<Rep, Period>& out, bool allow_zero) {
  if (!node.has(key)) return ok();
  AXON_TRY(c, node.child(key));
  AXON_TRY(v, c.as<double>());
  if (!std::isfinite(v) || v < 0 || (!allow_zero && v == 0)) {
    return c.error(CoreErrc::config_bad_value, allow_zero ? "expected a value >= 0" : "expected a value > 0");
  }
  out = std::chrono::duration_cast<std::chrono::duration<Rep, Period>>(seconds(v * unit_s));
  return ok();
}

Result<Obstacle> read_obstacle(const core::ConfigNode& node) {
  AXON_TRY(node.reject_unknown({"x_mm", "y_mm", "x2_mm", "y2_mm", "radius_mm", "name"}));
  Obstacle o;
  AXON_TRY(x, node.get<double>("x_mm"));
  AXON_TRY(y, node.get<double>("y_mm"));
  AXON_TRY(x2, node.get_or<double>("x2_mm", x));
  AXON_TRY(y2, node.get_or<double>("y2_mm", y));
  AXON_TRY(r, node.get_or<double>("radius_mm", 3.0));
  AXON_TRY(name, node.get_or<std::string>("name", ""));
  if (!std::isfinite(r) || r < 0) return node.error(CoreErrc::config_bad_value, "radius_mm must be >= 0");
  o.shape = {{x, y}, {x2, y2}};
  o.buffer_mm = r;
  o.name = name;
  return o;
}

}  // namespace

std::vector<Vec2> hex_grid(std::size_t count, double pitch_mm) {
  std::vector<Vec2> points;
  if (count == 0) return points;
  const auto rings = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(count)))) + 1;
  const double row = pitch_mm * std::sqrt(3.0) / 2.0;
  for (int j = -rings; j <= rings; ++j) {
    for (int i = -rings; i <= rings; ++i) {
      points.push_back({pitch_mm * (i + j / 2.0), row * j});
    }
  }
  std::sort(points.begin(), points.end(), [](const Vec2& a, const Vec2& b) {
    const double ra = std::round((a.x * a.x + a.y * a.y) * 1e6);
    const double rb = std::round((b.x * b.x + b.y * b.y) * 1e6);
    if (ra != rb) return ra < rb;
    return std::atan2(a.y, a.x) < std::atan2(b.y, b.x);
  });
  points.resize(std::min(count, points.size()));
  return points;
}

Result<SimulatorConfig> SimulatorConfig::grid(std::size_t count, const std::vector<std::string>& channels,
                                              std::uint16_t first_id, const PositionerConfig& defaults,
                                              double pitch_mm) {
  if (channels.empty()) return make_error(CoreErrc::invalid_argument, "simulator grid: no buses given");
  if (first_id < 1 || first_id + count - 1 > protocol::kMaxPositionerId) {
    return make_error(CoreErrc::invalid_argument,
                      fmt::format("simulator grid: ids {}..{} do not fit 1..2047", first_id, first_id + count - 1));
  }
  if (!std::isfinite(pitch_mm) || pitch_mm <= 0) {
    return make_error(CoreErrc::invalid_argument, "simulator grid: pitch must be positive");
  }
  SimulatorConfig out;
  const auto where = hex_grid(count, pitch_mm);
  const std::size_t per_bus = (count + channels.size() - 1) / channels.size();
  for (std::size_t k = 0; k < count; ++k) {
    RobotPlacement p{defaults, channels[k / per_bus]};
    p.config.id = static_cast<std::uint16_t>(first_id + k);
    p.config.x_mm = where[k].x;
    p.config.y_mm = where[k].y;
    out.robots.push_back(std::move(p));
  }
  return out;
}

Result<SimulatorConfig> SimulatorConfig::from_config(const core::ConfigNode& node) {
  AXON_TRY(node.reject_unknown({"time_scale", "tick_ms", "collision_step_ms", "processing_delay_us", "flash_delay_us",
                                "scale_protocol_timeouts", "neighbour_collisions", "reply_faults", "defaults",
                                "robots", "grid", "obstacles"}));
  SimulatorConfig out;
  SimulatorOptions& o = out.options;
  if (node.has("time_scale")) {
    AXON_TRY(v, node.get_in<double>("time_scale", 1e-6, 1e6));
    o.time_scale = v;
  }
  AXON_TRY(read_duration(node, "tick_ms", 1e-3, o.tick, false));
  AXON_TRY(read_duration(node, "collision_step_ms", 1e-3, o.collision_step, false));
  AXON_TRY(read_duration(node, "processing_delay_us", 1e-6, o.processing_delay, true));
  AXON_TRY(read_duration(node, "flash_delay_us", 1e-6, o.flash_delay, true));
  AXON_TRY(scale, node.get_or<bool>("scale_protocol_timeouts", o.scale_protocol_timeouts));
  o.scale_protocol_timeouts = scale;
  AXON_TRY(neighbours, node.get_or<bool>("neighbour_collisions", o.neighbour_collisions));
  o.neighbour_collisions = neighbours;
  if (node.has("reply_faults")) {
    AXON_TRY(f, node.child("reply_faults"));
    AXON_TRY(plan, can::FaultPlan::from_config(f));
    o.reply_faults = std::move(plan);
  }
  PositionerConfig defaults;
  if (node.has("defaults")) {
    AXON_TRY(d, node.child("defaults"));
    AXON_TRY(c, PositionerConfig::from_config(d, defaults));
    defaults = c;
  }
  if (node.has("robots")) {
    AXON_TRY(list, node.child("robots"));
    AXON_TRY(items, list.items());
    static constexpr std::string_view kBus[] = {"bus"};
    for (const auto& item : items) {
      if (!item.has("id")) return item.error(CoreErrc::config_missing_key, "every robot needs an id");
      AXON_TRY(bus, item.get<std::string>("bus"));
      AXON_TRY(c, PositionerConfig::from_config(item, defaults, kBus));
      out.robots.push_back(RobotPlacement{c, bus});
    }
  }
  if (node.has("grid")) {
    AXON_TRY(g, node.child("grid"));
    AXON_TRY(g.reject_unknown({"count", "buses", "first_id", "pitch_mm"}));
    AXON_TRY(count, g.get_in<std::uint32_t>("count", 1, protocol::kMaxPositionerId));
    AXON_TRY(first, g.get_or<std::uint16_t>("first_id", 1));
    AXON_TRY(pitch, g.get_or<double>("pitch_mm", 22.4));
    AXON_TRY(buses_node, g.child("buses"));
    AXON_TRY(bus_items, buses_node.items());
    std::vector<std::string> buses;
    for (const auto& b : bus_items) {
      AXON_TRY(name, b.as<std::string>());
      buses.push_back(name);
    }
    auto laid = grid(count, buses, first, defaults, pitch);
    if (!laid) return g.error(CoreErrc::config_bad_value, laid.error().detail);
    for (auto& r : laid.value().robots) out.robots.push_back(std::move(r));
  }
  if (node.has("obstacles")) {
    AXON_TRY(list, node.child("obstacles"));
    AXON_TRY(items, list.items());
    for (const auto& item : items) {
      AXON_TRY(ob, read_obstacle(item));
      out.obstacles.push_back(std::move(ob));
    }
  }
  // Ids must be unique over the whole plane.
  std::vector<std::uint16_t> ids;
  for (const auto& r : out.robots) ids.push_back(r.config.id);
  std::sort(ids.begin(), ids.end());
  if (const auto dup = std::adjacent_find(ids.begin(), ids.end()); dup != ids.end()) {
    return node.error(CoreErrc::config_bad_value, fmt::format("positioner id {} appears twice", *dup));
  }
  return out;
}

Result<std::unique_ptr<Simulator>> make_simulator(asio::any_io_executor executor, const SimulatorConfig& config,
                                                  can::BusProvider& provider) {
  AXON_TRY(config.options.validate());
  auto sim = std::make_unique<Simulator>(std::move(executor), config.options);
  if (config.geometry) sim->set_geometry(*config.geometry);
  for (const auto& r : config.robots) {
    auto added = sim->add(r.config, provider, r.channel);
    if (!added) {
      return Error(added.error().code,
                   fmt::format("positioner {} on bus '{}': {}", r.config.id, r.channel, added.error().detail));
    }
  }
  for (const auto& o : config.obstacles) sim->add_obstacle(o);
  sim->start();
  return sim;
}

}  // namespace axon::fps::sim
