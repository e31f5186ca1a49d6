// `axon c4g`: the PC side of the robot controller's open interface.
//   serve      runs a c4g::host::Server with one of the built-in applications (src/axon/c4g/apps)
//   init-info  prints an initialization packet from a 1200-byte file or from a capture
// The ready line `listening c4g HOST:PORT`, events and status lines go to stdout; logs to stderr.
// With --json, stdout carries one JSON document and nothing else: the lines go to stderr.
#include "axon/c4g/apps/app.hpp"
#include "axon/c4g/apps/contribute.hpp"
#include "axon/c4g/apps/correct.hpp"
#include "axon/c4g/apps/echo.hpp"
#include "axon/c4g/apps/handover.hpp"
#include "axon/c4g/apps/moni.hpp"
#include "axon/c4g/apps/monitor.hpp"
#include "axon/c4g/apps/pid.hpp"
#include "axon/c4g/apps/stream.hpp"
#include "axon/c4g/apps/trajectory.hpp"
#include "axon/c4g/host/server.hpp"
#include "axon/c4g/protocol/axis_map.hpp"
#include "axon/c4g/protocol/init_packet.hpp"
#include "checks.hpp"
#include "rotation_options.hpp"
#include "commands.hpp"
#include "axon/net/endpoint.hpp"
#include "run.hpp"
#include "stop_signals.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <pcap/pcap.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <memory>
#include <numbers>
#include <optional>
#include <thread>

