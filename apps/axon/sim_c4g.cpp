// `axon sim c4g`: a simulated C4G robot controller that plays a robot program (scenario) and talks
// to a PC server over the open interface's UDP protocol, as the real controller would. The run is
// c4g::sim::SimulatedController; here are the arguments and the printing. --http serves the
// controller's own truth (joints, modes, the program's step, the PC's replies judged, events) on the
// c4g simulator page (docs/dashboard.md): snapshots the controller's thread queues lock-free, taken
// and published on this thread.
#include "axon/c4g/host/server.hpp"
#include "axon/c4g/sim/simulated_controller.hpp"
#include "axon/net/endpoint.hpp"
#include "axon/web/c4g_sim_view.hpp"
#include "axon/web/server.hpp"
#include "checks.hpp"
#include "commands.hpp"
#include "run.hpp"
#include "stop_signals.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <memory>
#include <optional>
#include <thread>

namespace axon::app {
namespace {

namespace sim = c4g::sim;

struct SimC4gArgs {
  std::string robot = "six-axis";
  std::string server = fmt::format("{}:{}", c4g::host::kDefaultServerAddress, c4g::host::kDefaultPort);
  std::string bind;
  int period_ms = 0;
  std::string scenario;
  double duration_s = 0;
  double reply_deadline_us = 0;
  bool lenient_timing = false;
  std::string numbering = "same";
  int sync_packets = 3;
  bool json = false;
  // soft control switching (entering / leaving modes 1 and 2); negative: the robot's default
  double switch_t1_ms = -1, switch_t2_ms = -1, switch_t3_ms = -1;
  double switch_tolerance = -1;
  std::string switch_reducer = "controller";
  std::string http;          // HOST:PORT of the live page (empty: none)
  double http_linger_s = 0;  // keep serving the final state this long after the run
};

sim::SimulatedControllerOptions sim_options(const SimC4gArgs& o) {
  sim::SimulatedControllerOptions s;
  s.server = o.server;
  s.bind = o.bind;
  s.robot = o.robot;
  s.scenario_file = o.scenario;
  s.duration_s = o.duration_s;
  s.controller.period_ms = o.period_ms;
  s.controller.sync_packets = o.sync_packets;
  if (o.numbering == "next") s.controller.numbering = c4g::protocol::ReplyNumbering::next;
  else if (o.numbering != "same") throw Exception(Error(CoreErrc::invalid_argument, "--numbering is same or next"));
  if (o.lenient_timing) s.reply_window = sim::ReplyWindow::period;
  if (o.reply_deadline_us > 0) s.reply_deadline = std::chrono::nanoseconds(static_cast<std::int64_t>(o.reply_deadline_us * 1000));
  s.switch_t1_s = o.switch_t1_ms >= 0 ? o.switch_t1_ms * 1e-3 : -1;
  s.switch_t2_s = o.switch_t2_ms >= 0 ? o.switch_t2_ms * 1e-3 : -1;
  s.switch_t3_s = o.switch_t3_ms >= 0 ? o.switch_t3_ms * 1e-3 : -1;
  s.switch_tolerance = o.switch_tolerance;
  if (o.switch_reducer == "pc") s.pc_reduces_current = true;
  else if (o.switch_reducer != "controller") throw Exception(Error(CoreErrc::invalid_argument, "--switch-reducer is controller or pc"));
  // Events go to stderr as they happen (program steps only without --json, where the JSON has them).
  s.on_event = [json = o.json](const sim::Event& e) {
    if (e.name == sim::event::kStep && !json) return std::fprintf(stderr, "  %8.3f s  %s\n", e.time_s, e.text.c_str()), void();
    std::fprintf(stderr, "  %8.3f s  %-7s %s: %s\n", e.time_s, std::string(sim::to_string(e.level)).c_str(), e.name.c_str(),
                 e.text.c_str());
  };
  return s;
}

nlohmann::json report_json(const sim::SimulatedControllerReport& r) {
  const auto& s = r.stats;
  nlohmann::json events = nlohmann::json::array();
  for (const auto& e : r.events)
    events.push_back({{"t", e.time_s}, {"cycle", e.cycle}, {"level", sim::to_string(e.level)}, {"name", e.name}, {"text", e.text}});
  return {{"outcome", r.outcome_text}, {"exit_code", r.exit_code()}, {"robot", r.robot}, {"period_ms", r.period_ms},
          {"elapsed_s", r.elapsed_s}, {"ticks", s.ticks}, {"packets_sent", s.packets_sent}, {"sync_sent", s.sync_sent},
          {"init_sent", s.init_sent}, {"cyclic_sent", s.cyclic_sent}, {"replies_ok", s.replies_ok}, {"misses", s.misses},
          {"max_consecutive_misses", s.max_consecutive_misses}, {"late_replies", s.late_replies},
          {"wrong_number", s.wrong_number}, {"wrong_size", s.wrong_size}, {"malformed", s.malformed},
          {"frozen_cycles", s.frozen_cycles}, {"refused_requests", s.refused_requests},
          {"saturated_cycles", s.saturated_cycles}, {"overruns", r.overruns}, {"reply_window_us", r.reply_window_us},
          {"rtt_us", {{"count", r.rtt_count}, {"min", r.rtt_min_us}, {"mean", r.rtt_mean_us}, {"p50", r.rtt_p50_us},
                      {"p99", r.rtt_p99_us}, {"p999", r.rtt_p999_us}, {"max", r.rtt_max_us}}},
          {"events", events}};
}

void print_text(const sim::SimulatedControllerReport& r) {
  const auto& s = r.stats;
  auto u = [](std::uint64_t v) { return static_cast<unsigned long long>(v); };
  std::printf("sim c4g: %s after %.3f s: %llu cycles, %llu packets sent (%llu sync, %llu init), %llu replies ok, "
              "%llu misses (max %llu in a row; %llu late, %llu wrong number, %llu wrong size, %llu malformed), "
              "%llu schedule overruns\n",
              r.outcome_text.c_str(), r.elapsed_s, u(s.ticks), u(s.packets_sent), u(s.sync_sent), u(s.init_sent),
              u(s.replies_ok), u(s.misses), u(s.max_consecutive_misses), u(s.late_replies), u(s.wrong_number),
              u(s.wrong_size), u(s.malformed), u(r.overruns));
  std::printf("rtt: %llu samples, p50 %.1f us, p99 %.1f us, max %.1f us; reply window %.0f us\n", u(r.rtt_count),
              r.rtt_p50_us, r.rtt_p99_us, r.rtt_max_us, r.reply_window_us);
}

// ---- --http: the simulator's page -----------------------------------------------------------------

constexpr auto kLivePeriod = std::chrono::milliseconds(20);  // snapshots: 50 a second
constexpr auto kPublishPeriod = std::chrono::milliseconds(100);  // the page: 10 updates a second

struct SimWebPage {
  std::unique_ptr<web::Server> server;
  std::shared_ptr<web::Source> source;
  std::unique_ptr<web::C4gSimView> view;
  sim::LiveState live;
  std::chrono::steady_clock::time_point next{};

