#include "axon/fps/sim/focal_plane_sim.hpp"

#include "axon/core/deadline_queue.hpp"
#include "axon/core/error.hpp"
#include "axon/fps/plan/layout_model.hpp"
#include "axon/fps/sim/simulator_config.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/ip/address_v4.hpp>
#include <boost/asio/redirect_error.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/use_awaitable.hpp>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <optional>
#include <random>

namespace axon::fps::sim {

namespace {

Result<std::set<std::uint16_t>> read_ids(const core::ConfigNode& node, std::string_view key) {
  std::set<std::uint16_t> out;
  if (!node.has(key)) return out;
  AXON_TRY(list, node.child(key));
  AXON_TRY(items, list.items());
  for (const auto& item : items) {
    AXON_TRY(id, item.as<std::uint16_t>());
    if (id < 1 || id > 2047) return item.error(CoreErrc::config_bad_value, "a robot id is 1..2047");
    out.insert(id);
  }
  return out;
}

// The IPv4 address `k` after `first`, if both are IPv4 and the sum does not overflow.
std::optional<std::string> ipv4_plus(const std::string& first, std::size_t k) {
  boost::system::error_code ec;
  const auto a = asio::ip::make_address_v4(first, ec);
  if (ec || a.is_unspecified()) return std::nullopt;
  const std::uint64_t v = std::uint64_t{a.to_uint()} + k;
  if (v > 0xFFFF'FFFFu) return std::nullopt;
  return asio::ip::address_v4(static_cast<std::uint32_t>(v)).to_string();
}

}  // namespace

Result<std::map<std::uint16_t, net::Endpoint>> gateway_endpoints(const FocalPlane& plane, const GatewayBinding& binding) {
  std::map<std::uint16_t, net::Endpoint> out;
  std::set<std::pair<std::string, std::uint16_t>> taken;
  boost::system::error_code ec;
  const auto first = asio::ip::make_address_v4(binding.address, ec);
  const bool count_up = !ec && !first.is_unspecified();
  const bool from_layout = binding.address == GatewayBinding::kLayoutAddresses;
  if (from_layout && (binding.port != 0 || !binding.ports.empty()))
    return Error(CoreErrc::invalid_argument, "with the layout's addresses the ports come from the layout too");
  std::size_t k = 0;
  for (const auto& g : plane.gateways()) {
    net::Endpoint ep;
    if (from_layout) {
      auto parsed = net::parse_endpoint(g.address, can::cannet::kDefaultPort);
      if (!parsed)
        return Error(CoreErrc::invalid_argument, fmt::format("gateway {}: address '{}': {}", g.id, g.address, parsed.error().message()));
      ep = parsed.value();
    } else {
      const auto host = count_up ? ipv4_plus(binding.address, k) : binding.address;
      if (!host)
        return Error(CoreErrc::invalid_argument, fmt::format("gateway {}: no IPv4 address {} after {}", g.id, k, binding.address));
      const auto port = binding.ports.find(g.id);
      ep = net::Endpoint{*host, port == binding.ports.end() ? binding.port : port->second};
    }
    ++k;
    if (ep.port != 0 && !taken.emplace(ep.host, ep.port).second)
      return Error(CoreErrc::invalid_argument, fmt::format("gateways share the endpoint {}", ep.to_string()));
    out[g.id] = ep;
  }
  return out;
}

namespace {

Result<Arm> arm_of(const core::ConfigNode& item) {
  AXON_TRY(arm, item.get<std::string>("arm"));
  if (arm == "alpha") return Arm::alpha;
  if (arm == "beta") return Arm::beta;
  return item.error(CoreErrc::config_bad_value, fmt::format("arm '{}': use alpha or beta", arm));
}

// The scenario's friction: [{id, arm, level}] and hall: [{id, arm, fault}] lists.
Result<void> read_arm_faults(const core::ConfigNode& node, Scenario& s) {
  if (node.has("friction")) {
    AXON_TRY(list, node.child("friction"));
    AXON_TRY(items, list.items());
    for (const auto& item : items) {
      AXON_TRY(item.reject_unknown({"id", "arm", "level"}));
      AXON_TRY(id, item.get_in<std::uint16_t>("id", 1, 2047));
      AXON_TRY(arm, arm_of(item));
      AXON_TRY(level, item.get_in<std::int32_t>("level", -30, 100));
      s.friction.push_back({id, arm, level});
    }
  }
  if (node.has("hall")) {
    AXON_TRY(list, node.child("hall"));
    AXON_TRY(items, list.items());
    for (const auto& item : items) {
      AXON_TRY(item.reject_unknown({"id", "arm", "fault"}));
      AXON_TRY(id, item.get_in<std::uint16_t>("id", 1, 2047));
      AXON_TRY(arm, arm_of(item));
      AXON_TRY(name, item.get<std::string>("fault"));
      const auto fault = hall_fault_from(name);
      if (!fault || *fault == HallFault::none)
        return item.error(CoreErrc::config_bad_value, fmt::format("hall fault '{}': use stuck or dead", name));
      s.hall.push_back({id, arm, *fault});
    }
  }
  return ok();
}

}  // namespace

Result<Scenario> Scenario::from_config(const core::ConfigNode& node) {
  AXON_TRY(node.reject_unknown({"datum_lost", "uncalibrated", "collided", "bootloader", "absent", "collide_on_move", "extra",
                                "friction", "hall"}));
  Scenario s;
  AXON_TRY(a, read_ids(node, "datum_lost"));
  s.datum_lost = std::move(a);
  AXON_TRY(b, read_ids(node, "uncalibrated"));
  s.uncalibrated = std::move(b);
  AXON_TRY(c, read_ids(node, "collided"));
  s.collided = std::move(c);
  AXON_TRY(d, read_ids(node, "bootloader"));
  s.bootloader = std::move(d);
  AXON_TRY(e, read_ids(node, "absent"));
  s.absent = std::move(e);
  AXON_TRY(f, read_ids(node, "collide_on_move"));
  s.collide_on_move = std::move(f);
  if (node.has("extra")) {
    AXON_TRY(list, node.child("extra"));
    AXON_TRY(items, list.items());
    for (const auto& item : items) {
      AXON_TRY(item.reject_unknown({"id", "gateway", "bus"}));
      AXON_TRY(id, item.get_in<std::uint16_t>("id", 1, 2047));
      AXON_TRY(gw, item.get<std::uint16_t>("gateway"));
      AXON_TRY(ch, item.get_in<int>("bus", 1, kMaxGatewayChannels));
      s.extra[id] = BusRef{gw, static_cast<std::uint8_t>(ch)};
    }
  }
  AXON_TRY(read_arm_faults(node, s));
  return s;
}

struct FocalPlaneSimulator::Impl {
  asio::any_io_executor executor;
  FocalPlaneSimOptions options;
  can::VirtualBusRegistry registry;
  std::unique_ptr<Simulator> simulator;
  std::map<BusRef, std::shared_ptr<can::VirtualBus>> media;
  std::vector<GatewayInfo> gateways;
  std::vector<std::unique_ptr<can::CanNetGatewayEmulator>> emulators;  // parallel to gateways
  std::map<int, std::vector<std::uint16_t>> sextants;
  std::unique_ptr<plc::PlcEmulator> plc;
  std::array<bool, kSextants> positioner_power{true, true, true, true, true, true};
  bool sync_high = false;
  core::TimePoint sync_rose_at{};
  bool stopped = false;
  std::shared_ptr<bool> alive = std::make_shared<bool>(true);  // for hooks posted before stop()
  Counters counters;

