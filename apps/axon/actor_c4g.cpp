// `axon actor c4g`: the PC-side server of a C4G controller's open interface as a long-running actor
// on a RabbitMQ broker (docs/actor.md). Without --controller a simulated controller in this process
// plays a robot program that keeps giving the PC its turn, so that commands have something to
// serve. Parsing and library calls only: the actor is axon::actor::BusActor + C4gActor over a
// c4g::host::Server running a c4g::apps::AppSwitch.
#include "broker_options.hpp"
#include "axon/actor/bus_actor.hpp"
#include "axon/actor/c4g_actor.hpp"
#include "axon/c4g/apps/app_switch.hpp"
#include "axon/c4g/host/server.hpp"
#include "axon/c4g/sim/simulated_controller.hpp"
#include "axon/web/live_page.hpp"
#include "commands.hpp"
#include "run.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace axon::app {
namespace {

struct ActorC4gOptions {
  BrokerOptions bus;
  ActorOptions actor;
  std::string listen = fmt::format("{}:{}", c4g::host::kDefaultServerAddress, c4g::host::kDefaultPort);
  std::string controller;  // empty: the embedded simulator; "any": a real controller from anywhere
  std::string robot = "six-axis";
  std::string scenario;    // the simulator's robot program (empty: the built-in one below)
  bool lenient_timing = false;
  std::vector<std::string> stroke_ends;
  int rt_priority = 0;     // SCHED_FIFO for the cycle thread (and mlockall); 0: a normal thread
  std::vector<int> cpus;
  double stop_timeout_s = 5.0;
};

// The embedded controller's program: drive on, then again and again an open phase of type A in
// mode 4 and one of type B in mode 7 during a move out and back, each ending when the PC leaves it
// (WAIT FOR PC); the monitor holds each phase until a command starts an app that serves it.
std::string actor_program() {
  std::string y = "name: axon actor c4g (the PC's turn, again and again)\nsteps:\n  - drive_on\n";
  for (int k = 0; k < 500; ++k)
    y += "  - go_open: {type: A, mode: 4, arms: [1]}\n"
         "  - wait_for_pc: {arms: [1]}\n"
         "  - delay: 0.2\n"
         "  - go_open: {type: B, mode: 7, arms: [1]}\n"
         "  - move: {arm: 1, deg: [10, -5, 5, 0, 10, 0], duration: 1}\n"
         "  - move: {arm: 1, deg: [0, 0, 0, 0, 0, 0], duration: 1}\n"
         "  - wait_for_pc: {arms: [1]}\n"
         "  - delay: 0.2\n";
  return y + "  - run\n";
}

c4g::host::ServerOptions c4g_server_options(const ActorC4gOptions& o) {
  c4g::host::ServerOptions so;
  so.listen = need(net::parse_endpoint(o.listen, c4g::host::kManualPort));
  if (!o.controller.empty() && o.controller != "any") so.controller = need(net::parse_endpoint(o.controller, 0));
  for (const auto& spec : o.stroke_ends) need(c4g::host::parse_stroke_end(spec, 1, so.safety));
  so.cycle.realtime.fifo_priority = o.rt_priority;
  so.cycle.realtime.lock_memory = o.rt_priority > 0;
  so.cycle.realtime.cpus = o.cpus;
  return so;
}

std::unique_ptr<c4g::sim::SimulatedController> start_simulator(const ActorC4gOptions& o, const c4g::host::Server& server) {
  c4g::sim::SimulatedControllerOptions co;
  co.server = server.local_address().to_string();
  co.robot = o.robot;
  if (o.scenario.empty()) co.scenario_yaml = actor_program();
  else co.scenario_file = o.scenario;
  if (o.lenient_timing) co.reply_window = c4g::sim::ReplyWindow::period;
  // The simulated controller's warnings and errors (a communication error, a failed program step)
  // go to stderr as they happen, as `axon sim c4g` prints them.
  co.on_event = [](const c4g::sim::Event& e) {
    if (e.level == c4g::sim::EventLevel::info) return;
    std::fprintf(stderr, "simulated controller %8.3f s %s %s: %s\n", e.time_s, std::string(c4g::sim::to_string(e.level)).c_str(),
                 e.name.c_str(), e.text.c_str());
  };
  return std::make_unique<c4g::sim::SimulatedController>(c4g::sim::SimulatedController::start(co));
}

// --http: the server's page (web::C4gPage), fed the events the actor drains from the switch.
std::unique_ptr<web::C4gPage> open_c4g_page(const ActorC4gOptions& o, const c4g::apps::AppSwitch& apps,
                                            const c4g::host::Server& server) {
  web::C4gViewOptions vo;
  vo.command = fmt::format("actor {}", o.actor.name);
  return std::make_unique<web::C4gPage>(web::server_address(o.actor.http), apps, server, std::move(vo),
                                        fmt::format("c4g: actor {} on {}", o.actor.name, server.local_address().to_string()));
}

int run_actor_c4g(const ActorC4gOptions& o) {
  return run_command([&o](asio::io_context& io, SignalHook hook) -> asio::awaitable<int> {
    c4g::apps::AppSwitch apps({o.stop_timeout_s, 1.0});
    auto started = c4g::host::Server::start(apps, c4g_server_options(o));
    auto server = need(std::move(started));
    for (const auto& step : server->realtime_report().steps)
      if (!step.granted) spdlog::warn("actor c4g: {} refused: {}", step.name, step.reason);
    auto sim = o.controller.empty() ? start_simulator(o, *server) : nullptr;
    actor::BusActor bus({o.actor.name, o.bus.link()});
    {
      actor::C4gActorOptions ao;
      ao.status_period_s = o.actor.status_period_s;
      const auto page = o.actor.http.empty() ? nullptr : open_c4g_page(o, apps, *server);
      if (page) ao.on_event = [p = page.get()](const c4g::apps::Event& e, const std::string& text) { p->add_event(e, text); };
      actor::C4gActor c4g_actor(bus.core(), apps, *server, ao);
      bus.start();
      std::fprintf(stderr, "actor %s: serving c4g on %s (%s), commands on %s (exchange %s)\n", o.actor.name.c_str(),
                   server->local_address().to_string().c_str(), sim ? sim->describe().c_str() : "a real controller",
                   o.bus.broker.c_str(), o.bus.exchange.c_str());
      if (page) std::fprintf(stderr, "listening http %s\n", page->where().c_str());
      co_await wait_for_stop(io, o.actor.duration_s, hook);
      c4g_actor.shutdown();  // the app in force leaves its open modes (drive off if it cannot)
    }
    if (sim) {
      const auto seen = sim->stop();
      std::fprintf(stderr, "actor %s: simulated controller: %s, %llu packets, %llu misses\n", o.actor.name.c_str(),
                   seen.outcome_text.c_str(), static_cast<unsigned long long>(seen.stats.packets_sent),
                   static_cast<unsigned long long>(seen.stats.misses));
    }
    server->stop();
    const auto c = bus.core().counters();
    std::fprintf(stderr, "actor %s: %llu commands, %llu refused, %llu not understood; %llu apps run\n", o.actor.name.c_str(),
                 static_cast<unsigned long long>(c.received), static_cast<unsigned long long>(c.refused + c.busy),
                 static_cast<unsigned long long>(c.not_json + c.malformed + c.unknown + c.oversized),
                 static_cast<unsigned long long>(apps.installs()));
    co_return 0;
  });
}

}  // namespace

