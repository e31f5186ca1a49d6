#include "axon/fps/sim/simulated_plane.hpp"

#include "axon/core/loop_thread.hpp"
#include "axon/fps/layout/layout_name.hpp"
#include "axon/fps/sim/focal_plane_sim.hpp"

#include <fmt/format.h>

namespace axon::fps::sim {

struct SimulatedPlane::Impl {
  core::LoopThread loop;  // first: it outlives the simulator
  std::unique_ptr<FocalPlaneSimulator> sim;
  std::optional<FocalPlane> plane;  // with the emulators' addresses
};

namespace {

FocalPlaneSimOptions sim_options(const SimulatedPlaneOptions& o) {
  FocalPlaneSimOptions so;
  so.simulator.time_scale = o.time_scale;
  so.seed = o.seed;
  so.random_start = o.random_start;
  so.plc = o.plc;
  so.plc_options.bind_address = "127.0.0.1";
  so.plc_options.port = 0;
  return so;
}

}  // namespace

SimulatedPlane::SimulatedPlane(const std::string& layout, SimulatedPlaneOptions options)
    : SimulatedPlane(resolve_layout(layout).value(), options) {}

SimulatedPlane::SimulatedPlane(const FocalPlane& plane, SimulatedPlaneOptions options) : impl_(std::make_unique<Impl>()) {
  if (!(options.time_scale > 0))
    throw Exception(Error(CoreErrc::invalid_argument, fmt::format("time scale {:g}: must be > 0", options.time_scale)));
  auto* impl = impl_.get();
  impl->sim = impl->loop.call([impl, &plane, &options] {
    return FocalPlaneSimulator::start(impl->loop.executor(), plane, sim_options(options)).value();
  });
  impl->plane = with_gateway_addresses(plane, gateway_addresses()).value();
}

SimulatedPlane::~SimulatedPlane() { stop(); }

void SimulatedPlane::stop() noexcept {
  if (!impl_ || !impl_->sim) return;
  auto* impl = impl_.get();
  try {
    impl->loop.call([impl] {
      impl->sim->stop();
      impl->sim.reset();
    });
  } catch (...) {  // nothing more to do: the loop ends below
  }
  impl->loop.stop();
}

const FocalPlane& SimulatedPlane::plane() const noexcept { return *impl_->plane; }

std::map<std::uint16_t, std::string> SimulatedPlane::gateway_addresses() const {
  auto* impl = impl_.get();
  return impl->loop.call([impl] {
    std::map<std::uint16_t, std::string> out;
    for (const auto& g : impl->sim->gateways()) out[g.id] = g.endpoint.to_string();
    return out;
  });
}

std::vector<std::string> SimulatedPlane::bus_specs() const {
  const auto addresses = gateway_addresses();
  std::vector<std::string> out;
  for (const auto& bus : plane().buses())
    out.push_back(fmt::format("cannet://{}/{}", addresses.at(bus.gateway), unsigned{bus.channel}));
  return out;
}

std::string SimulatedPlane::plc_address() const {
  auto* impl = impl_.get();
  return impl->loop.call([impl] { return impl->sim->plc() ? impl->sim->plc()->endpoint().to_string() : std::string(); });
}

std::optional<Angles> SimulatedPlane::arms(std::uint16_t id) const {
  auto* impl = impl_.get();
  return impl->loop.call([impl, id]() -> std::optional<Angles> {
    const auto* m = impl->sim->simulator().find(id);
    if (!m) return std::nullopt;
    return Angles{m->physical_deg(Arm::alpha), m->physical_deg(Arm::beta)};
  });
}

std::uint64_t SimulatedPlane::collisions() const {
  auto* impl = impl_.get();
  return impl->loop.call([impl] {
    const auto& s = impl->sim->simulator().stats();
    return s.neighbour_collisions + s.obstacle_collisions;
  });
}

std::uint64_t SimulatedPlane::sync_edges() const {
  auto* impl = impl_.get();
  return impl->loop.call([impl] { return impl->sim->counters().sync_edges; });
}

void SimulatedPlane::inject_collision(std::uint16_t id) {
  auto* impl = impl_.get();
  impl->loop.call([impl, id] { impl->sim->simulator().force_collision(id, Arm::beta).value(); });
}

namespace {
Arm arm_of(char arm) {
  if (arm == 'a') return Arm::alpha;
  if (arm == 'b') return Arm::beta;
  throw Exception(Error(CoreErrc::invalid_argument, fmt::format("arm '{}': use 'a' (alpha) or 'b' (beta)", arm)));
}
}  // namespace

void SimulatedPlane::set_friction_fault(std::uint16_t id, char arm, int level) {
  auto* impl = impl_.get();
  const Arm a = arm_of(arm);
  const auto fault = level == 0 ? std::nullopt : std::optional<std::int32_t>(level);
  impl->loop.call([impl, id, a, fault] { impl->sim->simulator().set_friction_fault(id, a, fault).value(); });
}

void SimulatedPlane::set_hall_fault(std::uint16_t id, char arm, const std::string& fault) {
  auto* impl = impl_.get();
  const Arm a = arm_of(arm);
  const auto parsed = hall_fault_from(fault);
  if (!parsed) throw Exception(Error(CoreErrc::invalid_argument, fmt::format("hall fault '{}': use stuck, dead or none", fault)));
  const HallFault f = *parsed;
  impl->loop.call([impl, id, a, f] { impl->sim->simulator().set_hall_fault(id, a, f).value(); });
}

}  // namespace axon::fps::sim