namespace axon::app {
namespace {

namespace apps = c4g::apps;
namespace host = c4g::host;
namespace protocol = c4g::protocol;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

struct ServeOptions {
  std::string listen = fmt::format("{}:{}", host::kDefaultServerAddress, host::kDefaultPort);
  std::string controller;  // HOST[:PORT]; empty: learned from the first packet
  double period_ms = 0;    // timing figures until the initialization packet gives the period
  std::string app;
  // stream / correct / pid
  std::string file;
  std::string correct_file;
  std::vector<std::string> segments;
  int mode = 4;
  std::string units;
  bool relative = false;
  bool rearm = false;
  double start_tolerance_deg = 0.5;
  double max_motor_speed = 100.0;
  std::size_t arm = 1;
  std::vector<double> amplitude_deg;
  std::vector<double> frequency_hz;
  double open_time_s = 0;
  double ramp_s = 0.5;
  std::string feed;
  std::string feed_from;
  std::size_t feed_axes = 6;
  double feed_timeout_ms = 100;
  std::vector<double> max_correction_deg{apps::kDefaultMaxCorrectionDeg};
  std::vector<double> max_correction_step_deg{apps::kDefaultMaxCorrectionStepDeg};
  std::vector<double> kp, kv, ki;
  bool no_dynamic_model = false;
  bool reduce_in_pc = false;
  double switch_t1_ms = 50, switch_t2_ms = 100, switch_t3_ms = 50;
  // recording
  int moni = -1;
  std::string csv;
  // server
  std::string numbering = "same";
  std::string pcap;
  RotationArgs pcap_rotation, csv_rotation;
  int rt_priority = 0;
  std::vector<int> cpus;
  bool busy_poll = false;
  double max_step = 0;
  double duration_s = 0;
  double status_interval_s = 1.0;
  double stop_timeout_s = 5.0;
  bool json = false;
  // active freezing
  double freeze_at_s = 0;
  double freeze_for_s = 0;
};

// SIGUSR1 asks for active freezing, SIGUSR2 releases it (the main loop reads and clears this).
std::atomic<int> g_freeze_signal{0};
void on_freeze_signal(int sig) noexcept { g_freeze_signal.store(sig == SIGUSR1 ? 1 : 2); }

// Installs the SIGUSR1/SIGUSR2 handlers for the server's lifetime.
struct FreezeSignals {
  FreezeSignals() {
    g_freeze_signal.store(0);
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


Exception bad(std::string text) { return Exception(Error(CoreErrc::invalid_argument, std::move(text))); }

// Where the human-readable lines go: stdout, or stderr when stdout carries the JSON report.
std::FILE* text_out(const ServeOptions& o) { return o.json ? stderr : stdout; }

std::vector<double> deg_to_rad(const std::vector<double>& v) {
  std::vector<double> out;
  for (double d : v) out.push_back(d * std::numbers::pi / 180.0);
  return out;
}

apps::PidOptions pid_options(const ServeOptions& o) {
  apps::PidOptions p;
  p.arm = o.arm;
  p.amplitude_rad = deg_to_rad(o.amplitude_deg);
  p.frequency_hz = o.frequency_hz;
  p.open_time_s = o.open_time_s;
  p.ramp_s = o.ramp_s;
  p.dynamic_model_feedforward = !o.no_dynamic_model;
  p.reduce_in_pc = o.reduce_in_pc;
  p.limits.max_abs_rad = deg_to_rad(o.max_correction_deg);
  p.limits.max_step_rad = deg_to_rad(o.max_correction_step_deg);
  const std::size_t n = std::max({o.kp.size(), o.kv.size(), o.ki.size()});
  auto pick = [](const std::vector<double>& v, std::size_t i, double def) {
    return v.empty() ? def : (i < v.size() ? v[i] : v.back());
  };
  for (std::size_t i = 0; i < n; ++i) {
    const apps::PidGains d;
    p.gains.push_back({pick(o.kp, i, d.kp), pick(o.kv, i, d.kv), pick(o.ki, i, d.ki)});
  }
  return p;
}

std::unique_ptr<apps::App> make_app(const ServeOptions& o) {
  std::optional<apps::AngleUnit> unit;
  if (!o.units.empty()) {
    unit = apps::parse_angle_unit(o.units);
    if (!unit) throw bad("--units must be rad or deg");
  }
  if (o.app == "monitor") return std::make_unique<apps::MonitorApp>();
  if (o.app == "echo") return std::make_unique<apps::EchoApp>();
  auto stream_options = [&](const std::string& file) {
    apps::StreamOptions s;
    if (!file.empty() && !o.segments.empty()) throw bad("give --file or --segment, not both");
    if (!file.empty()) s.trajectory = std::make_shared<apps::Trajectory>(need(apps::Trajectory::load(file, unit)));
    for (const auto& spec : o.segments) {
      const auto eq = spec.find('=');
      int type = 0;
      try {
        type = eq == std::string::npos ? 0 : std::stoi(spec.substr(0, eq));
      } catch (const std::exception&) {
        type = 0;
      }
      if (eq == std::string::npos || type < 1 || type > 255 || eq + 1 >= spec.size())
        throw bad(fmt::format("--segment '{}': expected MOTION_TYPE=FILE.csv with a motion type 1..255", spec));
      s.segments.push_back({static_cast<std::uint8_t>(type),
                            std::make_shared<apps::Trajectory>(need(apps::Trajectory::load(spec.substr(eq + 1), unit)))});
    }
    s.mode = o.mode;
    s.arm = o.arm;
    s.relative = o.relative;
    s.start_tolerance_rad = o.start_tolerance_deg * std::numbers::pi / 180.0;
    s.max_motor_speed = o.max_motor_speed;
    s.stop_ramp_s = std::min(o.ramp_s, 0.5);
    return s;
  };
  auto correct_options = [&](const std::string& file) {
    apps::CorrectOptions c;
    c.arm = o.arm;
    if (!file.empty()) c.values = std::make_shared<apps::Trajectory>(need(apps::Trajectory::load(file, unit)));
    if (!o.feed.empty()) {
      apps::SensorFeedOptions f;
      f.listen = need(net::parse_endpoint(o.feed, 0));
      if (!o.feed_from.empty()) f.source = need(net::parse_endpoint(o.feed_from, 0));
      f.axes = o.feed_axes;
      f.degrees = o.units == "deg";
      c.feed = need(apps::SensorFeed::open(f));
      c.feed_timeout_s = o.feed_timeout_ms * 1e-3;
      std::fprintf(text_out(o), "correct: feed listening on %s:%u (%zu values per datagram, %s)\n", f.listen.host.c_str(),
                   static_cast<unsigned>(c.feed->port()), f.axes, f.degrees ? "deg" : "rad");
      std::fflush(text_out(o));
    }
    c.limits.max_abs_rad = deg_to_rad(o.max_correction_deg);
    c.limits.max_step_rad = deg_to_rad(o.max_correction_step_deg);
    c.amplitude_rad = deg_to_rad(o.amplitude_deg);
    c.frequency_hz = o.frequency_hz;
    c.open_time_s = o.open_time_s;
    c.ramp_s = o.ramp_s;
    c.max_motor_speed = o.max_motor_speed;
    return c;
  };
  if (o.app == "stream") {
    if (o.file.empty() && o.segments.empty()) throw bad("--app stream needs --file TRAJECTORY.csv or --segment N=FILE.csv");
    if (o.mode != 4 && o.mode != 5) throw bad("--app stream: --mode must be 4 or 5");
    auto s = stream_options(o.file);
    s.rearm = o.rearm;
    return std::make_unique<apps::StreamApp>(std::move(s));
  }
  if (o.app == "correct") {
    auto c = correct_options(o.file);
    c.rearm = o.rearm;
    return std::make_unique<apps::CorrectApp>(std::move(c));
  }
  if (o.app == "handover") {
    apps::HandoverOptions h;
    h.arm = o.arm;
    h.hold_s = o.open_time_s > 0 ? o.open_time_s : 0.5;
    if (!o.file.empty() || !o.segments.empty()) h.stream = stream_options(o.file);
    if (!o.correct_file.empty() || !o.feed.empty() || !o.amplitude_deg.empty()) {
      h.correct = correct_options(o.correct_file);
      if (h.correct->open_time_s <= 0 && !h.correct->values) h.correct->open_time_s = h.hold_s;
    }
    return std::make_unique<apps::HandoverApp>(std::move(h));
  }
  if (o.app == "pid") return std::make_unique<apps::PidApp>(pid_options(o));
  if (o.app == "contribute") {
    if (o.mode != 8 && o.mode != 9) throw bad("--app contribute: --mode must be 8 (velocity) or 9 (current)");
    apps::ContributeOptions c;
    c.arm = o.arm;
    c.mode = o.mode;
    c.amplitude = o.amplitude_deg;  // motor side for this app: turns/s (8) or A (9)
    c.max_motor_speed = o.max_motor_speed;
    c.frequency_hz = o.frequency_hz;
    c.open_time_s = o.open_time_s;
    c.ramp_s = o.ramp_s;
    return std::make_unique<apps::ContributeApp>(std::move(c));
  }
  throw bad(fmt::format("unknown --app '{}' (monitor, echo, stream, correct, pid, handover, contribute)", o.app));
}

json timing_json(const host::Server& server) {
  const auto& t = server.cycle().timing();
  const auto& h = t.cycle_times();
  auto s = [](std::int64_t ns) { return static_cast<double>(ns) * 1e-9; };
  // Figures relative to the controller's period are null while it is unknown.
  auto relative = [&](const json& v) { return t.nominal_known() ? v : json(nullptr); };
  return json{{"cycles", t.cycles()},
              {"nominal_period_s", relative(s(t.nominal_period_ns()))},
              {"worst_cycle_time_s", s(t.worst_cycle_time_ns())},
              {"inter_packet_period_s", {s(t.min_inter_step_ns()), s(t.max_inter_step_ns())}},
              {"inter_step_p50_s", s(t.inter_step_times().percentile(50))},
              {"jitter_s", relative({s(t.min_jitter_ns()), s(t.max_jitter_ns())})},
              {"jitter_percent", relative({t.min_percent_jitter(), t.max_percent_jitter()})},
              {"cycle_time_p50_s", s(h.percentile(50))},
              {"cycle_time_p99_s", s(h.percentile(99))},
              {"cycle_time_p999_s", s(h.percentile(99.9))},
              {"cycle_time_max_s", s(h.max())},
              {"missed_deadlines", t.missed_deadlines()},
              {"deadline_s", s(t.config().deadline_ns)}};
}

json session_json(const host::Server& server) {
  const auto& c = server.counters();
  const auto peer = server.peer();
  const auto last = host::SessionPeer::unpack(c.last_foreign.load());
  return json{{"controller", peer ? json(peer->to_string()) : json(nullptr)},
              {"sessions", c.sessions.load()},
              {"foreign", c.foreign.load()},
              {"last_foreign_source", last ? json(last->to_string()) : json(nullptr)}};
}

host::ServerOptions server_options(const ServeOptions& o) {
  host::ServerOptions so;
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
  return so;
}

// The final report: one JSON document, or text lines.
void print_report(const ServeOptions& o, const host::Server& server, const apps::App& app, const std::string& why,
                  const apps::MoniCsvWriter* csv) {
  if (o.json) {
    const auto& c = server.counters();
    json j{{"app", std::string(app.name())},
           {"reason", why},
           {"app_cycles", app.cycles()},
           {"finished", app.finished()},
           {"error", app.error()},
           {"app_summary", app.summary()},
           {"session", session_json(server)},
           {"packets", c.packets.load()},
           {"init_packets", c.init_packets.load()},
           {"cyclic_packets", c.cyclic_packets.load()},
           {"protocol_errors", c.protocol_errors.load()},
           {"safe_replies", c.safe_replies.load()},
           {"refused_mode_changes", c.refused_mode_changes.load()},
           {"controller_late", c.controller_late.load()},
           {"freezes", c.freezes.load()},
           {"frozen_cycles", c.frozen_cycles.load()},
           {"safety_fault", std::string(host::to_string(server.safety().reason()))},
           {"currents_clamped", server.safety().counters().currents_clamped.load()},
           {"timing", timing_json(server)}};
    if (csv) {
      j["csv_rows"] = csv->rows();
      j["csv_rotations"] = csv->rotations();
      j["csv_write_errors"] = csv->write_errors();
    }
    if (server.recorder()) {
      j["pcap_written"] = server.recorder()->written();
      j["pcap_rotations"] = server.recorder()->rotations();
      j["pcap_write_failures"] = server.recorder()->write_failures();
    }
    std::printf("%s\n", j.dump(2).c_str());
  } else {
    std::printf("stopped: %s\n%s%s", why.c_str(), server.summary().c_str(), app.summary().c_str());
    if (csv)
      std::printf("CSV %s: %llu rows (moni type %d), %llu rotations, %llu write errors\n", csv->path().c_str(),
                  static_cast<unsigned long long>(csv->rows()), o.moni < 0 ? 0 : o.moni,
                  static_cast<unsigned long long>(csv->rotations()), static_cast<unsigned long long>(csv->write_errors()));
    if (app.has_error()) std::printf("error: %s\n", app.error().c_str());
  }
  std::fflush(stdout);
}

// Active freezing driven from the command line: SIGUSR1 / SIGUSR2, or --freeze-at / --freeze-for;
// state changes are printed.
class FreezeControl {
 public:
  FreezeControl(const ServeOptions& o, host::Server& server, Clock::time_point start)
      : o_(o), server_(server), start_(start), at_done_(o.freeze_at_s <= 0) {}
  void poll(Clock::time_point now) {
    std::FILE* out = text_out(o_);
    const int sig = g_freeze_signal.exchange(0);
    if (sig == 1) { std::fprintf(out, "freeze: requested (SIGUSR1)\n"); server_.request_freeze(); }
    if (sig == 2) { std::fprintf(out, "freeze: released (SIGUSR2)\n"); server_.release_freeze(); }
    if (!at_done_ && now - start_ >= std::chrono::duration<double>(o_.freeze_at_s)) {
      at_done_ = true;
      std::fprintf(out, "freeze: requested (--freeze-at %.3f s)\n", o_.freeze_at_s);
      server_.request_freeze();
    }
    const auto st = server_.freeze_state();
    if (st != shown_) {
      std::fprintf(out, "freeze: %s\n", std::string(host::to_string(st)).c_str());
      shown_ = st;
      frozen_since_.reset();
      if (st == host::FreezeState::frozen) frozen_since_ = now;
    }
    if (frozen_since_ && o_.freeze_for_s > 0 && server_.freeze_requested() &&
        now - *frozen_since_ >= std::chrono::duration<double>(o_.freeze_for_s)) {
      std::fprintf(out, "freeze: released (--freeze-for %.3f s)\n", o_.freeze_for_s);
      server_.release_freeze();
    }
    std::fflush(out);
  }

 private:
  const ServeOptions& o_;
  host::Server& server_;
  Clock::time_point start_;
  bool at_done_;
  host::FreezeState shown_ = host::FreezeState::off;
  std::optional<Clock::time_point> frozen_since_;
};

Clock::duration seconds(double s) { return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s)); }

// Waits until the server has answered one more packet (the controller is still sending) or
// `limit_s` passed: a reply latched now (drive off) is then on the wire.
void wait_for_answer(const host::Server& server, double limit_s) {
  const auto before = server.counters().packets.load();
  const auto until = Clock::now() + seconds(limit_s);
  while (server.counters().packets.load() == before && Clock::now() < until &&
         server.state() == host::ServerState::running)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
}

int run_serve(const ServeOptions& o) {
  auto app = make_app(o);
  const host::ServerOptions so = server_options(o);
  std::FILE* out = text_out(o);

  std::unique_ptr<apps::MoniCsvWriter> csv;
  if (!o.csv.empty()) {
    csv = need(apps::MoniCsvWriter::open(o.csv, o.moni < 0 ? 0 : o.moni, o.csv_rotation.limits()));
    app->record_samples(8192);
  } else if (o.moni >= 0) {
    throw bad("--moni needs --csv FILE");
  }

  StopSignals signals;
  FreezeSignals freeze_signals;

  auto server = need(host::Server::start(*app, so));
  std::fprintf(out, "listening c4g %s\n", server->local_address().to_string().c_str());
  std::fflush(out);
  for (const auto& step : server->realtime_report().steps)
    if (!step.granted) spdlog::warn("c4g serve: {} refused: {}", step.name, step.reason);

  const auto start = Clock::now();
  auto next_status = start + seconds(o.status_interval_s);
  std::optional<net::SocketAddress> shown_peer;
  auto pump = [&] {
    if (const auto peer = server->peer(); peer && peer != shown_peer)
      std::fprintf(out, "session: controller %s\n", peer->to_string().c_str());
    shown_peer = server->peer();
    for (const auto& e : app->drain_events())
      std::fprintf(out, "event cycle %llu: %s\n", static_cast<unsigned long long>(e.cycle), app->describe(e).c_str());
    if (csv) app->drain_samples([&](const apps::Sample& s) { csv->write(s.cycle, s.wall_ns, s.request, s.reply); });
    std::fflush(out);
  };
  auto status_line = [&] {
    const auto& t = server->cycle().timing();
    std::fprintf(out, "status %s | %s | cycle time last %.1f us worst %.1f us, missed %llu | foreign %llu\n",
                 app->status().c_str(), std::string(host::to_string(server->state())).c_str(),
                 static_cast<double>(t.last_cycle_time_ns()) * 1e-3, static_cast<double>(t.worst_cycle_time_ns()) * 1e-3,
                 static_cast<unsigned long long>(t.missed_deadlines()),
                 static_cast<unsigned long long>(server->counters().foreign.load()));
  };
  FreezeControl freeze(o, *server, start);

  std::string why = "stopped";
  while (true) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    pump();
    const auto now = Clock::now();
    freeze.poll(now);
    if (signals.count() > 0) { why = "signal"; break; }
    if (o.duration_s > 0 && now - start >= seconds(o.duration_s)) { why = "duration reached"; break; }
    if (app->finished()) { why = "application finished"; break; }
    if (app->has_error()) {
      why = "application error";
      if (app->drive_off_on_error()) server->safety().trip(host::FaultReason::user_request);
      break;
    }
    if (app->controller_exited()) { why = "controller ended the exchange (504)"; break; }
    if (o.status_interval_s > 0 && now >= next_status) {
      status_line();
      next_status = now + seconds(o.status_interval_s);
    }
  }

