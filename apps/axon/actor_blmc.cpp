// `axon actor blmc`: one motor driver board as a long-running actor on a RabbitMQ broker
// (docs/actor.md). Parsing and library calls only: the actor is axon::actor::BusActor + BlmcActor
// over a blmc::MotorBoard, on a real board (--bus) or on the simulator started in this process.
#include "axon/actor/blmc_actor.hpp"
#include "axon/actor/bus_actor.hpp"
#include "axon/blmc/host/motor_board.hpp"
#include "axon/blmc/sim/simulated_board.hpp"
#include "axon/web/live_page.hpp"
#include "broker_options.hpp"
#include "commands.hpp"
#include "run.hpp"

#include <fmt/format.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <memory>
#include <mutex>
#include <optional>

namespace axon::app {
namespace actor_blmc_cli {

struct ActorBlmcOptions {
  BrokerOptions bus;
  ActorOptions actor;
  std::string board_bus;  // a real board by spec: no simulator
  double max_current_a = 2.0;
  double max_velocity_krpm = 2.0;
  double stale_ms = 20;
  double action_stale_ms = 500;
  std::uint32_t recv_timeout_ms = 50;
  double ready_timeout_s = 10;
  bool realtime = true;
};

// The simulator's own verb, for tests and demonstrations: the board raises an error now.
void add_blmc_simulator_verbs(actor::ActorCore& core, blmc::sim::SimulatedBoard& sim) {
  core.add({"sim-fault", "sim-fault KIND (embedded simulator only: encoder, pos_converter, transmit, over_current, undocumented)",
            false, [&sim](actor::Command& c) {
              constexpr std::array kinds{blmc::sim::FaultKind::encoder, blmc::sim::FaultKind::pos_converter,
                                         blmc::sim::FaultKind::transmit, blmc::sim::FaultKind::over_current,
                                         blmc::sim::FaultKind::undocumented};
              for (const auto kind : kinds)
                if (c.args().size() == 1 && c.args()[0] == blmc::sim::name(kind)) {
                  sim.inject(kind);
                  return c.finish({{"text", fmt::format("the simulated board raises {} now", c.args()[0])}});
                }
              c.fail("sim-fault takes one KIND: encoder, pos_converter, transmit, over_current or undocumented");
            }});
}

actor::BlmcActorOptions actor_options(const ActorBlmcOptions& o) {
  actor::BlmcActorOptions a;
  a.status_period_s = o.actor.status_period_s;
  a.control.limits.max_current_a = o.max_current_a;
  a.control.limits.max_velocity_krpm = o.max_velocity_krpm;
  a.control.limits.stale_after = std::chrono::duration_cast<core::Duration>(std::chrono::duration<double, std::milli>(o.stale_ms));
  a.control.realtime = o.realtime;
  a.front_end.stale_after = std::chrono::milliseconds(static_cast<std::int64_t>(o.action_stale_ms));
  a.recv_timeout_ms = o.recv_timeout_ms;
  return a;
}

// What the broker connection's changes reach: the actor while it lives (the link's thread calls in).
struct BrokerStateRelay {
  std::mutex mutex;
  actor::BlmcActor* target = nullptr;
  void operator()(bool up) {
    std::lock_guard lock(mutex);
    if (target) target->broker_state(up);
  }
  void set(actor::BlmcActor* a) {
    std::lock_guard lock(mutex);
    target = a;
  }
};

// --http: the board's page (web::BlmcPage), fed what the actor reads of the board.
std::unique_ptr<web::BlmcPage> open_blmc_page(const ActorBlmcOptions& o, const std::string& spec,
                                              const actor::BlmcActorOptions& ao) {
  web::BlmcPageOptions po;
  po.server = web::server_address(o.actor.http);
  po.view.boards.push_back({spec, ao.control.limits});
  po.view.sample_hz = 1.0 / ao.watch_period_s;
  po.view.command = "actor";
  po.title = fmt::format("blmc: actor {} on {}", o.actor.name, spec);
  return std::make_unique<web::BlmcPage>(std::move(po));
}

int run_actor_blmc(const ActorBlmcOptions& o) {
  if (auto v = actor_options(o).control.limits.validate(); !v) throw Exception(usage(v.error().detail));
  return run_command([&o](asio::io_context& io, SignalHook hook) -> asio::awaitable<int> {
    std::unique_ptr<blmc::sim::SimulatedBoard> sim;
    if (o.board_bus.empty()) sim = std::make_unique<blmc::sim::SimulatedBoard>();
    blmc::MotorBoardOptions bo;
    bo.name = o.actor.name;
    bo.recv_timeout_ms = o.recv_timeout_ms;
    bo.ready_timeout = std::chrono::milliseconds(static_cast<std::int64_t>(o.ready_timeout_s * 1000));
    const auto spec = sim ? sim->bus_spec() : o.board_bus;
    {
      blmc::MotorBoard board(spec, bo);
      actor::BusActor bus({o.actor.name, o.bus.link()});
      BrokerStateRelay relay;
      bus.on_state([&relay](bool up) { relay(up); });
      {
        auto ao = actor_options(o);
        const auto page = o.actor.http.empty() ? nullptr : open_blmc_page(o, spec, ao);
        if (page) ao.on_board_read = [p = page.get()](const blmc::host::Measurements& m) { p->add_measurements(0, m); };
        actor::BlmcActor blmc_actor(bus.core(), board, ao);
        relay.set(&blmc_actor);
        if (sim) add_blmc_simulator_verbs(bus.core(), *sim);
        bus.start();
        std::fprintf(stderr, "actor %s: board on %s%s, commands on %s (exchange %s)\n", o.actor.name.c_str(), spec.c_str(),
                     sim ? " (simulated)" : "", o.bus.broker.c_str(), o.bus.exchange.c_str());
        if (page) std::fprintf(stderr, "listening http %s\n", page->where().c_str());
        co_await wait_for_stop(io, o.actor.duration_s, hook);
        relay.set(nullptr);
      }  // the actor ends a wait in progress, closes the core, stops the loop and disables the motors
      const auto c = bus.core().counters();
      std::fprintf(stderr, "actor %s: motors disabled; %llu commands, %llu refused, %llu not understood\n", o.actor.name.c_str(),
                   static_cast<unsigned long long>(c.received), static_cast<unsigned long long>(c.refused + c.busy),
                   static_cast<unsigned long long>(c.not_json + c.malformed + c.unknown + c.oversized));
    }
    co_return 0;
  });
}

}  // namespace actor_blmc_cli

void add_actor_blmc_command(CLI::App& actor_group, GlobalOptions& global) {
  using actor_blmc_cli::ActorBlmcOptions;
  auto o = std::make_shared<ActorBlmcOptions>();
  auto* b = actor_group.add_subcommand("blmc", "a motor driver board as an actor (embedded simulated board unless --bus)");
  add_broker_options(*b, o->bus);
  add_actor_options(*b, o->actor, "blmc");
  b->add_option("--bus", o->board_bus, "a real board by spec (socketcan:can0, socketcand://HOST:PORT/CH, ...): no simulator");
  b->add_option("--max-current", o->max_current_a, "safety: current clamp, A (default 2; start may lower it)");
  b->add_option("--max-velocity", o->max_velocity_krpm, "safety: zero current above this speed, krpm (default 2)");
  b->add_option("--stale-ms", o->stale_ms, "safety: stop the loop when a measurement is older than this (default 20 ms; 200 with the simulator)");
  b->add_option("--action-stale-ms", o->action_stale_ms,
                "the loop falls back to zero current when the actor has not renewed the action for this long (default 500 ms)");
  b->add_option("--recv-timeout-ms", o->recv_timeout_ms, "the board's receive timeout during control (default 50, 250 with the simulator; 0: off)");
  b->add_option("--ready-timeout", o->ready_timeout_s, "seconds enable waits for the alignment (default 10)");
  b->add_flag("!--no-realtime", o->realtime, "do not ask for SCHED_FIFO / mlockall for the loop");
  // The embedded simulator shares this machine's cores with the loop: unless told otherwise, its
  // timing limits get the slack the library's examples give a simulator (a real board keeps the
  // defaults).
  auto* stale = b->get_option("--stale-ms");
  auto* recv = b->get_option("--recv-timeout-ms");
  b->callback([o, stale, recv, &global] {
    if (o->board_bus.empty() && stale->count() == 0) o->stale_ms = 200;
    if (o->board_bus.empty() && recv->count() == 0) o->recv_timeout_ms = 250;
    global.exit_code = actor_blmc_cli::run_actor_blmc(*o);
  });
}

}  // namespace axon::app
