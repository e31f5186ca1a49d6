// `axon c4g`: the PC side of the robot controller's open interface.
//   serve      runs a c4g::apps::ServeSession (server + one of the built-in applications + recorders)
//   init-info  prints an initialization packet from a 1200-byte file or from a capture
// The ready line `listening c4g HOST:PORT`, events and status lines go to stdout; logs to stderr.
// With --json, stdout carries one JSON document and nothing else: the lines go to stderr.
// --http HOST:PORT serves the live page and /metrics (docs/dashboard.md): a web::C4gView fed on
// run()'s thread from the session's hooks, never on the cycle thread.
// What runs lives in the library (src/axon/c4g/apps: app_factory.hpp, serve.hpp); here are the
// arguments, the freezing controls (signals, --freeze-at/--freeze-for) and the printing.
#include "axon/c4g/apps/app_factory.hpp"
#include "axon/c4g/apps/freeze_schedule.hpp"
#include "axon/c4g/apps/serve.hpp"
#include "axon/c4g/host/pcap_recorder.hpp"
#include "axon/c4g/host/server.hpp"
#include "axon/c4g/protocol/axis_map.hpp"
#include "axon/c4g/protocol/init_packet.hpp"
#include "axon/net/endpoint.hpp"
#include "axon/web/c4g_view.hpp"
#include "axon/web/server.hpp"
#include "checks.hpp"
#include "commands.hpp"
#include "rotation_options.hpp"
#include "run.hpp"
#include "stop_signals.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <memory>
#include <thread>

namespace axon::app {
namespace {

namespace apps = c4g::apps;
namespace host = c4g::host;
namespace protocol = c4g::protocol;
using json = nlohmann::json;

struct ServeArgs {
  apps::AppConfig app;
  std::string listen = fmt::format("{}:{}", host::kDefaultServerAddress, host::kDefaultPort);
  std::string controller;  // HOST[:PORT]; empty: learned from the first packet
  double period_ms = 0;    // timing figures until the initialization packet gives the period
  double switch_t1_ms = 50, switch_t2_ms = 100, switch_t3_ms = 50;
  int moni = -1;
  std::string csv;
  std::string numbering = "same";
  std::string pcap;
  RotationArgs pcap_rotation, csv_rotation;
  int rt_priority = 0;
  std::vector<int> cpus;
  bool busy_poll = false;
  double max_step = 0;
  std::vector<std::string> stroke_ends;  // [ARM.]AXIS=MIN:MAX [deg]
  bool no_stroke_ends = false, no_continuity_check = false, no_following_error_check = false;
  double duration_s = 0;
  bool until_controller_ends = false;
  double status_interval_s = 1.0;
  double stop_timeout_s = 5.0;
  bool json = false;
  double freeze_at_s = 0;  // active freezing
  double freeze_for_s = 0;
  std::string http;          // HOST:PORT of the live page (empty: none)
  double http_linger_s = 0;  // keep serving the final state this long after the run
};

struct InitInfoArgs {
  std::string file;
  bool from_pcap = false;
  bool json = false;
};

Exception bad(std::string text) { return Exception(Error(CoreErrc::invalid_argument, std::move(text))); }

// SIGUSR1 asks for active freezing, SIGUSR2 releases it (run_serve's poll reads and clears it). A
// signal handler can only reach a static: this is the one place it lives.
std::atomic<int>& freeze_signal() noexcept {
  static std::atomic<int> sig{0};
  return sig;
}
void on_freeze_signal(int sig) noexcept { freeze_signal().store(sig == SIGUSR1 ? 1 : 2); }

// Installs the SIGUSR1/SIGUSR2 handlers for the server's lifetime.
struct FreezeSignals {
  FreezeSignals() {
    freeze_signal().store(0);
    struct sigaction sa{};
    sa.sa_handler = &on_freeze_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGUSR1, &sa, nullptr);
    sigaction(SIGUSR2, &sa, nullptr);
  }
  ~FreezeSignals() {
    std::signal(SIGUSR1, SIG_DFL);
    std::signal(SIGUSR2, SIG_DFL);
  }
  FreezeSignals(const FreezeSignals&) = delete;
  FreezeSignals& operator=(const FreezeSignals&) = delete;
};

apps::ServeOptions serve_options(const ServeArgs& o) {
  apps::ServeOptions s;
  auto& so = s.server;
  so.listen = need(net::parse_endpoint(o.listen, host::kManualPort));
  if (!o.controller.empty()) so.controller = need(net::parse_endpoint(o.controller, 0));
  so.period = std::chrono::nanoseconds(static_cast<std::int64_t>(o.period_ms * 1e6));
  if (o.numbering == "same") so.numbering = protocol::ReplyNumbering::same;
  else if (o.numbering == "next") so.numbering = protocol::ReplyNumbering::next;
  else throw bad("--numbering must be same or next");
  so.pcap_path = o.pcap;
  so.pcap.rotation = o.pcap_rotation.limits();
  so.soft_switch = {o.switch_t1_ms * 1e-3, o.switch_t2_ms * 1e-3, o.switch_t3_ms * 1e-3};
  so.cycle.realtime.fifo_priority = o.rt_priority;
  so.cycle.realtime.lock_memory = o.rt_priority > 0;
  so.cycle.realtime.cpus = o.cpus;
  so.udp.busy_poll = o.busy_poll;
  if (o.max_step > 0)
    for (auto& a : so.safety.axes) a.max_step = static_cast<float>(o.max_step);
  so.safety.max_motor_speed = o.app.max_motor_speed;
  for (const auto& spec : o.stroke_ends) need(host::parse_stroke_end(spec, o.app.arm, so.safety));
  so.safety.check_stroke_ends = !o.no_stroke_ends;
  so.safety.check_continuity = !o.no_continuity_check;
  so.safety.check_following_error = !o.no_following_error_check;
  if (o.csv.empty() && o.moni >= 0) throw bad("--moni needs --csv FILE");
  s.csv = o.csv;
  s.moni = o.moni < 0 ? 0 : o.moni;
  s.csv_rotation = o.csv_rotation.limits();
  s.duration_s = o.duration_s;
  s.until_controller_ends = o.until_controller_ends;
  s.stop_timeout_s = o.stop_timeout_s;
  s.status_interval_s = o.status_interval_s;
  return s;
}

// ---- --http: the live page ----------------------------------------------------------------------

// The server's page on a web server of its own thread. The view is fed and published from the
// session's hooks on run()'s thread: the app's events as run() drains them, the server's counters
// read at each publish.
struct C4gWebPage {
  std::unique_ptr<web::Server> server;
  std::shared_ptr<web::Source> source;
  std::unique_ptr<web::C4gView> view;
  std::chrono::steady_clock::time_point next{};