  [[nodiscard]] std::string where() const { return fmt::format("{}:{}", server->address(), server->port()); }
  // Takes what the controller's thread queued; publishes every kPublishPeriod (the metrics once a second).
  void tick(sim::SimulatedController& c, bool force = false) {
    const bool got = c.take_live(live, [this](const sim::LiveEvent& e) { view->add_event(e); });
    if (got) view->update(live, c.live_dropped());
    const auto now = std::chrono::steady_clock::now();
    if (!force && now < next) return;
    next = now + kPublishPeriod;
    view->publish(*source, force ? 1 : 10);
  }
};

std::unique_ptr<SimWebPage> open_sim_page(const SimC4gArgs& o, const sim::SimulatedController& c) {
  const auto ep = need(net::parse_endpoint(o.http));
  web::ServerOptions so;
  so.address = ep.host;
  so.port = ep.port;
  auto page = std::make_unique<SimWebPage>();
  web::C4gSimViewOptions vo;
  vo.command = fmt::format("sim c4g --robot {}", o.robot);
  vo.robot = c.robot().name;
  vo.program = o.scenario.empty() ? "the default program" : o.scenario;
  vo.server = o.server;
  vo.period_ms = c.robot().init.period_ms;
  if (o.period_ms > 0) vo.period_ms = o.period_ms;
  vo.steps = c.program_steps();
  page->view = std::make_unique<web::C4gSimView>(std::move(vo));
  page->server = std::make_unique<web::Server>(so);
  page->source = std::make_shared<web::Source>("c4g-sim", fmt::format("c4g simulator: {} to {}", c.robot().name, o.server), "c4g-sim");
  page->source->set_info(page->view->info_json());
  page->view->publish(*page->source, 1);
  page->server->add(page->source);
  return page;
}

// --http-linger: the page goes on showing how the run ended until the time is up or a stop signal.
void linger_sim_page(SimWebPage& page, sim::SimulatedController& c, double seconds, const StopSignals& signals) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < until && signals.count() == 0) {
    std::this_thread::sleep_for(kPublishPeriod);
    page.tick(c, true);
  }
}