  Impl(asio::any_io_executor ex, FocalPlaneSimOptions o) : executor(ex), options(std::move(o)), registry(ex) {}

  Result<void> start_gateway(std::size_t i) {
    auto& g = gateways[i];
    can::CanNetEmulatorOptions eo = options.gateway_options;
    eo.bind_address = g.endpoint.host;
    eo.port = g.endpoint.port;
    std::vector<std::string> channels(static_cast<std::size_t>(kMaxGatewayChannels));
    for (const auto& [ch, name] : g.channels) channels[static_cast<std::size_t>(ch - 1)] = name;
    // Trailing empty channels are simply not fitted.
    while (!channels.empty() && channels.back().empty()) channels.pop_back();
    auto emu = std::make_unique<can::CanNetGatewayEmulator>(executor, registry, channels, eo);
    AXON_TRY(emu->start());
    g.endpoint = emu->local_endpoint();
    g.powered = true;
    emulators[i] = std::move(emu);
    return ok();
  }

  void on_relay(const plc::RelayEvent& e) {
    if (stopped) return;
    Result<void> r = ok();
    switch (e.relay.kind) {
      case plc::RelayKind::positioner_power: r = set_positioner_power(e.relay.sextant, e.on); break;
      case plc::RelayKind::gateway_power: r = set_gateway_power(e.relay.sextant, e.on); break;
      case plc::RelayKind::sync_line: set_sync(e.on, e.at); break;
    }
    if (!r) spdlog::warn("sim: {}: {}", e.relay.to_string(), r.error().message());
  }

