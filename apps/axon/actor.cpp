// `axon actor fps`: the focal plane as a long-running actor on a RabbitMQ broker (docs/actor.md);
// `axon tell ACTOR COMMAND...`: send one command over the bus and print the replies as they come.
// Parsing and library calls only: the actor is axon::actor::BusActor + FpsActor, the client
// axon::actor::tell.
#include "broker_options.hpp"
#include "axon/actor/bus_actor.hpp"
#include "axon/actor/fps_actor.hpp"
#include "axon/actor/teller.hpp"
#include "axon/fps/host/client.hpp"
#include "axon/fps/sim/simulated_plane.hpp"
#include "axon/web/fps_host_page.hpp"
#include "commands.hpp"
#include "layout_name.hpp"
#include "run.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <charconv>
#include <cstdio>
#include <memory>

namespace axon::app {
namespace {

struct ActorFpsOptions {
  BrokerOptions bus;
  ActorOptions actor;
  std::string layout = "benchtop";
  std::vector<std::string> buses;  // real buses: no simulator
  bool connect = false;            // the layout's own gateway addresses: no simulator
  double time_scale = 10.0;
  std::uint64_t seed = 1;
  std::string friction_history;    // the friction verb's CSV history
  std::string plc;                 // real devices: the PLC at HOST[:PORT] (upgrade, power, sync)
};

// The simulator's own verb, for tests and demonstrations: a robot reports a collision now.
void add_simulator_verbs(actor::ActorCore& core, fps::sim::SimulatedPlane& sim) {
  core.add({"sim-collision", "sim-collision ID (embedded simulator only)", false, [&sim](actor::Command& c) {
              std::uint16_t id = 0;
              const auto& arg = c.args().empty() ? std::string() : c.args()[0];
              const auto [end, ec] = std::from_chars(arg.data(), arg.data() + arg.size(), id);
              if (c.args().size() != 1 || ec != std::errc() || end != arg.data() + arg.size())
                return c.fail("sim-collision takes one robot id");
              sim.inject_collision(id);
              c.finish({{"text", fmt::format("robot {} reports a collision", c.args()[0])}});
            }});
}

int run_actor_fps(const ActorFpsOptions& o) {
  if (!o.actor.http.empty() && !o.buses.empty())
    throw Exception(usage("actor fps: --http draws the plane from its layout: give --layout (with --connect), not --bus"));
  const bool simulate = o.buses.empty() && !o.connect;
  return run_command([&o, simulate](asio::io_context& io, SignalHook hook) -> asio::awaitable<int> {
    std::unique_ptr<fps::sim::SimulatedPlane> sim;
    if (simulate) sim = std::make_unique<fps::sim::SimulatedPlane>(need(resolve_layout(o.layout)),
                                                                   fps::sim::SimulatedPlaneOptions{o.time_scale, o.seed});
    fps::ClientConfig cc;
    cc.plc_address = sim ? sim->plc_address() : o.plc;  // upgrade through the PLC
    fps::Client client(cc);
    if (!o.buses.empty()) client.open(o.buses);
    else client.open(sim ? sim->plane() : need(resolve_layout(o.layout)));
    actor::BusActor bus({o.actor.name, o.bus.link()});
    {
      // --http: the host's view of the plane, read beside the commands, out of their way.
      std::unique_ptr<web::FpsClientPage> page;
      if (!o.actor.http.empty()) {
        web::FpsHostPageOptions po;
        po.server = web::server_address(o.actor.http);
        page = std::make_unique<web::FpsClientPage>(po, client);
        std::fprintf(stderr, "listening http %s\n", page->where().c_str());
      }
      actor::FpsActorOptions fo;
      if (page) fo.on_bus_use = [&page](fps::BusUse use) { page->bus_use(use); };
      fo.status_period_s = o.actor.status_period_s;
      fo.friction_history = o.friction_history;
      fo.plc_address = cc.plc_address;
      actor::FpsActor fps_actor(bus.core(), client, fo);
      if (sim) add_simulator_verbs(bus.core(), *sim);
      bus.start();
      std::fprintf(stderr, "actor %s: %zu robots, commands on %s (exchange %s)\n", o.actor.name.c_str(), client.robots().size(),
                   o.bus.broker.c_str(), o.bus.exchange.c_str());
      co_await wait_for_stop(io, o.actor.duration_s, hook);
      bus.core().close();  // the simulator's verb too: nothing runs once the devices go
    }
    const auto c = bus.core().counters();
    std::fprintf(stderr, "actor %s: %llu commands, %llu refused, %llu not understood\n", o.actor.name.c_str(),
                 static_cast<unsigned long long>(c.received), static_cast<unsigned long long>(c.refused + c.busy),
                 static_cast<unsigned long long>(c.not_json + c.malformed + c.unknown + c.oversized));
    co_return 0;
  });
}

// ---- tell ---------------------------------------------------------------------------------------

struct TellArgs {
  BrokerOptions bus;
  std::string actor;
  std::vector<std::string> words;
  bool json = false;
  double timeout_s = 30;
};

// The words as one command line; a word with blanks or quotes is quoted.
std::string command_line(const std::vector<std::string>& words) {
  std::string line;
  for (const auto& w : words) {
    if (!line.empty()) line += ' ';
    if (w.find_first_of(" \t\"\\") == std::string::npos && !w.empty()) {
      line += w;
      continue;
    }
    line += '"';
    for (char c : w) line += (c == '"' || c == '\\') ? std::string{'\\', c} : std::string{c};
    line += '"';
  }
  return line;
}

void print_reply(const actor::TellReply& r, bool as_json) {
  if (as_json) {
    const nlohmann::json j{{"sender", r.sender}, {"message_code", std::string(1, actor::to_char(r.code))},
                           {"command_id", r.command_id}, {"keywords", r.keywords}};
    std::puts(j.dump().c_str());
  } else {
    std::string line = fmt::format("{} {}", r.sender, actor::to_char(r.code));
    for (const auto& [k, v] : r.keywords.items()) line += fmt::format(" {}={}", k, v.is_string() ? v.get<std::string>() : v.dump());
    std::puts(line.c_str());
  }
  std::fflush(stdout);
}

int run_tell(const TellArgs& a) {
  actor::TellOptions o;
  o.link = a.bus.link();
  o.timeout_s = a.timeout_s;
  const auto last = actor::tell(a.actor, command_line(a.words), o, [&a](const actor::TellReply& r) { print_reply(r, a.json); });
  return last.code == actor::MessageCode::done ? exit_code_value::ok : exit_code_value::failed;
}

}  // namespace

void add_actor_commands(CLI::App& app, GlobalOptions& global) {
  auto* group = app.add_subcommand("actor", "run axon as an actor on a RabbitMQ bus (docs/actor.md)");
  group->require_subcommand(1);
  auto fo = std::make_shared<ActorFpsOptions>();
  auto* f = group->add_subcommand("fps", "the focal plane as an actor (embedded simulated plane unless --bus/--connect)");
  add_broker_options(*f, fo->bus);
  add_actor_options(*f, fo->actor, "fps");
  f->add_option("--layout", fo->layout, "the plane: default, benchtop or a layout FILE (default benchtop)");
  f->add_option("--bus", fo->buses, "real buses by spec (cannet://HOST:PORT/N, ...): no simulator");
  f->add_flag("--connect", fo->connect, "the layout's gateways at their own addresses: no simulator");
  f->add_option("--time-scale", fo->time_scale, "simulator: simulated seconds per second (default 10)");
  f->add_option("--seed", fo->seed, "simulator: seed (default 1)");
  f->add_option("--plc", fo->plc, "with --connect or --bus: the PLC at HOST[:PORT] for upgrade, plc, power, gateway and sync (the simulator has its own)");
  f->add_option("--friction-history", fo->friction_history,
                 "CSV history the friction verb judges against and appends to (default: none, every arm a baseline)");
  f->callback([fo, &global] { global.exit_code = run_actor_fps(*fo); });
  add_actor_blmc_command(*group, global);
  add_actor_c4g_command(*group, global);

  auto ta = std::make_shared<TellArgs>();
  auto* t = app.add_subcommand("tell", "send a command to an actor over the bus; print the replies (exit 0 on ':')");
  add_broker_options(*t, ta->bus);
  t->add_option("actor", ta->actor, "the actor's name")->required();
  t->add_flag("--json", ta->json, "one JSON object per reply: sender, message_code, command_id, keywords");
  t->add_option("--timeout", ta->timeout_s, "seconds to wait for the final reply (default 30)");
  // Everything after the actor's name is the command, options of tell included (give those first):
  // `axon tell fps goto 12 -30 170` needs no `--`.
  t->prefix_command();
  t->footer("COMMAND [ARG ...] follows ACTOR; tell's own options go before ACTOR.");
  t->callback([ta, t, &global] {
    ta->words = t->remaining();
    if (!ta->words.empty() && ta->words.front() == "--") ta->words.erase(ta->words.begin());
    if (ta->words.empty()) throw Exception(usage("tell: give the command after the actor's name"));
    global.exit_code = run_tell(*ta);
  });
}

}  // namespace axon::app