int run_sim_c4g(const SimC4gArgs& o) {
  std::optional<StopSignals> signals(std::in_place);
  auto options = sim_options(o);
  if (!o.http.empty()) options.live_period_s = std::chrono::duration<double>(kLivePeriod).count();
  auto controller = sim::SimulatedController::start(std::move(options));
  std::fprintf(stderr, "sim c4g: %s\n", controller.describe().c_str());
  auto page = o.http.empty() ? nullptr : open_sim_page(o, controller);
  if (page) {
    std::fprintf(o.json ? stderr : stdout, "listening http %s\n", page->where().c_str());
    std::fflush(o.json ? stderr : stdout);
  }
  std::optional<sim::SimulatedControllerReport> report;
  while (!(report = controller.wait_for(kLivePeriod))) {
    if (signals->count() > 0) report = controller.stop();
    if (page) page->tick(controller);
  }
  if (page) page->tick(controller, true);  // the last snapshot and events
  if (o.json) std::printf("%s\n", report_json(*report).dump(2).c_str());
  else print_text(*report);
  std::fflush(stdout);
  // A run a signal ended does not linger: the user asked to stop.
  if (page && o.http_linger_s > 0 && signals->count() == 0) linger_sim_page(*page, controller, o.http_linger_s, *signals);
  signals.reset();
  return report->exit_code();
}

}  // namespace

void add_sim_c4g_command(CLI::App& sim_cmd, GlobalOptions& global) {
  auto o = std::make_shared<SimC4gArgs>();
  auto* c = sim_cmd.add_subcommand("c4g", "simulated C4G controller (open interface client) playing a robot program");
  c->add_option("--robot", o->robot, "robot: six-axis (the manual's example), or a file: a captured 1200-byte initialization packet or its fields in YAML (docs/c4g-simulator.md)");
  c->add_option("--server", o->server, "the PC server HOST[:PORT] (default 127.0.0.1:11000, where `axon c4g serve` listens by default; a host alone: the manual's port 1000)");
  c->add_option("--bind", o->bind, "local HOST:PORT of the controller (default: any)");
  c->add_option("--period-ms", o->period_ms, "controller period, 1 or 2 ms (default: the robot's, 2)")->check(CLI::Range(1, 2));
  c->add_option("--scenario", o->scenario, "scenario YAML (docs/c4g-simulator.md); default: drive on, mode 0, a move, run");
  c->add_option("--duration", o->duration_s, "stop after this many seconds (default: when the scenario ends or Ctrl-C)")->check(non_negative());
  c->add_option("--reply-deadline-us", o->reply_deadline_us, "reply window after each send [us] (default: the manual's T_CYCLE1, 500 us)")->check(positive());
  c->add_flag("--lenient-timing", o->lenient_timing, "accept a reply up to a whole period after the send (slow or loaded machines; the real controller does not)");
  c->add_option("--numbering", o->numbering, "reply numbering expected: same (manual) or next (NUM + 1)");
  c->add_option("--sync-packets", o->sync_packets, "answered sync packets before the initialization packet")->check(CLI::Range(0, 1000));
  c->add_flag("--json", o->json, "print the summary (and events) as JSON");
  c->add_option("--switch-t1-ms", o->switch_t1_ms, "soft switching pre-switching interval T1 [ms] (default 50)")->check(CLI::Range(0.0, 60000.0));
  c->add_option("--switch-t2-ms", o->switch_t2_ms, "soft switching ramp T2 [ms] (default 100)")->check(CLI::Range(0.0, 60000.0));
  c->add_option("--switch-t3-ms", o->switch_t3_ms, "soft switching post-switching interval T3 [ms] (default 50)")->check(CLI::Range(0.0, 60000.0));
  c->add_option("--switch-tolerance", o->switch_tolerance, "motor turns the robot may move during T1..T3 (default 0.02)")->check(CLI::Range(0.0, 1e6));
  c->add_option("--switch-reducer", o->switch_reducer, "who scales the PC's current while switching: controller (default) or pc");
  c->add_option("--http", o->http, "serve the controller's live page (the simulator's truth), /api/state and /metrics on "
                                   "HOST:PORT (port 0: any; docs/dashboard.md)");
  c->add_option("--http-linger", o->http_linger_s, "with --http: keep serving the final state this many seconds after the "
                                                   "run (a stop signal ends it; default 0)")->check(non_negative());
  c->callback([o, &global] { global.exit_code = run_sim_c4g(*o); });
}

}  // namespace axon::app