  Result<void> set_positioner_power(int sextant, bool on) {
    if (sextant < 1 || sextant > kSextants)
      return Error(CoreErrc::invalid_argument, fmt::format("sextant {} (expected 1..6)", sextant));
    auto& state = positioner_power[static_cast<std::size_t>(sextant - 1)];
    if (state == on) return ok();
    state = on;
    ++counters.sextant_power_changes;
    const auto it = sextants.find(sextant);
    const std::vector<std::uint16_t> none;
    const auto& ids = it == sextants.end() ? none : it->second;
    spdlog::info("sim: positioner power of sextant {} {} ({} robots{})", sextant, on ? "on" : "off", ids.size(),
                 on && !sync_high ? ", sync line low: bootloader" : "");
    if (on) return simulator->power_on(ids, !sync_high);
    return simulator->power_off(ids, true);
  }

  Result<void> set_gateway_power(int sextant, bool on) {
    if (sextant < 1 || sextant > kSextants)
      return Error(CoreErrc::invalid_argument, fmt::format("sextant {} (expected 1..6)", sextant));
    for (std::size_t i = 0; i < gateways.size(); ++i) {
      auto& g = gateways[i];
      if (g.sextant != sextant || g.powered == on) continue;
      ++counters.gateway_power_changes;
      spdlog::info("sim: gateway {} ({}) power {}", g.id, g.endpoint.to_string(), on ? "on" : "off");
      if (on) {
        AXON_TRY(start_gateway(i));
      } else {
        emulators[i]->power_off();
        g.powered = false;
      }
    }
    return ok();
  }

  // Scripted collisions: each listed robot reports one the first time it is seen moving.
  static asio::awaitable<void> watch_collisions(Impl* self, std::shared_ptr<bool> alive, std::set<std::uint16_t> ids) {
    asio::steady_timer timer(self->executor);
    while (!ids.empty()) {
      timer.expires_after(std::chrono::milliseconds(5));
      boost::system::error_code ec;
      co_await timer.async_wait(asio::redirect_error(asio::use_awaitable, ec));
      if (!*alive) co_return;
      for (auto it = ids.begin(); it != ids.end();) {
        auto* m = self->simulator->find(*it);
        if (m != nullptr && m->moving()) {
          spdlog::info("sim: scripted collision of robot {}", *it);
          (void)self->simulator->force_collision(*it, Arm::beta);
          it = ids.erase(it);
        } else {
          ++it;
        }
      }
    }
  }

