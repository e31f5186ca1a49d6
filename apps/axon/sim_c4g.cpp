// `axon sim c4g`: a simulated C4G robot controller that plays a robot program (scenario) and talks
// to a PC server over the open interface's UDP protocol, as the real controller would.
#include "axon/c4g/host/server.hpp"
#include "axon/c4g/sim/client_runner.hpp"
#include "axon/c4g/sim/controller.hpp"
#include "axon/c4g/sim/robots.hpp"
#include "axon/c4g/sim/scenario.hpp"
#include "axon/c4g/sim/udp_client.hpp"
#include "checks.hpp"
#include "exit_codes.hpp"
#include "commands.hpp"
#include "axon/net/endpoint.hpp"
#include "run.hpp"
#include "stop_signals.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <optional>

namespace axon::app {
namespace {

namespace sim = c4g::sim;

struct SimC4gOptions {
  std::string robot = "six-axis";
  std::string server = fmt::format("{}:{}", c4g::host::kDefaultServerAddress, c4g::host::kDefaultPort);
  std::string bind;
  int period_ms = 0;
  std::string scenario;
  double duration_s = 0;
  double reply_deadline_us = 0;
  std::string numbering = "same";
  int sync_packets = 3;
  bool json = false;
  // soft control switching (entering / leaving modes 1 and 2); negative: the robot's default
  double switch_t1_ms = -1, switch_t2_ms = -1, switch_t3_ms = -1;
  double switch_tolerance = -1;
  std::string switch_reducer = "controller";
};


double us(std::int64_t ns) { return static_cast<double>(ns) / 1000.0; }

int run_sim_c4g(const SimC4gOptions& o) {
  auto robot = need(sim::find_robot(o.robot));
  if (o.switch_t1_ms >= 0) robot.scs.times.t1_s = o.switch_t1_ms * 1e-3;
  if (o.switch_t2_ms >= 0) robot.scs.times.t2_s = o.switch_t2_ms * 1e-3;
  if (o.switch_t3_ms >= 0) robot.scs.times.t3_s = o.switch_t3_ms * 1e-3;
  if (o.switch_tolerance >= 0) robot.scs.still_tolerance = o.switch_tolerance;
  if (o.switch_reducer == "pc") robot.scs.reduce_pc_current = false;
  else if (o.switch_reducer != "controller") throw Exception(Error(CoreErrc::invalid_argument, "--switch-reducer is controller or pc"));
  const auto scenario = o.scenario.empty() ? sim::Scenario::default_scenario() : need(sim::Scenario::load_file(o.scenario));
  sim::ControllerOptions co;
  co.period_ms = o.period_ms;
  co.sync_packets = o.sync_packets;
  if (o.numbering == "next") co.numbering = c4g::protocol::ReplyNumbering::next;
  else if (o.numbering != "same") throw Exception(Error(CoreErrc::invalid_argument, "--numbering is same or next"));
  auto controller = need(sim::Controller::create(std::move(robot), scenario, co));
  const auto server = need(net::parse_endpoint(o.server, c4g::host::kManualPort));
  std::optional<net::Endpoint> local;
  if (!o.bind.empty()) local = need(net::parse_endpoint(o.bind, 0));
  auto opened = sim::UdpClient::open(server, local);
  if (!opened)
    throw Exception(Error(opened.error().code, fmt::format("{}: C4GOpen: error opening the socket UDP port {} ({})",
                                                           sim::event::kSocketError, server.port, opened.error().detail)));
  auto udp = std::move(opened).value();

  std::fprintf(stderr, "sim c4g: robot %s, %zu open axes, %d ms, scenario '%s', server %s, from %s\n",
               controller.robot().name.c_str(), controller.axis_count(), controller.init().period_ms,
               scenario.name.c_str(), server.to_string().c_str(), udp.local_endpoint().to_string().c_str());
  std::optional<StopSignals> signals(std::in_place);
  sim::RunOptions ro;
  ro.duration_s = o.duration_s;
  ro.stop = signals->flag();
  if (o.reply_deadline_us > 0)
    ro.reply_deadline = std::chrono::nanoseconds(static_cast<std::int64_t>(o.reply_deadline_us * 1000));
  nlohmann::json events = nlohmann::json::array();
  ro.on_event = [&](const sim::Event& e) {
    if (e.name == sim::event::kStep && !o.json) return std::fprintf(stderr, "  %8.3f s  %s\n", e.time_s, e.text.c_str()), void();
    std::fprintf(stderr, "  %8.3f s  %-7s %s: %s\n", e.time_s, std::string(sim::to_string(e.level)).c_str(), e.name.c_str(),
                 e.text.c_str());
    if (o.json) events.push_back({{"t", e.time_s}, {"cycle", e.cycle}, {"level", sim::to_string(e.level)}, {"name", e.name}, {"text", e.text}});
  };
  const auto report = sim::run_client(controller, udp, ro);
  signals.reset();

  const auto& s = controller.stats();
  const bool completed = controller.scenario_done() || (controller.scenario_running_forever() && report.stopped);
  int rc = 0;
  std::string outcome = "completed";
  // The exit-code scheme of every command (exit_codes.hpp): the controller's communication error
  // is its safety reaction (drives off): 4; a scenario that failed or did not finish: 1.
  if (controller.communication_error()) {
    rc = exit_code_value::safety_stop;
    outcome = "communication error";
  } else if (controller.scenario_failed()) {
    rc = exit_code_value::failed;
    outcome = "scenario error: " + controller.scenario_error();
  } else if (!completed) {
    rc = exit_code_value::failed;
    outcome = "scenario incomplete";
  }
  const auto& h = report.rtt;
  if (o.json) {
    nlohmann::json j = {
        {"outcome", outcome},
        {"exit_code", rc},
        {"robot", controller.robot().name},
        {"period_ms", controller.init().period_ms},
        {"elapsed_s", report.elapsed_s},
        {"ticks", s.ticks},
        {"packets_sent", s.packets_sent},
        {"sync_sent", s.sync_sent},
        {"init_sent", s.init_sent},
        {"cyclic_sent", s.cyclic_sent},
        {"replies_ok", s.replies_ok},
        {"misses", s.misses},
        {"max_consecutive_misses", s.max_consecutive_misses},
        {"late_replies", s.late_replies},
        {"wrong_number", s.wrong_number},
        {"wrong_size", s.wrong_size},
        {"malformed", s.malformed},
        {"frozen_cycles", s.frozen_cycles},
        {"refused_requests", s.refused_requests},
        {"saturated_cycles", s.saturated_cycles},
        {"overruns", report.overruns},
        {"rtt_us", {{"count", h.count()}, {"min", us(h.min())}, {"mean", h.mean() / 1000.0}, {"p50", us(h.percentile(50))},
                    {"p99", us(h.percentile(99))}, {"p999", us(h.percentile(99.9))}, {"max", us(h.max())}}},
        {"events", events},
    };
    std::printf("%s\n", j.dump(2).c_str());
  } else {
    std::printf("sim c4g: %s after %.3f s: %llu cycles, %llu packets sent (%llu sync, %llu init), %llu replies ok, "
                "%llu misses (max %llu in a row; %llu late, %llu wrong number, %llu wrong size, %llu malformed), "
                "%llu schedule overruns\n",
                outcome.c_str(), report.elapsed_s, static_cast<unsigned long long>(s.ticks),
                static_cast<unsigned long long>(s.packets_sent), static_cast<unsigned long long>(s.sync_sent),
                static_cast<unsigned long long>(s.init_sent), static_cast<unsigned long long>(s.replies_ok),
                static_cast<unsigned long long>(s.misses), static_cast<unsigned long long>(s.max_consecutive_misses),
                static_cast<unsigned long long>(s.late_replies), static_cast<unsigned long long>(s.wrong_number),
                static_cast<unsigned long long>(s.wrong_size), static_cast<unsigned long long>(s.malformed),
                static_cast<unsigned long long>(report.overruns));
    std::printf("rtt: %llu samples, p50 %.1f us, p99 %.1f us, max %.1f us\n", static_cast<unsigned long long>(h.count()),
                us(h.percentile(50)), us(h.percentile(99)), us(h.max()));
  }
  std::fflush(stdout);
  return rc;
}

}  // namespace

void add_sim_c4g_command(CLI::App& sim_cmd) {
  static SimC4gOptions opts;
  auto* c = sim_cmd.add_subcommand("c4g", "simulated C4G controller (open interface client) playing a robot program");
  c->add_option("--robot", opts.robot, "robot model (six-axis)");
  c->add_option("--server", opts.server, "the PC server HOST[:PORT] (default 127.0.0.1:11000, where `axon c4g serve` listens by default; a host alone: the manual's port 1000)");
  c->add_option("--bind", opts.bind, "local HOST:PORT of the controller (default: any)");
  c->add_option("--period-ms", opts.period_ms, "controller period, 1 or 2 ms (default: the robot's, 2)")->check(CLI::Range(1, 2));
  c->add_option("--scenario", opts.scenario, "scenario YAML (docs/c4g-simulator.md); default: drive on, mode 0, a move, run");
  c->add_option("--duration", opts.duration_s, "stop after this many seconds (default: when the scenario ends or Ctrl-C)")->check(non_negative());
  c->add_option("--reply-deadline-us", opts.reply_deadline_us, "reply deadline after each send (default: one period)")->check(positive());
  c->add_option("--numbering", opts.numbering, "reply numbering expected: same (manual) or next (NUM + 1)");
  c->add_option("--sync-packets", opts.sync_packets, "answered sync packets before the initialization packet")->check(CLI::Range(0, 1000));
  c->add_flag("--json", opts.json, "print the summary (and events) as JSON");
  c->add_option("--switch-t1-ms", opts.switch_t1_ms, "soft switching pre-switching interval T1 [ms] (default 50)")->check(CLI::Range(0.0, 60000.0));
  c->add_option("--switch-t2-ms", opts.switch_t2_ms, "soft switching ramp T2 [ms] (default 100)")->check(CLI::Range(0.0, 60000.0));
  c->add_option("--switch-t3-ms", opts.switch_t3_ms, "soft switching post-switching interval T3 [ms] (default 50)")->check(CLI::Range(0.0, 60000.0));
  c->add_option("--switch-tolerance", opts.switch_tolerance, "motor turns the robot may move during T1..T3 (default 0.02)")->check(CLI::Range(0.0, 1e6));
  c->add_option("--switch-reducer", opts.switch_reducer, "who scales the PC's current while switching: controller (default) or pc");
  c->callback([] { exit_code() = run_sim_c4g(opts); });
}

}  // namespace axon::app