  [[nodiscard]] std::string where() const { return fmt::format("{}:{}", server->address(), server->port()); }
  // About 10 times a second (run() polls every 20 ms); the metrics once a second.
  void tick() {
    const auto now = std::chrono::steady_clock::now();
    if (now < next) return;
    next = now + std::chrono::milliseconds(100);
    view->publish(*source, 10);
  }
  void publish_all() { view->publish(*source, 1); }
};

std::unique_ptr<C4gWebPage> open_c4g_page(const ServeArgs& o, const apps::App& app, apps::ServeSession& session) {
  const auto ep = need(net::parse_endpoint(o.http));
  web::ServerOptions so;
  so.address = ep.host;
  so.port = ep.port;
  auto page = std::make_unique<C4gWebPage>();
  web::C4gViewOptions vo;
  vo.command = fmt::format("serve --app {}", o.app.app);
  vo.soft_switch = {o.switch_t1_ms * 1e-3, o.switch_t2_ms * 1e-3, o.switch_t3_ms * 1e-3};
  page->view = std::make_unique<web::C4gView>(app, session.server(), std::move(vo));
  page->server = std::make_unique<web::Server>(so);
  page->source = std::make_shared<web::Source>(
      "c4g", fmt::format("c4g: {} on {}", o.app.app, session.local_address()), "c4g");
  page->source->set_info(page->view->info_json());
  page->publish_all();
  page->server->add(page->source);
  return page;
}

// --http-linger: the page goes on showing how the run ended until the time is up or a stop signal,
// which is then the normal end. A run a signal ended does not linger: the user asked to stop.
void linger_c4g_page(C4gWebPage& page, double seconds_left, const StopSignals& signals) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds_left);
  while (std::chrono::steady_clock::now() < until && signals.count() == 0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    page.publish_all();
  }
}