  // `at`: when the PLC switched the line (its hooks run here later).
  void set_sync(bool high, core::TimePoint at) {
    if (high == sync_high) return;
    sync_high = high;
    if (high) {
      ++counters.sync_edges;
      sync_rose_at = at;
      std::size_t running = 0;
      for (const auto* m : simulator->robots()) running += m->run_state() == RunState::application ? 1 : 0;
      spdlog::info("sim: sync line rising edge: {} robots", running);
    } else {
      counters.sync_last_high = at - sync_rose_at;
      spdlog::info("sim: sync line low after {:.3f} s high", std::chrono::duration<double>(counters.sync_last_high).count());
    }
    // Every robot sees the level at the same instant; those without power ignore it, and each
    // robot running its application starts only if the line is still high at its second look.
    simulator->set_sync_line(high);
  }
};

FocalPlaneSimulator::FocalPlaneSimulator(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
FocalPlaneSimulator::~FocalPlaneSimulator() { stop(); }

std::string FocalPlaneSimulator::medium_name(const BusRef& bus) { return fmt::format("gw{}c{}", bus.gateway, bus.channel); }

Result<std::unique_ptr<FocalPlaneSimulator>> FocalPlaneSimulator::start(asio::any_io_executor executor,
                                                                        const FocalPlane& plane,
                                                                        FocalPlaneSimOptions options) {
  auto impl = std::make_unique<Impl>(executor, std::move(options));
  Impl& s = *impl;
  const auto& o = s.options;
  const auto& sc = o.scenario;
  std::vector<std::uint16_t> named;  // every robot the scenario names
  for (const auto* set : {&sc.datum_lost, &sc.uncalibrated, &sc.collided, &sc.bootloader, &sc.absent, &sc.collide_on_move})
    named.insert(named.end(), set->begin(), set->end());
  for (const auto& f : sc.friction) named.push_back(f.id);
  for (const auto& f : sc.hall) named.push_back(f.id);
  for (auto id : named) {
    if (plane.find(id) == nullptr && !sc.extra.contains(id))
      return Error(CoreErrc::invalid_argument, fmt::format("scenario: robot {} is not in layout '{}'", id, plane.name()));
  }
  for (const auto& [id, bus] : sc.extra) {
    if (plane.find(id) != nullptr)
      return Error(CoreErrc::invalid_argument, fmt::format("scenario: extra robot {} is already in the layout", id));
    const auto* gw = plane.gateway(bus.gateway);
    if (gw == nullptr || bus.channel < 1 || bus.channel > gw->channels)
      return Error(CoreErrc::invalid_argument, fmt::format("scenario: extra robot {}: no bus {}", id, bus.to_string()));
  }

  core::DeadlineQueue::of(executor).set_slack(o.timer_slack);
  // One medium per bus of every gateway channel the layout uses (or an extra robot uses).
  can::WireModel wire;
  wire.enabled = true;
  wire.bitrate = o.bitrate;
  wire.pace_realtime = o.pace_realtime;
  std::set<BusRef> buses;
  for (const auto& b : plane.buses()) buses.insert(b);
  for (const auto& [id, b] : sc.extra) buses.insert(b);
  for (const auto& b : buses) {
    AXON_TRY(m, s.registry.add(medium_name(b), wire));
    s.media[b] = m;
  }

  // Robots.
  SimulatorConfig config;
  config.options = o.simulator;
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> alpha(0.0, 360.0), scatter(-2.0, 2.0);
  auto place = [&](std::uint16_t id, double x, double y, const BusRef& bus) {
    RobotPlacement p;
    p.config = o.defaults;
    p.config.id = id;
    p.config.x_mm = x;
    p.config.y_mm = y;
    p.config.seed = o.seed * 1000003u + id;
    const double a = alpha(rng), b = scatter(rng);  // drawn for every robot: positions do not depend on the scenario
    if (o.random_start) p.config.start_position_deg = PerArm<double>{{a, 180.0 + b}};
    if (sc.datum_lost.contains(id)) p.config.datums_initialized = false;
    if (sc.uncalibrated.contains(id)) {
      p.config.motors_calibrated = false;
      p.config.datums_calibrated = false;
      p.config.cogging_calibrated = false;
      p.config.datums_initialized = false;
    }
    if (sc.bootloader.contains(id)) p.config.sync_line_low_at_power_on = true;
    p.channel = medium_name(bus);
    config.robots.push_back(std::move(p));
  };
  // The planner's geometry of the layout: every robot's own arms, orientation and zero offsets,
  // the fiducials, the guide cameras.
  plan::LayoutModelOptions geometry;
  geometry.buffer_mm = o.defaults.collision_buffer_mm;
  geometry.fiducial_buffer_mm = o.fiducial_radius_mm;
  config.geometry = plan::model_spec_from_layout(plane, geometry);
  for (std::size_t i = 0; i < plane.robots().size(); ++i) {
    const auto& r = plane.robots()[i];
    if (r.offline || sc.absent.contains(r.id)) continue;
    place(r.id, r.x_mm, r.y_mm, r.bus);
    // The same figures in the robot's config, for whoever shows it (the collision check uses the
    // geometry above).
    auto& c = config.robots.back().config;
    c.orientation_deg = r.orientation_deg;
    c.arms = plan::Positioner(config.geometry->robots[i], config.geometry->design).arms();
    s.sextants[r.sextant].push_back(r.id);
  }
  for (const auto& [id, bus] : sc.extra) {
    // Far off the plate: it answers on the bus but touches nobody.
    place(id, 10000.0 + 100.0 * id, 0.0, bus);
    s.sextants[0].push_back(id);
  }
  AXON_TRY(sim, make_simulator(executor, config, s.registry));
  s.simulator = std::move(sim);
  for (auto id : sc.collided) {
    if (s.simulator->find(id) != nullptr) {
      AXON_TRY(s.simulator->force_collision(id, Arm::beta));
    }
  }

  for (const auto& f : sc.friction) {
    if (s.simulator->find(f.id) != nullptr) {
      AXON_TRY(s.simulator->set_friction_fault(f.id, f.arm, f.level));
    }
  }
  for (const auto& f : sc.hall) {
    if (s.simulator->find(f.id) != nullptr) {
      AXON_TRY(s.simulator->set_hall_fault(f.id, f.arm, f.fault));
    }
  }
  if (!sc.collide_on_move.empty())
    asio::co_spawn(executor, Impl::watch_collisions(&s, s.alive, sc.collide_on_move), asio::detached);

  // Gateways: one emulator each, its channels are the layout's buses on it.
  AXON_TRY(endpoints, gateway_endpoints(plane, o.binding));
  for (const auto& gw : plane.gateways()) {
    GatewayInfo g;
    g.id = gw.id;
    g.sextant = gw.sextant;
    g.endpoint = endpoints.at(gw.id);
    for (const auto& b : buses) {
      if (b.gateway == gw.id) g.channels.emplace_back(b.channel, medium_name(b));
    }
    for (const auto& r : config.robots) {
      for (const auto& [ch, name] : g.channels) g.robots += r.channel == name ? 1 : 0;
    }
    if (g.channels.empty()) continue;
    s.gateways.push_back(std::move(g));
  }
  s.emulators.resize(s.gateways.size());
  for (std::size_t i = 0; i < s.gateways.size(); ++i) {
    AXON_TRY(s.start_gateway(i));
  }

  // The PLC, whose relays act here (hooks posted to our executor).
  if (o.plc) {
    plc::EmulatorOptions po = o.plc_options;
    po.hook_executor = executor;
    po.power_on_at_start = true;
    AXON_TRY(p, plc::PlcEmulator::start(std::move(po)));
    s.plc = std::move(p);
    Impl* self = &s;
    std::weak_ptr<bool> alive = s.alive;
    s.plc->on_relay_change([self, alive](const plc::RelayEvent& e) {
      if (auto a = alive.lock(); a && *a) self->on_relay(e);
    });
  }
  return std::unique_ptr<FocalPlaneSimulator>(new FocalPlaneSimulator(std::move(impl)));
}

void FocalPlaneSimulator::stop() {
  if (!impl_ || impl_->stopped) return;
  impl_->stopped = true;
  *impl_->alive = false;
  impl_->alive.reset();
  if (impl_->plc) impl_->plc->stop();
  for (auto& e : impl_->emulators)
    if (e) e->stop();
  if (impl_->simulator) impl_->simulator->stop();
}

Simulator& FocalPlaneSimulator::simulator() noexcept { return *impl_->simulator; }
can::VirtualBusRegistry& FocalPlaneSimulator::registry() noexcept { return impl_->registry; }
const std::vector<GatewayInfo>& FocalPlaneSimulator::gateways() const noexcept { return impl_->gateways; }
plc::PlcEmulator* FocalPlaneSimulator::plc() noexcept { return impl_->plc.get(); }
can::CanNetGatewayEmulator* FocalPlaneSimulator::gateway_emulator(std::uint16_t id) noexcept {
  for (std::size_t i = 0; i < impl_->gateways.size(); ++i)
    if (impl_->gateways[i].id == id && impl_->gateways[i].powered) return impl_->emulators[i].get();
  return nullptr;
}
std::shared_ptr<can::VirtualBus> FocalPlaneSimulator::medium(const BusRef& bus) const {
  const auto it = impl_->media.find(bus);
  return it == impl_->media.end() ? nullptr : it->second;
}
const std::map<int, std::vector<std::uint16_t>>& FocalPlaneSimulator::sextants() const noexcept { return impl_->sextants; }
Result<void> FocalPlaneSimulator::set_positioner_power(int sextant, bool on) { return impl_->set_positioner_power(sextant, on); }
Result<void> FocalPlaneSimulator::set_gateway_power(int sextant, bool on) { return impl_->set_gateway_power(sextant, on); }
void FocalPlaneSimulator::set_sync_line(bool high) { impl_->set_sync(high, core::steady_now()); }
bool FocalPlaneSimulator::sync_line() const noexcept { return impl_->sync_high; }
const FocalPlaneSimulator::Counters& FocalPlaneSimulator::counters() const noexcept { return impl_->counters; }

}  // namespace axon::fps::sim
