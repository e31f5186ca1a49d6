// `axon blmc ...`: one motor driver board (two motors) on one CAN bus, through the host driver
// (docs/blmc-host.md). This file parses options and prints; the work is the library's: motion
// commands are blmc::host::with_motors_enabled around run_control / run_pd / run_homing
// (control_run.hpp) with the safety limits given by flags, so on every way out (the end, a safety
// stop, a failed start, an exception, a closed stdout, Ctrl-C/SIGTERM/SIGHUP) the board gets zero
// current and is disabled, and the disable's result decides the exit code. Tables and results go
// to stdout (JSON Lines with --json), logs to stderr. The options live in one Blmc object per
// invocation, shared by the subcommands' callbacks. --http serves the board's live page and
// /metrics (docs/dashboard.md): a web::BlmcView fed on the bus thread from the loop's records.
#include "axon/blmc/host/board.hpp"
#include "axon/blmc/host/control_run.hpp"
#include "axon/blmc/host/error.hpp"
#include "axon/blmc/host/motor_session.hpp"
#include "axon/blmc/host/observe.hpp"
#include "axon/blmc/host/session_log.hpp"
#include "axon/blmc/protocol/command.hpp"
#include "axon/blmc/protocol/frames.hpp"
#include "axon/can/bus_spec.hpp"
#include "axon/can/candump_log.hpp"
#include "axon/can/open.hpp"
#include "axon/net/endpoint.hpp"
#include "axon/web/blmc_view.hpp"
#include "axon/web/server.hpp"
#include "checks.hpp"
#include "commands.hpp"
#include "run.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>
#include <utility>

namespace axon::app {
namespace {

using namespace std::chrono_literals;
namespace bh = blmc::host;
namespace bp = blmc::protocol;
using json = nlohmann::json;

// `onboard`: what to set on the board's own controller; each pair is (motor 1, motor 2), empty when
// not given.
struct Onboard {
  std::vector<double> kp, kd, position, velocity, p_limit, d_limit;
  std::vector<int> springs;
  int rollover_error = -1;  // -1: leave it
};

struct BlmcOptions {
  std::string bus;
  std::string socketcand;
  std::string socketcan;
  std::string log;  // candump log of every frame of the session
  std::string csv;  // motion commands: one line per control cycle
  std::string motors = "both";
  double max_current = 2.0;
  double max_velocity = 2.0;  // krpm
  double stale_ms = 20;
  std::uint32_t recv_timeout_ms = 50;
  double ready_timeout_s = 10;
  double rate_hz = 1000;
  double duration_s = 0;  // 0: until Ctrl-C (monitor/status), per command otherwise
  double refresh_hz = 10;
  bool realtime = true;
  std::vector<int> cpus;
  bool pace_measurements = false;
  bool json = false;
  std::string http;          // HOST:PORT of the live page (empty: none)
  double http_linger_s = 0;  // keep serving the final state this long after the command
  // The subcommands' own arguments.
  int current_motor = 1;
  double current_amps = 0;
  double current_duration_s = 1;
  bh::PdGains pd_gains;
  double pd_amplitude = 0, pd_frequency = 0.5, pd_duration_s = 5;
  bh::HomingOptions home;
  double home_timeout_s = 20;
  std::string raw_text;
  std::string record_file;
  Onboard onboard;
};

std::string bus_text(const BlmcOptions& o) {
  int given = !o.bus.empty() + !o.socketcand.empty() + !o.socketcan.empty();
  if (given > 1) throw Exception(usage("give one of --bus, --socketcand, --socketcan"));
  if (!o.socketcand.empty()) return "socketcand://" + o.socketcand;
  if (!o.socketcan.empty()) return "socketcan:" + o.socketcan;
  if (!o.bus.empty()) return o.bus;
  return "socketcan:can0";
}

std::array<bool, 2> motor_set(const std::string& m) {
  if (m == "1") return {true, false};
  if (m == "2") return {false, true};
  if (m == "both" || m == "1,2") return {true, true};
  throw Exception(usage(fmt::format("--motors {}: use 1, 2 or both", m)));
}

core::Duration seconds(double s) { return std::chrono::duration_cast<core::Duration>(std::chrono::duration<double>(s)); }

// The loop and safety settings the flags give (the motion commands' duration set by each).
bh::ControlOptions control_options(const BlmcOptions& o, double duration_s) {
  bh::ControlOptions c;
  c.limits.motors = motor_set(o.motors);
  c.limits.max_current_a = o.max_current;
  c.limits.max_velocity_krpm = o.max_velocity;
  c.limits.stale_after = std::chrono::microseconds(static_cast<std::int64_t>(o.stale_ms * 1000));
  c.loop.period = seconds(1.0 / o.rate_hz);
  c.loop.realtime = o.realtime;
  c.loop.cpus = o.cpus;
  c.loop.pacing = o.pace_measurements ? bh::Pacing::measurements : bh::Pacing::clock;
  c.duration = seconds(duration_s);
  c.refresh = seconds(1.0 / o.refresh_hz);
  return c;
}

// ---- output -------------------------------------------------------------------------------------

// stdout, with the failure noticed: SIGPIPE is ignored, so a reader that went away (`| head`)
// shows as EPIPE here and the command stops (its devices made safe) instead of running blind.
class Output {
 public:
  explicit Output(const bool& json) : json_(&json) {}
  [[nodiscard]] bool is_json() const noexcept { return *json_; }
  [[nodiscard]] bool ok() const noexcept { return ok_; }