int run_serve(const ServeArgs& o) {
  std::FILE* out = o.json ? stderr : stdout;  // stdout carries the JSON report alone
  auto say = [out](const std::string& line) {
    std::fprintf(out, "%s\n", line.c_str());
    std::fflush(out);
  };
  auto app = apps::make_app(o.app, say);
  StopSignals signals;
  FreezeSignals freeze_signals;
  apps::ServeSession session(*app, serve_options(o));
  session.start();
  auto page = o.http.empty() ? nullptr : open_c4g_page(o, *app, session);
  say("listening c4g " + session.local_address());
  if (page) say("listening http " + page->where());
  apps::FreezeSchedule freeze(session.server(), {o.freeze_at_s, o.freeze_for_s}, say);
  apps::ServeSession::Hooks hooks;
  hooks.on_session = [&](const std::string& peer) { std::fprintf(out, "session: controller %s\n", peer.c_str()); };
  hooks.on_event = [&](const apps::Event& e, const std::string& text) {
    std::fprintf(out, "event cycle %llu: %s\n", static_cast<unsigned long long>(e.cycle), text.c_str());
    if (page) page->view->add_event(e, text);
  };
  hooks.on_status = say;
  hooks.on_poll = [&] {
    if (const int sig = freeze_signal().exchange(0); sig == 1) freeze.request("SIGUSR1");
    else if (sig == 2) freeze.release("SIGUSR2");
    freeze.poll();
    if (page) page->tick();
    std::fflush(out);
  };
  hooks.on_stopping = [&] { freeze.stopping(); };
  hooks.interruptions = [&] { return signals.count(); };
  const auto report = session.run(hooks);
  if (o.json) std::printf("%s\n", report.json().c_str());
  else std::printf("%s", report.text().c_str());
  std::fflush(stdout);
  if (page) {
    page->publish_all();
    if (o.http_linger_s > 0) linger_c4g_page(*page, o.http_linger_s, signals);
  }
  return report.exit_code();
}

// The initialization packet as JSON: every field under its name in the controller's struct (arrays
// for the per-axis ones), then the open axes as the axis map reads them.
json init_json(const protocol::InitPacket& init, const Result<protocol::AxisMap>& map) {
  json fields = json::object();
  protocol::for_each_field(init, [&](std::string_view name, int index, const auto& v) {
    const std::string key(name);
    if (index < 0) fields[key] = v;
    else fields[key].push_back(v);
  });
  json j{{"fields", fields}, {"open_axes", init.open_axes}, {"period_ms", init.period_ms}};
  if (!map) {
    j["axis_map_error"] = map.error().detail;
    return j;
  }
  json axes = json::array();
  for (std::size_t i = 0; i < map.value().count(); ++i) {
    const auto ref = map.value().logical(i);
    axes.push_back({{"open_axis", i + 1}, {"arm", ref.arm}, {"axis", ref.axis}});
  }
  j["axis_map"] = axes;
  return j;
}