void add_actor_c4g_command(CLI::App& actor_group, GlobalOptions& global) {
  auto o = std::make_shared<ActorC4gOptions>();
  auto* c = actor_group.add_subcommand(
      "c4g", "the c4g open-interface server as an actor (embedded simulated controller unless --controller)");
  add_broker_options(*c, o->bus);
  add_actor_options(*c, o->actor, "c4g");
  c->add_option("--listen", o->listen, "HOST[:PORT] to serve the controller on (default 127.0.0.1:11000; port 0: any free)");
  c->add_option("--controller", o->controller,
                "a real controller: its HOST[:PORT] (only it may start a session), or any; no simulator");
  c->add_option("--robot", o->robot, "simulator: the robot, six-axis or a robot FILE (default six-axis)");
  c->add_option("--scenario", o->scenario, "simulator: the robot program FILE (default: open phases in modes 4 and 7, again and again)");
  c->add_flag("--lenient-timing", o->lenient_timing, "simulator: accept a reply up to a whole period late (loaded machines)");
  c->add_option("--stroke-end", o->stroke_ends, "Safety: a joint's stroke ends, [ARM.]AXIS=MIN:MAX [deg]; repeatable");
  c->add_option("--rt-priority", o->rt_priority, "SCHED_FIFO priority of the server's cycle thread (and mlockall)")
      ->check(CLI::Range(0, 99));
  c->add_option("--cpu", o->cpus, "pin the cycle thread to this CPU (repeatable)");
  c->add_option("--stop-timeout", o->stop_timeout_s, "seconds an app may take to leave its open modes before drive off (default 5)")
      ->check(CLI::NonNegativeNumber);
  c->callback([o, &global] { global.exit_code = run_actor_c4g(*o); });
}

}  // namespace axon::app