  bool emit(const std::string& line) {
    if (!ok_) return false;
    if (std::fputs(line.c_str(), stdout) < 0 || std::fputc('\n', stdout) == EOF || std::fflush(stdout) != 0) {
      ok_ = false;
      spdlog::error("blmc: cannot write to stdout ({}): stopping", std::strerror(errno));
    }
    return ok_;
  }
  bool emit(const json& j) { return emit(j.dump()); }

  bool status(const bp::Status& s) {
    if (!is_json()) return emit(fmt::format("{}  (byte 0x{:02X})", s.to_string(), s.to_byte()));
    auto j = status_json(s);
    j["type"] = "status";
    return emit(j);
  }

  bool table_header() {
    if (is_json()) return true;
    return emit(fmt::format("{:>8} | {:>8} {:>8} | {:>9} {:>9} | {:>8} {:>8} | {:>6} {:>6} | {}", "t[s]", "I1[A]", "I2[A]",
                            "pos1[rev]", "pos2[rev]", "v1[krpm]", "v2[krpm]", "adcA", "adcB", "status"));
  }

  bool row(double t, const bh::Measurements& m) {
    const auto& st = m.status;
    if (is_json()) {
      return emit(json{{"type", "sample"},
                       {"t", t},
                       {"current", pair_json(m.current.value)},
                       {"position", pair_json(m.position.value)},
                       {"velocity", pair_json(m.velocity.value)},
                       {"adc", pair_json(m.adc.value)},
                       {"status", st.received() ? status_json(st.value) : json(nullptr)}});
    }
    return emit(fmt::format("{:8.3f} | {:8.3f} {:8.3f} | {:9.4f} {:9.4f} | {:8.4f} {:8.4f} | {:6.3f} {:6.3f} | {}", t,
                            m.current.value.motor1, m.current.value.motor2, m.position.value.motor1,
                            m.position.value.motor2, m.velocity.value.motor1, m.velocity.value.motor2, m.adc.value.motor1,
                            m.adc.value.motor2, st.received() ? st.value.to_string() : "(no status yet)"));
  }

  static json pair_json(const bh::MotorPair& p) { return json::array({p.motor1, p.motor2}); }
  static json status_json(const bp::Status& s) {
    return json{{"system_enabled", s.system_enabled}, {"motor1_enabled", s.motor1_enabled},
                {"motor1_ready", s.motor1_ready}, {"motor2_enabled", s.motor2_enabled}, {"motor2_ready", s.motor2_ready},
                {"error", std::string(bp::name(s.error))}, {"byte", s.to_byte()}};
  }