int run_init_info(const InitInfoArgs& a) {
  std::vector<std::byte> bytes;
  if (a.from_pcap) {
    bytes = need(host::read_init_packet(a.file));
  } else {
    std::ifstream in(a.file, std::ios::binary);
    if (!in) throw bad(fmt::format("cannot open {}", a.file));
    std::vector<char> raw((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (char c : raw) bytes.push_back(static_cast<std::byte>(c));
  }
  const auto init = need(protocol::decode_init(bytes));
  auto map = protocol::AxisMap::from_init(init);
  if (a.json) {
    std::printf("%s\n", init_json(init, map).dump(2).c_str());
    return map ? 0 : 1;
  }
  std::printf("%s", protocol::to_string(init).c_str());
  if (!map) {
    std::printf("axis map: %s\n", map.error().detail.c_str());
    return 1;
  }
  for (std::size_t i = 0; i < map.value().count(); ++i) {
    const auto ref = map.value().logical(i);
    std::printf("open axis %zu = arm %u axis %u\n", i + 1, static_cast<unsigned>(ref.arm), static_cast<unsigned>(ref.axis));
  }
  return 0;
}

void add_serve(CLI::App* c4g, GlobalOptions& global) {
  auto o = std::make_shared<ServeArgs>();
  auto* s = c4g->add_subcommand("serve", "serve the controller's packets with a built-in application (docs/c4g-cli.md)");
  s->add_option("--listen", o->listen, "HOST[:PORT] to serve on (default 127.0.0.1:11000; the manual's: 10.2.12.149:1000; a host alone: port 1000; port 0: any free)");
  s->add_option("--controller", o->controller, "HOST[:PORT] of the controller: only it may start a session (default: the first well-formed packet's source; a host alone: any port)");
  s->add_option("--period-ms", o->period_ms, "the controller's period for the timing figures until its initialization packet gives it [ms]")->check(positive());
  s->add_option("--app", o->app.app, "monitor (mode 0), echo (0'), stream (4/5), correct (7), pid (1/2), handover (every open phase: 4/5 and 7), contribute (8/9)")->required();
  s->add_option("--file", o->app.file, "stream: trajectory CSV; correct: correction values CSV");
  s->add_option("--segment", o->app.segments, "stream/handover: MOTION_TYPE=FILE.csv, the trajectory for that motion type (CMD byte of the arm); repeatable");
  s->add_option("--correct-file", o->app.correct_file, "handover: correction values CSV for mode 7");
  s->add_flag("--rearm", o->app.rearm, "stream/correct: serve the mode again each time the program re-enters it (until 504 or Ctrl-C)");
  s->add_option("--mode", o->app.mode, "stream: 4 (absolute targets) or 5 (increments); contribute: 8 (velocity) or 9 (current)");
  s->add_option("--units", o->app.units, "angles in the CSV: rad or deg (else the file's '# units:' line, else rad)");
  s->add_flag("--relative", o->app.relative, "stream: the trajectory is offsets from the robot's position at the start");
  s->add_option("--start-tolerance", o->app.start_tolerance_deg, "stream: start-point tolerance [deg] (default 0.5)")->check(non_negative());
  s->add_option("--max-motor-speed", o->app.max_motor_speed, "continuity limit [motor turns/s] of the apps and of Safety (default 100)")->check(positive());
  s->add_option("--arm", o->app.arm, "the arm the application drives (default 1)")->check(CLI::Range(1, 4));
  s->add_option("--amplitude", o->app.amplitude, "correct/pid: sine amplitude per axis [deg, link side]; contribute: [motor turns/s] (mode 8) or [A] (mode 9)")->delimiter(',');
  s->add_option("--frequency", o->app.frequency_hz, "correct/pid: sine frequency per axis [Hz] (default 0.5)")->delimiter(',')->check(non_negative());
  s->add_option("--open-time", o->app.open_time_s, "correct/pid: leave the open mode after this long [s] (0: until stopped); handover: hold / zero-correction / sine time per phase (default 0.5)")->check(non_negative());
  s->add_option("--ramp", o->app.ramp_s, "fade in/out time of corrections and sines [s] (default 0.5)")->check(non_negative());
  s->add_option("--feed", o->app.feed, "correct: live correction values over UDP on HOST:PORT (one datagram of numbers per measurement)");
  s->add_option("--feed-from", o->app.feed_from, "correct: read the feed only from this sensor HOST[:PORT] (a host alone: any port); others are counted and ignored");
  s->add_option("--feed-axes", o->app.feed_axes, "correct: values per feed datagram (default 6)")->check(CLI::Range(1, 10));
  s->add_option("--feed-timeout-ms", o->app.feed_timeout_ms, "correct: feed values older than this count as none (default 100)")->check(positive());
  s->add_option("--max-correction", o->app.max_correction_deg, "correct (and the pid sine): largest correction per axis [deg, link side] (default 5; one value: every axis); beyond it a feed reading is refused, a sine or file is refused at start")->delimiter(',')->check(positive());
  s->add_option("--max-correction-step", o->app.max_correction_step_deg, "correct (and the pid sine): largest change of the correction per cycle and axis [deg, link side] (default 0.1); a feed slews at it, a sine or file that needs more is refused")->delimiter(',')->check(positive());
  s->add_option("--kp", o->app.kp, "pid: position gain per axis [1/s]")->delimiter(',');
  s->add_option("--kv", o->app.kv, "pid: velocity gain per axis [A/(turn/s)]")->delimiter(',');
  s->add_option("--ki", o->app.ki, "pid: velocity integral rate per axis [1/s]")->delimiter(',');
  s->add_flag("--no-dynamic-model", o->app.no_dynamic_model, "pid: do not feed the controller's dynamic-model current forward");
  s->add_flag("--reduce-in-pc", o->app.reduce_in_pc, "pid: scale D5 by the soft-switching factor here (for a controller that does not)");
  s->add_option("--switch-t1-ms", o->switch_t1_ms, "the controller's soft switching T1 [ms] (default 50)")->check(CLI::Range(0.0, 60000.0));
  s->add_option("--switch-t2-ms", o->switch_t2_ms, "the controller's soft switching T2 [ms] (default 100)")->check(CLI::Range(0.0, 60000.0));
  s->add_option("--switch-t3-ms", o->switch_t3_ms, "the controller's soft switching T3 [ms] (default 50)")->check(CLI::Range(0.0, 60000.0));
  s->add_option("--moni", o->moni, "with --csv: monitoring view 19..24 of the manual (default 0: every field)");
  s->add_option("--csv", o->csv, "write every cycle to this CSV file");
  add_rotation_options(s, o->csv_rotation, "csv", "--csv");
  s->add_option("--numbering", o->numbering, "reply number: same (the manual) or next (NUM + 1)");
  s->add_option("--pcap", o->pcap, "record every datagram into this pcap file");
  add_rotation_options(s, o->pcap_rotation, "pcap", "--pcap");
  s->add_option("--rt-priority", o->rt_priority, "SCHED_FIFO priority of the cycle thread (and mlockall)")->check(CLI::Range(0, 99));
  s->add_option("--cpu", o->cpus, "pin the cycle thread to this CPU (repeatable)");
  s->add_flag("--busy-poll", o->busy_poll, "spin on the socket instead of sleeping (a dedicated core)");
  s->add_option("--max-step", o->max_step, "Safety: max change of a commanded position per cycle [motor turns] (default: --max-motor-speed x the period)")->check(non_negative());
  s->add_option("--stroke-end", o->stroke_ends, "Safety: a joint's stroke ends at the link, [ARM.]AXIS=MIN:MAX [deg] (arm: --arm's; default -180:180 for every joint); repeatable");
  s->add_flag("--no-stroke-ends", o->no_stroke_ends, "Safety: do not check the stroke ends (the manual makes them the PC's job)");
  s->add_flag("--no-continuity-check", o->no_continuity_check, "Safety: do not check the continuity of commanded positions");
  s->add_flag("--no-following-error-check", o->no_following_error_check, "Safety: do not check the following error in modes 1, 2, 4 and 5");
  s->add_option("--duration", o->duration_s, "stop after this many seconds (default: until Ctrl-C or the app finishes)")->check(non_negative());
  s->add_flag("--until-controller-ends", o->until_controller_ends, "a finished app does not end the run: answer the rest of the robot program until the controller ends the exchange (504) or falls silent");
  s->add_option("--status-interval", o->status_interval_s, "seconds between status lines (0: none; default 1)")->check(non_negative());
  s->add_option("--stop-timeout", o->stop_timeout_s, "seconds to wait for mode 0 when stopping before drive off (default 5)")->check(non_negative());
  s->add_flag("--json", o->json, "print the final report as one JSON document on stdout (the other lines go to stderr)");
  s->add_option("--freeze-at", o->freeze_at_s, "active freezing (500) from this many seconds after start (also: SIGUSR1 freezes, SIGUSR2 releases)")->check(non_negative());
  s->add_option("--http", o->http, "serve the live page and /metrics on HOST:PORT (docs/dashboard.md; 127.0.0.1 keeps it on this machine, port 0: any)");
  s->add_option("--http-linger", o->http_linger_s, "with --http: keep serving the final state this many seconds after the run (a stop signal ends it; default 0)")->check(non_negative());
  s->add_option("--freeze-for", o->freeze_for_s, "release an active freezing this many seconds after the controller shows 500 (0: on SIGUSR2)")->check(non_negative());
  s->callback([o, &global] { global.exit_code = run_serve(*o); });
}

void add_init_info(CLI::App* c4g, GlobalOptions& global) {
  auto a = std::make_shared<InitInfoArgs>();
  auto* i = c4g->add_subcommand("init-info", "print an initialization packet (1200-byte file, or the first one in a pcap)");
  i->add_option("file", a->file, "the file")->required();
  i->add_flag("--from-pcap", a->from_pcap, "the file is a capture: use its first 1200-byte UDP payload");
  i->add_flag("--json", a->json, "print the packet as one JSON document");
  i->callback([a, &global] { global.exit_code = run_init_info(*a); });
}

}  // namespace

void add_c4g_commands(CLI::App& app, GlobalOptions& global) {
  auto* c4g = app.add_subcommand("c4g", "robot controller open interface: the PC-side real-time server");
  c4g->require_subcommand(1);
  add_serve(c4g, global);
  add_init_info(c4g, global);
}

}  // namespace axon::app