  // Leave cleanly: the app ends its open modes (replies stay safe meanwhile); if the controller does
  // not come back to mode 0 in time, ask for drive off and give it a moment to obey.
  spdlog::info("c4g serve: stopping ({})", why);
  app->request_stop();
  if (server->freeze_requested()) {
    std::fprintf(out, "freeze: released (stopping)\n");
    server->release_freeze();
  }
  auto settled = [&] {
    return app->quiescent() || server->state() == host::ServerState::silent ||
           server->state() == host::ServerState::waiting || app->controller_exited();
  };
  auto wait_until = [&](double s) {
    const auto until = Clock::now() + seconds(s);
    while (!settled() && Clock::now() < until && signals.count() < 2) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      pump();
      freeze.poll(Clock::now());
    }
    return settled();
  };
  if (!wait_until(o.stop_timeout_s)) {
    if (signals.count() >= 2) spdlog::warn("c4g serve: a second signal: asking for drive off now");
    else spdlog::warn("c4g serve: the controller is still in an open mode after {} s: asking for drive off", o.stop_timeout_s);
    server->safety().trip(host::FaultReason::user_request);
    if (signals.count() < 2) wait_until(1.0);
    wait_for_answer(*server, 0.1);  // the drive off must go out before the socket closes
  }
  server->stop();
  pump();
  if (csv) csv->flush();