 private:
  const bool* json_;
  bool ok_ = true;
};

// One `axon blmc` invocation: its options (filled by the parser), its stdout, and whether the
// motors may be on: true from the moment a command enables them until their disable was sent.
// Still true after run_command only when the command was abandoned (a second signal stops the
// event loop at once): then the board is disabled over a new connection.
struct Blmc {
  BlmcOptions o;
  Output out{o.json};
  bool motors_may_be_on = false;
  const char* command = "";  // the subcommand running
  bool motion = false;       // it runs the control loop
};

// ---- --http: the live page ----------------------------------------------------------------------

// The board's page on a web server of its own thread; the view is fed and published on the bus
// thread (the loop's records drained there, or the monitor's samples), never on the real-time one.
struct WebPage {
  std::unique_ptr<web::Server> server;
  std::shared_ptr<web::Source> source;
  std::unique_ptr<web::BlmcView> view;
  void publish(bool with_metrics = false) { view->publish(*source, with_metrics ? 1 : 10); }
};

std::unique_ptr<WebPage> open_web_page(const Blmc& cli, const std::string& board) {
  const auto ep = need(net::parse_endpoint(cli.o.http));
  web::ServerOptions so;
  so.address = ep.host;
  so.port = ep.port;
  auto page = std::make_unique<WebPage>();
  web::BlmcViewOptions vo;
  vo.boards = {{board, cli.motion ? std::optional(control_options(cli.o, 0).limits) : std::nullopt}};
  vo.nominal_period = control_options(cli.o, 0).loop.period;
  vo.command = cli.command;
  page->view = std::make_unique<web::BlmcView>(std::move(vo));
  page->server = std::make_unique<web::Server>(so);
  page->source = std::make_shared<web::Source>("blmc", fmt::format("blmc: board on {} ({})", board, cli.command), "blmc");
  page->source->set_info(page->view->info_json());
  page->publish(true);
  page->server->add(page->source);
  return page;
}

// ---- session ------------------------------------------------------------------------------------

// One session: bus, board, optional candump log, stop requests.
struct Session {
  Blmc* cli = nullptr;
  std::unique_ptr<can::Bus> bus;
  std::unique_ptr<bh::Board> board;
  std::optional<can::CandumpWriter> log;
  std::string iface;
  std::unique_ptr<WebPage> web;  // with --http
  bool stop = false;
  bool signal_ends_normally = false;  // monitor/record until Ctrl-C: a signal is their end
  [[nodiscard]] const BlmcOptions& o() const { return cli->o; }
  [[nodiscard]] Output& out() const { return cli->out; }
};

asio::awaitable<std::unique_ptr<Session>> open_session(Blmc& cli, asio::io_context& io,
                                                       const SignalHook& on_signal,
                                                       bool signal_ends_normally) {
  const auto& o = cli.o;
  auto s = std::make_unique<Session>();
  s->cli = &cli;
  s->signal_ends_normally = signal_ends_normally;
  const auto spec = need(can::parse_bus_spec(bus_text(o)));
  const asio::any_io_executor ex = io.get_executor();
  auto r = co_await can::open_bus(ex, spec);
  s->bus = need(std::move(r));
  s->iface = spec.short_name();
  bh::BoardOptions bo;
  bo.name = spec.short_name();
  bo.motors = motor_set(o.motors);
  bo.recv_timeout_ms = o.recv_timeout_ms;
  bo.ready_timeout = seconds(o.ready_timeout_s);
  s->board = std::make_unique<bh::Board>(*s->bus, bo);
  if (!o.log.empty()) {
    s->log.emplace(need(can::CandumpWriter::create(o.log, can::CandumpWriter::Flush::on_request)));
    s->board->set_tap(bh::candump_tap(*s->log, s->iface));
  }
  Session* raw = s.get();
  // A stop request ends the waits on the board at once (an enable waiting for the alignment).
  on_signal([raw, on_signal] {
    if (raw->signal_ends_normally) on_signal.signal_ends_normally();
    raw->stop = true;
    raw->board->interrupt();
  });
  spdlog::info("blmc: board on {}", spec.to_string());
  if (!o.http.empty()) {
    s->web = open_web_page(cli, s->iface);
    const auto where = fmt::format("{}:{}", s->web->server->address(), s->web->server->port());
    if (s->out().is_json()) s->out().emit(json{{"type", "listening"}, {"http", where}});
    else s->out().emit("listening http " + where);
  }
  co_return s;
}

asio::awaitable<void> close_session(Session& s) {
  if (s.log) (void)s.log->flush();
  auto f = co_await s.bus->flush(1s);
  (void)f;
  s.board.reset();
  s.bus->close();
}

// A command abandoned with the motors on (Blmc::motors_may_be_on). Returns false when that failed too.
bool disable_over_new_connection(const BlmcOptions& o) {
  spdlog::warn("blmc: stopped before the motors were disabled: disabling the board over a new connection");
  const auto spec = can::parse_bus_spec(bus_text(o));
  const Result<void> result = spec ? bh::disable_over_new_connection(spec.value()) : Result<void>(spec.error());
  if (result) spdlog::info("blmc: board disabled, currents zero");
  else spdlog::error("blmc: could not disable the board: {}", result.error().message());
  return static_cast<bool>(result);
}

// --http-linger: the page goes on showing the board's status (disabled, its error) after the
// command, until the time is up or a stop signal, which is then the normal end.
asio::awaitable<void> linger(Session& s, const SignalHook& on_signal) {
  Session* raw = &s;
  on_signal([raw, on_signal] {
    on_signal.signal_ends_normally();
    raw->board->interrupt();
  });
  co_await bh::monitor(*s.board, 100ms, seconds(s.o().http_linger_s), [raw](double, const bh::Measurements& m) {
    if (m.status_byte.received()) raw->web->view->set_status(0, m.status_byte.value);
    raw->web->publish();
    return true;
  });
}

using Body = std::function<asio::awaitable<int>(Session&)>;

int run_blmc(Blmc& cli, bool signal_ends_normally, const Body& body) {
  int rc = 0;
  try {
    rc = run_command([&](asio::io_context& io, auto set_on_signal) -> asio::awaitable<int> {
      auto s = co_await open_session(cli, io, set_on_signal, signal_ends_normally);
      int code = 0;
      std::exception_ptr failure;
      try {
        code = co_await body(*s);
        if (s->web && cli.o.http_linger_s > 0) co_await linger(*s, set_on_signal);
      } catch (...) {
        failure = std::current_exception();
      }
      co_await close_session(*s);
      if (failure) std::rethrow_exception(failure);
      co_return code;
    });
  } catch (...) {
    if (cli.motors_may_be_on) disable_over_new_connection(cli.o);
    throw;
  }
  if (cli.motors_may_be_on && !disable_over_new_connection(cli.o) && rc == exit_code_value::ok) rc = exit_code_value::failed;
  return rc;
}

// ---- the real-time loop -------------------------------------------------------------------------

// What a motion command hands back for its report.
struct Outcome {
  int rc = exit_code_value::ok;
  json report = json::object();  // command-specific figures (tracking, homing)
  std::vector<std::string> lines;  // the same for people (text mode)
};

json stats_json(const bh::LoopStats& st) {
  auto us = [](core::Duration d) { return std::chrono::duration<double, std::micro>(d).count(); };
  return json{{"cycles", st.cycles},          {"period_nominal_us", us(st.nominal)}, {"period_mean_us", us(st.period_mean)},
              {"jitter_p50_us", us(st.jitter_p50)}, {"jitter_p99_us", us(st.jitter_p99)}, {"jitter_max_us", us(st.jitter_max)},
              {"overruns", st.overruns},      {"missed", st.missed}};
}

// The table header now, then a row at each refresh of the library's control run (bh::run_control);
// a row that cannot be written stops the run.
// With --csv, every cycle's record goes to that file too.
bh::ControlHooks table_hooks(Session& s) {
  s.out().table_header();
  bh::ControlHooks h;
  std::shared_ptr<bh::CycleCsv> csv;
  if (!s.o().csv.empty()) csv = std::make_shared<bh::CycleCsv>(need(bh::CycleCsv::create(s.o().csv)));
  if (csv || s.web) {
    h.record = [csv, view = s.web ? s.web->view.get() : nullptr](const bh::CycleRecord& r) {
      if (csv) csv->write(r);
      if (view) view->add_record(r);
    };
  }
  h.refresh = [&s](double t, const bh::CycleRecord* last) {
    if (s.web) s.web->publish();
    if (!s.out().ok()) return false;
    return last == nullptr || s.out().row(t, bh::measurements_of(*last));
  };
  return h;
}

// The loop's figures and how it ended, for the report and the exit code.
Outcome outcome_of(const Session& s, const bh::ControlOutcome& c) {
  const auto& st = c.stats;
  if (s.web) {
    s.web->view->end_run(st, c.fault);
    s.web->publish(true);
  }
  spdlog::info("blmc: {} cycles, period {:.1f} us mean, jitter p99 {} us max {} us, {} overruns, {} missed",
               st.cycles, std::chrono::duration<double, std::micro>(st.period_mean).count(),
               std::chrono::duration_cast<std::chrono::microseconds>(st.jitter_p99).count(),
               std::chrono::duration_cast<std::chrono::microseconds>(st.jitter_max).count(), st.overruns, st.missed);
  Outcome out;
  out.report["loop"] = stats_json(st);
  out.report["fault"] = nullptr;
  if (c.fault) {
    spdlog::error("blmc: safety stop: {}", c.fault->fault.describe());
    out.report["fault"] = json{{"kind", bh::to_string(c.fault->fault.kind)}, {"text", c.fault->fault.describe()}};
    out.rc = exit_code_value::safety_stop;
  } else if (!s.out().ok()) {
    out.rc = exit_code_value::failed;
  }
  return out;
}

// The end of a motion command: its figures (a JSON report line, or text lines), and its exit code
// from the work and the disable.
int report(Output& output, const char* command, const bh::EnabledRun<Outcome>& run) {
  int rc = exit_code_value::failed;
  json j{{"type", "report"}, {"command", command}, {"enabled", static_cast<bool>(run.enable)}};
  if (!run.enable) {
    if (run.enable.error() != bh::HostErrc::interrupted) spdlog::error("blmc: enable: {}", run.enable.error().message());
    j["error"] = run.enable.error().message();
  } else if (run.value) {
    rc = run.value->rc;
    j.update(run.value->report);
  }
  const int signo = received_stop_signal().load();
  j["stopped_by"] = signo ? json(signal_name(signo)) : json(nullptr);
  j["disabled"] = static_cast<bool>(run.disable);
  if (run.disable) spdlog::info("blmc: board disabled, currents zero");
  else if (rc == exit_code_value::ok) rc = exit_code_value::failed;  // the library logged why
  if (output.is_json()) {
    j["exit_code"] = signo ? signal_exit_code(signo) : rc;
    output.emit(j);
  } else if (run.value) {
    for (const auto& line : run.value->lines)
      if (!output.emit(line)) break;
  }
  return rc;
}

using Work = asio::awaitable<Outcome> (*)(Session&);

// Enables the motors, runs `work`, and disables them on every way out (the library's MotorSession).
// An exception leaves motors_may_be_on set: whether the session's disable went through is not
// known then, so the disable over a new connection runs too (a second disable is harmless).
asio::awaitable<int> with_motors(Session& s, const char* command, Work work) {
  s.cli->motors_may_be_on = true;
  const std::function<asio::awaitable<Outcome>()> body = [&]() -> asio::awaitable<Outcome> {
    auto out = co_await work(s);
    co_return out;
  };
  auto run = co_await bh::with_motors_enabled<Outcome>(*s.board, body);
  s.cli->motors_may_be_on = !run.disable;  // a failed disable: try again over a new connection
  co_return report(s.out(), command, run);
}

// ---- subcommands ------------------------------------------------------------------------------

asio::awaitable<int> cmd_status(Session& s) {
  auto r = co_await bh::watch_status(*s.board, seconds(s.o().duration_s), [&s](const bp::Status& st) { return s.out().status(st); });
  if (!r) {
    spdlog::error("blmc: {}", r.error().message());
    co_return exit_code_value::failed;
  }
  co_return s.out().ok() ? exit_code_value::ok : exit_code_value::failed;
}

asio::awaitable<int> cmd_monitor(Session& s) {
  const auto& o = s.o();
  bool writing = s.out().table_header();
  if (writing)
    writing = co_await bh::monitor(*s.board, seconds(1.0 / o.refresh_hz), seconds(o.duration_s),
                                   [&s](double t, const bh::Measurements& m) {
                                     if (s.web) {
                                       s.web->view->add_measurements(0, t, m);
                                       s.web->publish();
                                     }
                                     return s.out().row(t, m);
                                   });
  const auto& m = s.board->latest();
  spdlog::info("blmc: {} board frames, {} rejected, {} foreign", m.frames, m.rejected, m.foreign);
  co_return writing ? exit_code_value::ok : exit_code_value::failed;
}

// `enable` hands the board on enabled (that is what it is for); a failed or interrupted enable is
// disabled again.
asio::awaitable<int> cmd_enable(Session& s) {
  s.cli->motors_may_be_on = true;  // until handed on or disabled
  auto r = co_await s.board->enable();
  if (!r) {
    if (r.error() != bh::HostErrc::interrupted) spdlog::error("blmc: enable: {}", r.error().message());
    auto d = co_await s.board->disable();
    if (d) spdlog::info("blmc: board disabled, currents zero");
    else spdlog::error("blmc: could not disable the board: {}", d.error().message());
    s.cli->motors_may_be_on = false;
    co_return exit_code_value::failed;
  }
  s.board->leave_enabled();
  s.cli->motors_may_be_on = false;
  co_return s.out().status(s.board->latest().status.value) ? exit_code_value::ok : exit_code_value::failed;
}

asio::awaitable<int> cmd_disable(Session& s) {
  auto r = co_await s.board->disable();
  need(std::move(r));
  co_return exit_code_value::ok;
}

asio::awaitable<Outcome> current_work(Session& s) {
  const auto& o = s.o();
  const int motor = o.current_motor;
  const double amps = o.current_amps;
  bh::FunctionController ctl([motor, amps](const bh::ControlInput&, std::span<bh::MotorPair> out) {
    out[0] = motor == 1 ? bh::MotorPair{amps, 0} : bh::MotorPair{0, amps};
  });
  const auto options = control_options(o, o.current_duration_s);
  auto hooks = table_hooks(s);
  auto r = co_await bh::run_control(*s.board, ctl, options, std::move(hooks));
  co_return outcome_of(s, need(std::move(r)));
}

asio::awaitable<Outcome> pd_work(Session& s) {
  const auto& o = s.o();
  const auto m = motor_set(o.motors);
  std::array<bh::PdTarget, 2> t;
  for (std::size_t i = 0; i < 2; ++i) t[i] = {m[i], o.pd_amplitude, o.pd_frequency, 0};
  const auto options = control_options(o, o.pd_duration_s);
  auto hooks = table_hooks(s);
  auto r = co_await bh::run_pd(*s.board, o.pd_gains, t, options, std::move(hooks));
  const auto pd = need(std::move(r));
  auto out = outcome_of(s, pd.control);
  out.report["tracking"] = json::array();
  for (int k = 0; k < 2; ++k) {
    if (!m[static_cast<std::size_t>(k)]) continue;
    const auto& ts = pd.tracking[static_cast<std::size_t>(k)];
    out.report["tracking"].push_back(
        json{{"motor", k + 1}, {"rms_rev", ts.rms_rev()}, {"max_rev", ts.max_abs_error_rev}, {"samples", ts.samples}});
    out.lines.push_back(fmt::format("motor {}: tracking error rms {:.5f} rev, max {:.5f} rev ({} samples)", k + 1,
                                    ts.rms_rev(), ts.max_abs_error_rev, ts.samples));
  }
  co_return out;
}

asio::awaitable<Outcome> home_work(Session& s) {
  const auto& o = s.o();
  auto ho = o.home;
  ho.motors = motor_set(o.motors);
  const auto options = control_options(o, o.home_timeout_s);
  auto hooks = table_hooks(s);
  auto r = co_await bh::run_homing(*s.board, ho, options, std::move(hooks));
  const auto home = need(std::move(r));
  auto out = outcome_of(s, home.control);
  out.report["homing"] = json::array();
  for (int k = 0; k < 2; ++k) {
    const auto& h = home.motors[static_cast<std::size_t>(k)];
    if (h.state == bh::MotorHoming::State::idle) continue;
    const bool found = h.state == bh::MotorHoming::State::found;
    out.report["homing"].push_back(json{{"motor", k + 1}, {"state", bh::to_string(h.state)},
                                        {"index_rev", found ? json(h.index_rev) : json(nullptr)}, {"start_rev", h.start_rev}});
    out.lines.push_back(found ? fmt::format("motor {}: index at {:.6f} rev (started at {:.6f})", k + 1, h.index_rev, h.start_rev)
                              : fmt::format("motor {}: {} (no index within {:.2f} rev)", k + 1, bh::to_string(h.state),
                                            ho.max_travel_rev));
  }
  if (out.rc == exit_code_value::ok && !home.all_found) out.rc = exit_code_value::failed;
  co_return out;
}

asio::awaitable<int> cmd_record(Session& s) {
  const auto& o = s.o();
  auto w = need(can::CandumpWriter::create(o.record_file));
  const auto n = co_await bh::record(*s.board, w, s.iface, seconds(o.duration_s));
  spdlog::info("blmc: {} frames to {}", n, o.record_file);
  co_return exit_code_value::ok;
}

asio::awaitable<int> cmd_raw(Session& s) {
  const auto& text = s.o().raw_text;
  can::Frame f;
  if (text.find('#') != std::string::npos) f = need(can::Frame::parse(text));
  else f = need(bp::encode(need(bp::Command::parse(text))));
  auto r = co_await s.board->send_frame(f);
  need(std::move(r));
  auto m = bp::decode_to_board(f);
  const std::string decoded = m ? bp::to_string(m.value()) : std::string();
  const bool written = s.out().is_json()
                           ? s.out().emit(json{{"type", "sent"}, {"frame", f.to_string()}, {"decoded", m ? json(decoded) : json(nullptr)}})
                           : s.out().emit(fmt::format("sent {}{}", f.to_string(), m ? " (" + decoded + ")" : ""));
  co_return written ? exit_code_value::ok : exit_code_value::failed;
}

bh::MotorPair pair_of(const std::vector<double>& v) { return {v.at(0), v.at(1)}; }

// `onboard`: the settings given, in this order, each through the library (which checks the
// values first); what was sent is printed as one line each (one JSON object with --json).
asio::awaitable<int> cmd_onboard(Session& s) {
  const auto& o = s.o().onboard;
  if (o.rollover_error < 0 && o.position.empty() && o.kp.empty() && o.p_limit.empty() && o.springs.empty())
    throw Exception(usage("onboard: give at least one of --kp/--kd, --position/--velocity, --p-limit/--d-limit, "
                          "--springs, --rollover-error"));
  auto& b = *s.board;
  json sent = json::object();
  std::vector<std::string> lines;
  const auto note = [&](const char* key, const std::vector<double>& v, const char* unit) {
    sent[key] = json::array({v.at(0), v.at(1)});
    lines.push_back(fmt::format("set {} {:g} {:g} {}", key, v.at(0), v.at(1), unit));
  };
  if (o.rollover_error >= 0) {
    auto r = co_await b.set_rollover_error(o.rollover_error == 1);
    need(std::move(r));
    sent["rollover_error"] = o.rollover_error == 1;
    lines.push_back(fmt::format("set rollover_error {}", o.rollover_error));
  }
  if (!o.position.empty()) {
    auto r = co_await b.set_onboard_references({pair_of(o.position), pair_of(o.velocity)});
    need(std::move(r));
    note("position", o.position, "rev");
    note("velocity", o.velocity, "krpm");
  }
  if (!o.kp.empty()) {
    auto r = co_await b.set_onboard_gains({pair_of(o.kp), pair_of(o.kd)});
    need(std::move(r));
    note("kp", o.kp, "A/rev");
    note("kd", o.kd, "A/krpm");
  }
  if (!o.p_limit.empty()) {
    auto r = co_await b.set_onboard_current_limits({pair_of(o.p_limit), pair_of(o.d_limit)});
    need(std::move(r));
    note("p_limit", o.p_limit, "A");
    note("d_limit", o.d_limit, "A");
  }
  if (!o.springs.empty()) {
    auto r = co_await b.set_virtual_springs({o.springs.at(0) != 0, o.springs.at(1) != 0});
    need(std::move(r));
    sent["springs"] = json::array({o.springs.at(0) == 1, o.springs.at(1) == 1});
    lines.push_back(fmt::format("set springs {} {}", o.springs.at(0), o.springs.at(1)));
  }
  if (s.out().is_json()) {
    sent["type"] = "onboard";
    co_return s.out().emit(sent) ? exit_code_value::ok : exit_code_value::failed;
  }
  for (const auto& line : lines)
    if (!s.out().emit(line)) co_return exit_code_value::failed;
  co_return exit_code_value::ok;
}

// How a subcommand ends on SIGINT/SIGTERM/SIGHUP: observers (monitor, record) end normally (exit 0),
// motion commands check the loop options first; every other command exits 128+N.
enum class Kind { plain, observe, motion };

// The loop options that only make sense together, checked before anything is sent to the board
// (each alone is checked by its validator).
void check_loop_options(const BlmcOptions& o) {
  if (auto v = bh::validate(control_options(o, 1), o.recv_timeout_ms); !v)
    throw Exception(usage(fmt::format("--rate {:g} / --recv-timeout-ms {}: {}", o.rate_hz, o.recv_timeout_ms, v.error().detail)));
}

CLI::App* add(CLI::App* parent, GlobalOptions& global, const std::shared_ptr<Blmc>& cli, const char* name, const char* help, Kind kind, Body body) {
  auto* c = parent->add_subcommand(name, help);
  c->callback([cli, body = std::move(body), kind, name, &global] {
    cli->command = name;
    cli->motion = kind == Kind::motion;
    if (kind == Kind::motion) check_loop_options(cli->o);
    global.exit_code = run_blmc(*cli, kind == Kind::observe, body);
  });
  return c;
}

CLI::App* add_motion(CLI::App* parent, GlobalOptions& global, const std::shared_ptr<Blmc>& cli, const char* name, const char* help, Work work) {
  return add(parent, global, cli, name, help, Kind::motion, [name, work](Session& s) -> asio::awaitable<int> {
    const int rc = co_await with_motors(s, name, work);
    co_return rc;
  });
}

// A current of either sign (clamped to --max-current when sent).
CLI::Validator amperes() { return between(-100, 100); }

// Not zero: its sign is meaningful (a direction).
CLI::Validator nonzero() {
  return CLI::Validator(
      [](std::string& in) -> std::string {
        double v = 0;
        if (!detail::finite_number(in, v)) return fmt::format("must be a number other than 0, got '{}'", in);
        return v != 0 ? std::string() : "must not be 0 (its sign gives the direction)";
      },
      "!= 0", "nonzero");
}

void add_board_options(CLI::App* b, BlmcOptions& o) {
  b->add_option("--bus", o.bus, "bus spec: socketcan:can0, socketcand://HOST[:PORT]/CH, cannet://HOST/N, virtual:NAME");
  b->add_option("--socketcand", o.socketcand, "socketcand server as HOST:PORT/CHANNEL");
  b->add_option("--socketcan", o.socketcan, "SocketCAN interface (default can0)");
  b->add_option("--log", o.log, "write every frame of the session to this candump log");
  b->add_option("--csv", o.csv, "current, pd, home: write every control cycle to this CSV file (docs/library-blmc.md)");
  b->add_option("--motors", o.motors, "motors to use: 1, 2 or both (default both)");
  b->add_option("--max-current", o.max_current, "safety: current clamp, A (default 2)")->check(positive());
  b->add_option("--max-velocity", o.max_velocity, "safety: zero current above this speed, krpm (default 2)")->check(positive());
  b->add_option("--stale-ms", o.stale_ms, "safety: stop when a measurement is older than this (default 20 ms)")->check(positive());
  b->add_option("--recv-timeout-ms", o.recv_timeout_ms, "board receive timeout set when control starts (default 50; 0: off)")
      ->check(non_negative());
  b->add_option("--ready-timeout", o.ready_timeout_s, "seconds to wait for alignment (default 10)")->check(positive());
  b->add_option("--rate", o.rate_hz, "control loop rate, Hz (default 1000)")->check(positive());
  b->add_option("--refresh", o.refresh_hz, "table refresh rate, Hz (default 10)")->check(positive());
  b->add_flag("!--no-realtime", o.realtime, "do not ask for SCHED_FIFO / mlockall");
  b->add_option("--cpu", o.cpus, "pin the control thread to these CPUs")->delimiter(',');
  b->add_flag("--pace-measurements", o.pace_measurements, "start each cycle when the board's data burst arrived");
  b->add_flag("--json", o.json, "stdout: JSON Lines (one object per line: status, sample, report, sent)");
  b->add_option("--http", o.http, "monitor, current, pd, home: serve the board's live page and /metrics on HOST:PORT "
                                   "(docs/dashboard.md; 127.0.0.1 keeps it on this machine, port 0: any)");
  b->add_option("--http-linger", o.http_linger_s, "with --http: keep serving the final state this many seconds after the "
                                                  "command (Ctrl-C ends it; default 0)")->check(non_negative());
}

void add_motion_commands(CLI::App* b, GlobalOptions& global, const std::shared_ptr<Blmc>& cli) {
  auto& o = cli->o;
  auto* cur = add_motion(b, global, cli, "current", "apply a constant current to one motor for a while (safety limits apply)",
                         current_work);
  cur->add_option("motor", o.current_motor, "1 or 2")->required()->check(CLI::Range(1, 2));
  cur->add_option("amperes", o.current_amps, "current, A (clamped to --max-current)")->required()->check(amperes());
  cur->add_option("--duration", o.current_duration_s, "seconds (default 1)")->check(positive());

  auto* pd = add_motion(b, global, cli, "pd", "host-side PD: hold the start position, or track a sine around it", pd_work);
  pd->add_option("--kp", o.pd_gains.kp, "A per motor revolution (default 5)")->check(non_negative());
  pd->add_option("--kd", o.pd_gains.kd, "A per rev/s (default 0.05)")->check(non_negative());
  pd->add_option("--amplitude", o.pd_amplitude, "sine amplitude, motor rev (default 0: hold)")->check(non_negative());
  pd->add_option("--frequency", o.pd_frequency, "sine frequency, Hz (default 0.5)")->check(non_negative());
  pd->add_option("--duration", o.pd_duration_s, "seconds (default 5)")->check(positive());

  auto* home = add_motion(b, global, cli, "home", "find the encoder index of each motor and report its position (the offset)",
                          home_work);
  home->add_option("--speed", o.home.speed_rev_s, "motor rev/s, sign gives the direction (default 0.5)")->check(nonzero());
  home->add_option("--kp", o.home.kp, "A per rev (default 2)")->check(positive());
  home->add_option("--kd", o.home.kd, "A per rev/s (default 0.02)")->check(non_negative());
  home->add_option("--current", o.home.max_current_a, "current limit while homing, A (default 0.5)")->check(positive());
  home->add_option("--travel", o.home.max_travel_rev, "give up after this many motor rev (default 2)")->check(positive());
  home->add_option("--timeout", o.home_timeout_s, "seconds (default 20)")->check(positive());
}

// Each option takes motor 1's value, then motor 2's.
void add_onboard_command(CLI::App* b, GlobalOptions& global, const std::shared_ptr<Blmc>& cli) {
  auto& o = cli->o.onboard;
  auto* c = add(b, global, cli, "onboard",
                "set the board's own controller (optional in the spec), rollover error, virtual springs", Kind::plain,
                cmd_onboard);
  const auto pair = [c](const char* name, std::vector<double>& v, const char* help) {
    return c->add_option(name, v, help)->expected(2);
  };
  auto* kp = pair("--kp", o.kp, "KP per motor, A/rev (with --kd)");
  auto* kd = pair("--kd", o.kd, "KD per motor, A/krpm (with --kp)");
  auto* pos = pair("--position", o.position, "POS_REF per motor, rev (with --velocity)");
  auto* vel = pair("--velocity", o.velocity, "VEL_REF per motor, krpm (with --position)");
  auto* pl = pair("--p-limit", o.p_limit, "P term current limit per motor, A (with --d-limit)");
  auto* dl = pair("--d-limit", o.d_limit, "D term current limit per motor, A (with --p-limit)");
  for (auto [one, other] : {std::pair{kp, kd}, std::pair{pos, vel}, std::pair{pl, dl}}) {
    one->needs(other);
    other->needs(one);
  }
  c->add_option("--springs", o.springs, "virtual spring per motor, 1 = on, 0 = off")->expected(2)->check(CLI::Range(0, 1));
  c->add_option("--rollover-error", o.rollover_error, "1: the board stops itself at the +-100 rev rollover, 0: not")
      ->check(CLI::Range(0, 1));
}

}  // namespace

void add_blmc_commands(CLI::App& app, GlobalOptions& global) {
  auto cli = std::make_shared<Blmc>();
  auto& o = cli->o;
  auto* b = app.add_subcommand("blmc", "motor driver board: status, monitor, enable, current, PD, homing, record, raw, onboard");
  b->require_subcommand(1);
  add_board_options(b, o);

  add(b, global, cli, "status", "decoded status frames (one, or live with --duration)", Kind::plain, cmd_status)
      ->add_option("--duration", o.duration_s, "seconds to keep printing (default 0: one)")
      ->check(non_negative());
  add(b, global, cli, "monitor", "live table of currents, positions, velocities, ADC", Kind::observe, cmd_monitor)
      ->add_option("--duration", o.duration_s, "seconds (default 0: until Ctrl-C)")
      ->check(non_negative());
  add(b, global, cli, "enable", "enable the system and motors, wait until they are aligned, and leave them enabled", Kind::plain,
      cmd_enable);
  add(b, global, cli, "disable", "zero currents, disable the motors and the system", Kind::plain, cmd_disable);
  add_motion_commands(b, global, cli);

  auto* rec = add(b, global, cli, "record", "write a candump log of the bus (everything the board sends and receives)",
                  Kind::observe, cmd_record);
  rec->add_option("file", o.record_file, "candump log file")->required();
  rec->add_option("--duration", o.duration_s, "seconds (default 0: until Ctrl-C)")->check(non_negative());

  add(b, global, cli, "raw", "send one frame (ID#DATA) or command (NAME=value)", Kind::plain, cmd_raw)
      ->add_option("frame", o.raw_text, "e.g. 000#0000000100000001 or ENABLE_SYS=1")
      ->required();
  add_onboard_command(b, global, cli);
}

}  // namespace axon::app