  const bool faulted = server->safety().faulted() && server->safety().reason() != host::FaultReason::user_request;
  print_report(o, *server, *app, why, csv.get());
  if (faulted) return exit_code_value::safety_stop;
  return app->has_error() ? exit_code_value::failed : exit_code_value::ok;
}

// The first 1200-byte UDP payload of a capture (Ethernet / IPv4 / UDP, as PcapRecorder and
// tcpdump on an Ethernet interface write them).
std::vector<std::byte> init_from_pcap(const std::string& path) {
  char err[PCAP_ERRBUF_SIZE] = {};
  pcap_t* p = pcap_open_offline(path.c_str(), err);
  if (!p) throw bad(fmt::format("cannot read capture {}: {}", path, err));
  std::vector<std::byte> out;
  const int link = pcap_datalink(p);
  pcap_pkthdr* hdr = nullptr;
  const u_char* data = nullptr;
  while (out.empty() && pcap_next_ex(p, &hdr, &data) == 1) {
    std::size_t off = link == DLT_EN10MB ? 14 : (link == DLT_RAW ? 0 : SIZE_MAX);
    if (off == SIZE_MAX || hdr->caplen < off + 28) continue;
    if (link == DLT_EN10MB && (data[12] != 0x08 || data[13] != 0x00)) continue;
    const std::size_t ihl = (data[off] & 0x0F) * 4u;
    if ((data[off] >> 4) != 4 || data[off + 9] != 17) continue;
    const std::size_t udp = off + ihl;
    const std::size_t len = (static_cast<std::size_t>(data[udp + 4]) << 8 | data[udp + 5]);
    if (len != 8 + protocol::kInitPacketSize || hdr->caplen < udp + len) continue;
    const auto* payload = reinterpret_cast<const std::byte*>(data + udp + 8);
    out.assign(payload, payload + protocol::kInitPacketSize);
  }
  pcap_close(p);
  if (out.empty()) throw bad(fmt::format("{}: no 1200-byte initialization packet in the capture", path));
  return out;
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

int run_init_info(const std::string& file, bool from_pcap, bool as_json) {
  std::vector<std::byte> bytes;
  if (from_pcap) {
    bytes = init_from_pcap(file);
  } else {
    std::ifstream in(file, std::ios::binary);
    if (!in) throw bad(fmt::format("cannot open {}", file));
    std::vector<char> raw((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (char c : raw) bytes.push_back(static_cast<std::byte>(c));
  }
  const auto init = need(protocol::decode_init(bytes));
  auto map = protocol::AxisMap::from_init(init);
  if (as_json) {
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

}  // namespace

void add_c4g_commands(CLI::App& app, GlobalOptions&) {
  auto* c4g = app.add_subcommand("c4g", "robot controller open interface: the PC-side real-time server");
  c4g->require_subcommand(1);

  static ServeOptions so;
  auto* s = c4g->add_subcommand("serve", "serve the controller's packets with a built-in application (docs/c4g-cli.md)");
  s->add_option("--listen", so.listen, "HOST[:PORT] to serve on (default 127.0.0.1:11000; the manual's: 10.2.12.149:1000; a host alone: port 1000; port 0: any free)");
  s->add_option("--controller", so.controller, "HOST[:PORT] of the controller: only it may start a session (default: the first well-formed packet's source; a host alone: any port)");
  s->add_option("--period-ms", so.period_ms, "the controller's period for the timing figures until its initialization packet gives it [ms]")->check(positive());
  s->add_option("--app", so.app, "monitor (mode 0), echo (0'), stream (4/5), correct (7), pid (1/2), handover (every open phase: 4/5 and 7), contribute (8/9)")->required();
  s->add_option("--file", so.file, "stream: trajectory CSV; correct: correction values CSV");
  s->add_option("--segment", so.segments, "stream/handover: MOTION_TYPE=FILE.csv, the trajectory for that motion type (CMD byte of the arm); repeatable");
  s->add_option("--correct-file", so.correct_file, "handover: correction values CSV for mode 7");
  s->add_flag("--rearm", so.rearm, "stream/correct: serve the mode again each time the program re-enters it (until 504 or Ctrl-C)");
  s->add_option("--mode", so.mode, "stream: 4 (absolute targets) or 5 (increments); contribute: 8 (velocity) or 9 (current)");
  s->add_option("--units", so.units, "angles in the CSV: rad or deg (else the file's '# units:' line, else rad)");
  s->add_flag("--relative", so.relative, "stream: the trajectory is offsets from the robot's position at the start");
  s->add_option("--start-tolerance", so.start_tolerance_deg, "stream: start-point tolerance [deg] (default 0.5)")->check(non_negative());
  s->add_option("--max-motor-speed", so.max_motor_speed, "continuity limit [motor turns/s] (default 100)")->check(positive());
  s->add_option("--arm", so.arm, "the arm the application drives (default 1)")->check(CLI::Range(1, 4));
  s->add_option("--amplitude", so.amplitude_deg, "correct/pid: sine amplitude per axis [deg, link side]; contribute: [motor turns/s] (mode 8) or [A] (mode 9)")->delimiter(',');
  s->add_option("--frequency", so.frequency_hz, "correct/pid: sine frequency per axis [Hz] (default 0.5)")->delimiter(',')->check(non_negative());
  s->add_option("--open-time", so.open_time_s, "correct/pid: leave the open mode after this long [s] (0: until stopped); handover: hold / zero-correction / sine time per phase (default 0.5)")->check(non_negative());
  s->add_option("--ramp", so.ramp_s, "fade in/out time of corrections and sines [s] (default 0.5)")->check(non_negative());
  s->add_option("--feed", so.feed, "correct: live correction values over UDP on HOST:PORT (one datagram of numbers per measurement)");
  s->add_option("--feed-from", so.feed_from, "correct: read the feed only from this sensor HOST[:PORT] (a host alone: any port); others are counted and ignored");
  s->add_option("--feed-axes", so.feed_axes, "correct: values per feed datagram (default 6)")->check(CLI::Range(1, 10));
  s->add_option("--feed-timeout-ms", so.feed_timeout_ms, "correct: feed values older than this count as none (default 100)")->check(positive());
  s->add_option("--max-correction", so.max_correction_deg, "correct (and the pid sine): largest correction per axis [deg, link side] (default 5; one value: every axis); beyond it a feed reading is refused, a sine or file is refused at start")->delimiter(',')->check(positive());
  s->add_option("--max-correction-step", so.max_correction_step_deg, "correct (and the pid sine): largest change of the correction per cycle and axis [deg, link side] (default 0.1); a feed slews at it, a sine or file that needs more is refused")->delimiter(',')->check(positive());
  s->add_option("--kp", so.kp, "pid: position gain per axis [1/s]")->delimiter(',');
  s->add_option("--kv", so.kv, "pid: velocity gain per axis [A/(turn/s)]")->delimiter(',');
  s->add_option("--ki", so.ki, "pid: velocity integral rate per axis [1/s]")->delimiter(',');
  s->add_flag("--no-dynamic-model", so.no_dynamic_model, "pid: do not feed the controller's dynamic-model current forward");
  s->add_flag("--reduce-in-pc", so.reduce_in_pc, "pid: scale D5 by the soft-switching factor here (for a controller that does not)");
  s->add_option("--switch-t1-ms", so.switch_t1_ms, "the controller's soft switching T1 [ms] (default 50)")->check(CLI::Range(0.0, 60000.0));
  s->add_option("--switch-t2-ms", so.switch_t2_ms, "the controller's soft switching T2 [ms] (default 100)")->check(CLI::Range(0.0, 60000.0));
  s->add_option("--switch-t3-ms", so.switch_t3_ms, "the controller's soft switching T3 [ms] (default 50)")->check(CLI::Range(0.0, 60000.0));
  s->add_option("--moni", so.moni, "with --csv: monitoring view 19..24 of the manual (default 0: every field)");
  s->add_option("--csv", so.csv, "write every cycle to this CSV file");
  add_rotation_options(s, so.csv_rotation, "csv", "--csv");
  s->add_option("--numbering", so.numbering, "reply number: same (the manual) or next (NUM + 1)");
  s->add_option("--pcap", so.pcap, "record every datagram into this pcap file");
  add_rotation_options(s, so.pcap_rotation, "pcap", "--pcap");
  s->add_option("--rt-priority", so.rt_priority, "SCHED_FIFO priority of the cycle thread (and mlockall)")->check(CLI::Range(0, 99));
  s->add_option("--cpu", so.cpus, "pin the cycle thread to this CPU (repeatable)");
  s->add_flag("--busy-poll", so.busy_poll, "spin on the socket instead of sleeping (a dedicated core)");
  s->add_option("--max-step", so.max_step, "Safety: max change of a commanded position per cycle [motor turns] (0: off)")->check(non_negative());
  s->add_option("--duration", so.duration_s, "stop after this many seconds (default: until Ctrl-C or the app finishes)")->check(non_negative());
  s->add_option("--status-interval", so.status_interval_s, "seconds between status lines (0: none; default 1)")->check(non_negative());
  s->add_option("--stop-timeout", so.stop_timeout_s, "seconds to wait for mode 0 when stopping before drive off (default 5)")->check(non_negative());
  s->add_flag("--json", so.json, "print the final report as one JSON document on stdout (the other lines go to stderr)");
  s->add_option("--freeze-at", so.freeze_at_s, "active freezing (500) from this many seconds after start (also: SIGUSR1 freezes, SIGUSR2 releases)")->check(non_negative());
  s->add_option("--freeze-for", so.freeze_for_s, "release an active freezing this many seconds after the controller shows 500 (0: on SIGUSR2)")->check(non_negative());
  s->callback([] { exit_code() = run_serve(so); });

  static std::string init_file;
  static bool from_pcap = false;
  static bool init_json_out = false;
  auto* i = c4g->add_subcommand("init-info", "print an initialization packet (1200-byte file, or the first one in a pcap)");
  i->add_option("file", init_file, "the file")->required();
  i->add_flag("--from-pcap", from_pcap, "the file is a capture: use its first 1200-byte UDP payload");
  i->add_flag("--json", init_json_out, "print the packet as one JSON document");
  i->callback([] { exit_code() = run_init_info(init_file, from_pcap, init_json_out); });
}

}  // namespace axon::app
