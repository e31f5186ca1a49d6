// `axon blmc ...`: one motor driver board (two motors) on one CAN bus, through the host driver
// (docs/blmc-host.md). Motion commands run the real-time ControlLoop with the safety limits given
// by flags inside a blmc::host::MotorSession: on every way out (the end, a safety stop, a failed
// start, an exception, a closed stdout, Ctrl-C/SIGTERM/SIGHUP) the board gets zero current and is
// disabled, and the disable's result decides the exit code. Tables and results go to stdout (JSON
// Lines with --json), logs to stderr.
#include "axon/blmc/host/board.hpp"
#include "axon/blmc/host/control_loop.hpp"
#include "axon/blmc/host/error.hpp"
#include "axon/blmc/host/homing.hpp"
#include "axon/blmc/host/motor_session.hpp"
#include "axon/blmc/host/pd_controller.hpp"
#include "axon/blmc/protocol/command.hpp"
#include "axon/blmc/protocol/frames.hpp"
#include "axon/can/bus_spec.hpp"
#include "axon/can/candump_log.hpp"
#include "axon/can/open.hpp"
#include "checks.hpp"
#include "commands.hpp"
#include "axon/core/wakeup.hpp"
#include "run.hpp"

#include <boost/asio/detached.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>

namespace axon::app {
namespace {

using namespace std::chrono_literals;
namespace bh = blmc::host;
namespace bp = blmc::protocol;
using json = nlohmann::json;

struct BlmcOptions {
  std::string bus;
  std::string socketcand;
  std::string socketcan;
  std::string log;  // candump log of every frame of the session
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
};

BlmcOptions& opts() {
  static BlmcOptions o;
  return o;
}

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

bh::SafetyLimits limits(const BlmcOptions& o) {
  bh::SafetyLimits l;
  l.motors = motor_set(o.motors);
  l.max_current_a = o.max_current;
  l.max_velocity_krpm = o.max_velocity;
  l.stale_after = std::chrono::microseconds(static_cast<std::int64_t>(o.stale_ms * 1000));
  return l;
}

core::Duration seconds(double s) { return std::chrono::duration_cast<core::Duration>(std::chrono::duration<double>(s)); }

// The loop options that only make sense together, checked before anything is sent to the board
// (each alone is checked by its validator).
void check_loop_options(const BlmcOptions& o) {
  constexpr double kMaxRate = 10000;
  if (o.rate_hz > kMaxRate)
    throw Exception(usage(fmt::format("--rate: must be at most {:g} Hz (the board runs at 1 kHz), got {:g}", kMaxRate, o.rate_hz)));
  const double period_ms = 1000.0 / o.rate_hz;
  if (o.recv_timeout_ms > 0 && period_ms >= o.recv_timeout_ms)
    throw Exception(usage(fmt::format("--rate {:g}: one current reference every {:g} ms, not within the board's receive "
                                      "timeout of {} ms (--recv-timeout-ms): the board would trip",
                                      o.rate_hz, period_ms, o.recv_timeout_ms)));
  if (auto v = limits(o).validate(); !v) throw Exception(usage(v.error().detail));
}

// ---- output -------------------------------------------------------------------------------------

// stdout, with the failure noticed: SIGPIPE is ignored, so a reader that went away (`| head`)
// shows as EPIPE here and the command stops (its devices made safe) instead of running blind.
bool g_output_ok = true;

bool emit(const std::string& line) {
  if (!g_output_ok) return false;
  if (std::fputs(line.c_str(), stdout) < 0 || std::fputc('\n', stdout) == EOF || std::fflush(stdout) != 0) {
    g_output_ok = false;
    spdlog::error("blmc: cannot write to stdout ({}): stopping", std::strerror(errno));
  }
  return g_output_ok;
}
bool emit(const json& j) { return emit(j.dump()); }

json pair_json(const bh::MotorPair& p) { return json::array({p.motor1, p.motor2}); }

json status_json(const bp::Status& s) {
  return json{{"system_enabled", s.system_enabled}, {"motor1_enabled", s.motor1_enabled},
              {"motor1_ready", s.motor1_ready}, {"motor2_enabled", s.motor2_enabled}, {"motor2_ready", s.motor2_ready},
              {"error", std::string(bp::name(s.error))}, {"byte", s.to_byte()}};
}

bool print_status(const bp::Status& s) {
  if (opts().json) {
    auto j = status_json(s);
    j["type"] = "status";
    return emit(j);
  }
  return emit(fmt::format("{}  (byte 0x{:02X})", s.to_string(), s.to_byte()));
}

bool print_table_header() {
  if (opts().json) return true;
  return emit(fmt::format("{:>8} | {:>8} {:>8} | {:>9} {:>9} | {:>8} {:>8} | {:>6} {:>6} | {}", "t[s]", "I1[A]", "I2[A]",
                          "pos1[rev]", "pos2[rev]", "v1[krpm]", "v2[krpm]", "adcA", "adcB", "status"));
}

bool print_row(double t, const bh::Measurements& m) {
  const auto& st = m.status;
  if (opts().json) {
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

// ---- session ------------------------------------------------------------------------------------

// One session: bus, board, optional candump log, stop requests.
struct Session {
  std::unique_ptr<can::Bus> bus;
  std::unique_ptr<bh::Board> board;
  std::optional<can::CandumpWriter> log;
  std::string iface;
  bool stop = false;
  bool signal_ends_normally = false;  // monitor/record until Ctrl-C: a signal is their end
};

// True from the moment a command enables the motors until their disable was sent. Still true
// after run_command only when the command was abandoned (a second signal stops the event loop
// at once): then the board is disabled over a new connection.
bool g_motors_may_be_on = false;

asio::awaitable<std::unique_ptr<Session>> open_session(asio::io_context& io,
                                                       const std::function<void(std::function<void()>)>& on_signal,
                                                       bool signal_ends_normally) {
  const auto& o = opts();
  auto s = std::make_unique<Session>();
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
    Session* raw = s.get();
    s->board->set_tap([raw](const can::Frame& f, bool) {
      can::Frame g = f;
      if (g.timestamp().count() == 0) g.set_timestamp(core::SteadyClock::instance().wall());
      (void)raw->log->write(g, raw->iface);
    });
  }
  Session* raw = s.get();
  // A stop request ends the waits on the board at once (an enable waiting for the alignment).
  on_signal([raw] {
    if (raw->signal_ends_normally) signal_is_normal_end().store(true);
    raw->stop = true;
    raw->board->interrupt();
  });
  spdlog::info("blmc: board on {}", spec.to_string());
  co_return s;
}

asio::awaitable<void> close_session(Session& s) {
  if (s.log) (void)s.log->flush();
  auto f = co_await s.bus->flush(1s);
  (void)f;
  s.board.reset();
  s.bus->close();
}

// A command abandoned with the motors on (see g_motors_may_be_on): IqRef=0 and the disables over
// a new connection, on a new event loop. Returns false when that failed too.
bool disable_over_new_connection() {
  spdlog::warn("blmc: stopped before the motors were disabled: disabling the board over a new connection");
  asio::io_context io;
  Result<void> result = Error(bh::HostErrc::timeout, "no answer from the bus within 3 s");
  asio::co_spawn(
      io,
      [&]() -> asio::awaitable<void> {
        const auto spec = need(can::parse_bus_spec(bus_text(opts())));
        auto b = co_await can::open_bus(io.get_executor(), spec);
        if (!b) {
          result = b.error();
          co_return;
        }
        auto bus = std::move(b).value();
        {
          bh::Board board(*bus);
          result = co_await board.disable();
        }
        auto f = co_await bus->flush(1s);
        (void)f;
        bus->close();
      },
      [](std::exception_ptr) {});
  io.run_for(3s);
  if (result) spdlog::info("blmc: board disabled, currents zero");
  else spdlog::error("blmc: could not disable the board: {}", result.error().message());
  return static_cast<bool>(result);
}

int run_blmc(bool signal_ends_normally, const std::function<asio::awaitable<int>(Session&)>& body) {
  int rc = 0;
  try {
    rc = run_command([&](asio::io_context& io, auto set_on_signal) -> asio::awaitable<int> {
      auto s = co_await open_session(io, set_on_signal, signal_ends_normally);
      int code = 0;
      std::exception_ptr failure;
      try {
        code = co_await body(*s);
      } catch (...) {
        failure = std::current_exception();
      }
      co_await close_session(*s);
      if (failure) std::rethrow_exception(failure);
      co_return code;
    });
  } catch (...) {
    if (g_motors_may_be_on) disable_over_new_connection();
    throw;
  }
  if (g_motors_may_be_on && !disable_over_new_connection() && rc == exit_code_value::ok) rc = exit_code_value::failed;
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

// Runs `controller` in the real-time loop until `duration` (0: until the controller says done or
// a stop request), printing a row at the refresh rate. The loop is stopped and destroyed before
// this returns or throws; the caller's MotorSession then leaves cyclic mode and disables.
asio::awaitable<Outcome> run_loop(Session& s, bh::Controller& controller, double duration_s,
                                  const std::function<bool()>& done = {}) {
  const auto& o = opts();
  auto r0 = co_await s.board->start_cyclic();
  need(std::move(r0));
  bh::LoopOptions lo;
  lo.period = seconds(1.0 / o.rate_hz);
  lo.realtime = o.realtime;
  lo.cpus = o.cpus;
  lo.pacing = o.pace_measurements ? bh::Pacing::measurements : bh::Pacing::clock;
  bh::ControlLoop loop({&s.board->port()}, controller, {limits(o)}, lo);
  need(loop.start());
  const auto t0 = core::SteadyClock::instance().now();
  const auto refresh = seconds(1.0 / o.refresh_hz);
  bool writing = print_table_header();
  bh::CycleRecord rec{}, last{};
  bool have = false;
  while (loop.running() && !s.stop && writing) {
    co_await core::sleep_for(refresh);
    while (loop.pop_record(rec)) {
      last = rec;
      have = true;
    }
    const double t = std::chrono::duration<double>(core::SteadyClock::instance().now() - t0).count();
    if (have) {
      bh::Measurements m;
      const auto& b = last.board[0];
      m.current.value = b.current;
      m.position.value = b.position;
      m.velocity.value = b.velocity;
      m.adc.value = b.adc;
      if (auto st = bp::Status::from_byte(b.status)) m.status = {st.value(), {}, 1};
      writing = print_row(t, m);
    }
    if (duration_s > 0 && t >= duration_s) break;
    if (done && done()) break;
  }
  loop.stop();
  const auto st = loop.stats();
  spdlog::info("blmc: {} cycles, period {:.1f} us mean, jitter p99 {} us max {} us, {} overruns, {} missed",
               st.cycles, std::chrono::duration<double, std::micro>(st.period_mean).count(),
               std::chrono::duration_cast<std::chrono::microseconds>(st.jitter_p99).count(),
               std::chrono::duration_cast<std::chrono::microseconds>(st.jitter_max).count(), st.overruns, st.missed);
  Outcome out;
  out.report["loop"] = stats_json(st);
  out.report["fault"] = nullptr;
  if (auto f = loop.fault()) {
    spdlog::error("blmc: safety stop: {}", f->fault.describe());
    out.report["fault"] = json{{"kind", bh::to_string(f->fault.kind)}, {"text", f->fault.describe()}};
    out.rc = exit_code_value::safety_stop;
  } else if (!writing) {
    out.rc = exit_code_value::failed;
  }
  co_return out;
}

// The end of a motion command: its figures (a JSON report line, or text lines), and its exit code
// from the work and the disable.
int report(const char* command, const bh::EnabledRun<Outcome>& run) {
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
  if (opts().json) {
    j["exit_code"] = signo ? signal_exit_code(signo) : rc;
    emit(j);
  } else if (run.value) {
    for (const auto& line : run.value->lines)
      if (!emit(line)) break;
  }
  return rc;
}

// Enables the motors, runs `work`, and disables them on every way out (MotorSession).
asio::awaitable<int> with_motors(Session& s, const char* command,
                                 const std::function<asio::awaitable<Outcome>(Session&)>& work) {
  g_motors_may_be_on = true;
  const std::function<asio::awaitable<Outcome>()> body = [&]() -> asio::awaitable<Outcome> {
    auto out = co_await work(s);
    co_return out;
  };
  std::optional<bh::EnabledRun<Outcome>> run;
  try {
    auto r = co_await bh::with_motors_enabled<Outcome>(*s.board, body);
    run = std::move(r);
  } catch (...) {
    // The session sent its disable, but whether it went through is not known here: the flag stays,
    // so the disable over a new connection runs too (a second disable is harmless).
    throw;
  }
  g_motors_may_be_on = !run->disable;  // a failed disable: try again over a new connection
  co_return report(command, *run);
}

// ---- subcommands ------------------------------------------------------------------------------

asio::awaitable<int> cmd_status(Session& s) {
  const auto& o = opts();
  const auto t0 = core::SteadyClock::instance().now();
  int printed = 0;
  while (!s.stop) {
    auto st = co_await s.board->wait_status(s.board->options().status_timeout);
    if (!st) {
      if (st.error() == bh::HostErrc::interrupted) break;
      spdlog::error("blmc: {}", st.error().message());
      co_return exit_code_value::failed;
    }
    if (!print_status(st.value())) co_return exit_code_value::failed;
    ++printed;
    if (o.duration_s <= 0 && printed >= 1) break;
    if (o.duration_s > 0 && core::SteadyClock::instance().now() - t0 >= seconds(o.duration_s)) break;
  }
  co_return exit_code_value::ok;
}

asio::awaitable<int> cmd_monitor(Session& s) {
  const auto& o = opts();
  const auto t0 = core::SteadyClock::instance().now();
  bool writing = print_table_header();
  while (!s.stop && !s.board->closed() && writing) {
    co_await core::sleep_for(seconds(1.0 / o.refresh_hz));
    const double t = std::chrono::duration<double>(core::SteadyClock::instance().now() - t0).count();
    writing = print_row(t, s.board->latest());
    if (o.duration_s > 0 && t >= o.duration_s) break;
  }
  const auto& m = s.board->latest();
  spdlog::info("blmc: {} board frames, {} rejected, {} foreign", m.frames, m.rejected, m.foreign);
  co_return writing ? exit_code_value::ok : exit_code_value::failed;
}

// `enable` hands the board on enabled (that is what it is for); a failed or interrupted enable is
// disabled again.
asio::awaitable<int> cmd_enable(Session& s) {
  g_motors_may_be_on = true;  // until handed on or disabled
  auto r = co_await s.board->enable();
  if (!r) {
    if (r.error() != bh::HostErrc::interrupted) spdlog::error("blmc: enable: {}", r.error().message());
    auto d = co_await s.board->disable();
    if (d) spdlog::info("blmc: board disabled, currents zero");
    else spdlog::error("blmc: could not disable the board: {}", d.error().message());
    g_motors_may_be_on = false;
    co_return exit_code_value::failed;
  }
  s.board->leave_enabled();
  g_motors_may_be_on = false;
  co_return print_status(s.board->latest().status.value) ? exit_code_value::ok : exit_code_value::failed;
}

asio::awaitable<int> cmd_disable(Session& s) {
  auto r = co_await s.board->disable();
  need(std::move(r));
  co_return exit_code_value::ok;
}

struct CurrentArgs {
  int motor = 1;
  double amps = 0;
  double duration_s = 1;
} current_args;

struct PdArgs {
  double kp = 5, kd = 0.05, amplitude = 0, frequency = 0.5, duration_s = 5;
} pd_args;

bh::HomingOptions home_args;
double home_timeout_s = 20;

std::string raw_text;
std::string record_file;

asio::awaitable<Outcome> current_work(Session& s) {
  const auto a = current_args;
  bh::FunctionController ctl([a](const bh::ControlInput&, std::span<bh::MotorPair> out) {
    out[0] = a.motor == 1 ? bh::MotorPair{a.amps, 0} : bh::MotorPair{0, a.amps};
  });
  auto out = co_await run_loop(s, ctl, a.duration_s);
  co_return out;
}

asio::awaitable<Outcome> pd_work(Session& s) {
  const auto m = motor_set(opts().motors);
  std::array<bh::PdTarget, 2> t;
  for (std::size_t i = 0; i < 2; ++i) t[i] = {m[i], pd_args.amplitude, pd_args.frequency, 0};
  bh::PdController ctl(1, {pd_args.kp, pd_args.kd}, t);
  auto out = co_await run_loop(s, ctl, pd_args.duration_s);
  out.report["tracking"] = json::array();
  for (int k = 0; k < 2; ++k) {
    if (!m[static_cast<std::size_t>(k)]) continue;
    const auto& ts = ctl.tracking(0, k);
    out.report["tracking"].push_back(
        json{{"motor", k + 1}, {"rms_rev", ts.rms_rev()}, {"max_rev", ts.max_abs_error_rev}, {"samples", ts.samples}});
    out.lines.push_back(fmt::format("motor {}: tracking error rms {:.5f} rev, max {:.5f} rev ({} samples)", k + 1,
                                    ts.rms_rev(), ts.max_abs_error_rev, ts.samples));
  }
  co_return out;
}

asio::awaitable<Outcome> home_work(Session& s) {
  auto ho = home_args;
  ho.motors = motor_set(opts().motors);
  bh::HomingController ctl(1, ho);
  const std::function<bool()> done = [&] { return ctl.done(); };
  auto out = co_await run_loop(s, ctl, home_timeout_s, done);
  out.report["homing"] = json::array();
  for (int k = 0; k < 2; ++k) {
    const auto& r = ctl.result(0, k);
    if (r.state == bh::MotorHoming::State::idle) continue;
    const bool found = r.state == bh::MotorHoming::State::found;
    out.report["homing"].push_back(json{{"motor", k + 1}, {"state", bh::to_string(r.state)},
                                        {"index_rev", found ? json(r.index_rev) : json(nullptr)}, {"start_rev", r.start_rev}});
    out.lines.push_back(found ? fmt::format("motor {}: index at {:.6f} rev (started at {:.6f})", k + 1, r.index_rev, r.start_rev)
                              : fmt::format("motor {}: {} (no index within {:.2f} rev)", k + 1, bh::to_string(r.state),
                                            ho.max_travel_rev));
  }
  if (out.rc == exit_code_value::ok && !ctl.all_found()) out.rc = exit_code_value::failed;
  co_return out;
}

asio::awaitable<int> cmd_record(Session& s) {
  const auto& oo = opts();
  auto w = need(can::CandumpWriter::create(record_file));
  std::uint64_t n = 0;
  s.board->set_tap([&](const can::Frame& f, bool) {
    can::Frame g = f;
    if (g.timestamp().count() == 0) g.set_timestamp(core::SteadyClock::instance().wall());
    if (w.write(g, s.iface)) ++n;
  });
  const auto t0 = core::SteadyClock::instance().now();
  while (!s.stop && !s.board->closed()) {
    co_await core::sleep_for(100ms);
    if (oo.duration_s > 0 && core::SteadyClock::instance().now() - t0 >= seconds(oo.duration_s)) break;
  }
  s.board->set_tap({});
  (void)w.flush();
  spdlog::info("blmc: {} frames to {}", n, record_file);
  co_return exit_code_value::ok;
}

asio::awaitable<int> cmd_raw(Session& s) {
  can::Frame f;
  if (raw_text.find('#') != std::string::npos) f = need(can::Frame::parse(raw_text));
  else f = need(bp::encode(need(bp::Command::parse(raw_text))));
  auto r = co_await s.board->send_frame(f);
  need(std::move(r));
  auto m = bp::decode_to_board(f);
  const std::string decoded = m ? bp::to_string(m.value()) : std::string();
  if (opts().json)
    co_return emit(json{{"type", "sent"}, {"frame", f.to_string()}, {"decoded", m ? json(decoded) : json(nullptr)}})
        ? exit_code_value::ok
        : exit_code_value::failed;
  co_return emit(fmt::format("sent {}{}", f.to_string(), m ? " (" + decoded + ")" : "")) ? exit_code_value::ok
                                                                                         : exit_code_value::failed;
}

// How a subcommand ends on SIGINT/SIGTERM/SIGHUP: observers (monitor, record) end normally (exit 0),
// motion commands check the loop options first; every other command exits 128+N.
enum class Kind { plain, observe, motion };

CLI::App* add(CLI::App* parent, const char* name, const char* help, Kind kind,
              std::function<asio::awaitable<int>(Session&)> body) {
  auto* c = parent->add_subcommand(name, help);
  c->callback([body, kind] {
    if (kind == Kind::motion) check_loop_options(opts());
    exit_code() = run_blmc(kind == Kind::observe, body);
  });
  return c;
}

CLI::App* add_motion(CLI::App* parent, const char* name, const char* help,
                     asio::awaitable<Outcome> (*work)(Session&)) {
  return add(parent, name, help, Kind::motion, [name, work](Session& s) -> asio::awaitable<int> {
    const std::function<asio::awaitable<Outcome>(Session&)> w = work;
    const int rc = co_await with_motors(s, name, w);
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
}

}  // namespace

void add_blmc_commands(CLI::App& app, GlobalOptions& /*global*/) {
  auto& o = opts();
  auto* b = app.add_subcommand("blmc", "motor driver board: status, monitor, enable, current, PD, homing, record, raw");
  b->require_subcommand(1);
  add_board_options(b, o);

  add(b, "status", "decoded status frames (one, or live with --duration)", Kind::plain, cmd_status)
      ->add_option("--duration", o.duration_s, "seconds to keep printing (default 0: one)")
      ->check(non_negative());
  add(b, "monitor", "live table of currents, positions, velocities, ADC", Kind::observe, cmd_monitor)
      ->add_option("--duration", o.duration_s, "seconds (default 0: until Ctrl-C)")
      ->check(non_negative());
  add(b, "enable", "enable the system and motors, wait until they are aligned, and leave them enabled", Kind::plain,
      cmd_enable);
  add(b, "disable", "zero currents, disable the motors and the system", Kind::plain, cmd_disable);

  auto* cur = add_motion(b, "current", "apply a constant current to one motor for a while (safety limits apply)",
                         current_work);
  cur->add_option("motor", current_args.motor, "1 or 2")->required()->check(CLI::Range(1, 2));
  cur->add_option("amperes", current_args.amps, "current, A (clamped to --max-current)")->required()->check(amperes());
  cur->add_option("--duration", current_args.duration_s, "seconds (default 1)")->check(positive());

  auto* pd = add_motion(b, "pd", "host-side PD: hold the start position, or track a sine around it", pd_work);
  pd->add_option("--kp", pd_args.kp, "A per motor revolution (default 5)")->check(non_negative());
  pd->add_option("--kd", pd_args.kd, "A per rev/s (default 0.05)")->check(non_negative());
  pd->add_option("--amplitude", pd_args.amplitude, "sine amplitude, motor rev (default 0: hold)")->check(non_negative());
  pd->add_option("--frequency", pd_args.frequency, "sine frequency, Hz (default 0.5)")->check(non_negative());
  pd->add_option("--duration", pd_args.duration_s, "seconds (default 5)")->check(positive());

  auto* home = add_motion(b, "home", "find the encoder index of each motor and report its position (the offset)",
                          home_work);
  home->add_option("--speed", home_args.speed_rev_s, "motor rev/s, sign gives the direction (default 0.5)")->check(nonzero());
  home->add_option("--kp", home_args.kp, "A per rev (default 2)")->check(positive());
  home->add_option("--kd", home_args.kd, "A per rev/s (default 0.02)")->check(non_negative());
  home->add_option("--current", home_args.max_current_a, "current limit while homing, A (default 0.5)")->check(positive());
  home->add_option("--travel", home_args.max_travel_rev, "give up after this many motor rev (default 2)")->check(positive());
  home->add_option("--timeout", home_timeout_s, "seconds (default 20)")->check(positive());

  auto* rec = add(b, "record", "write a candump log of the bus (everything the board sends and receives)", Kind::observe,
                  cmd_record);
  rec->add_option("file", record_file, "candump log file")->required();
  rec->add_option("--duration", o.duration_s, "seconds (default 0: until Ctrl-C)")->check(non_negative());

  add(b, "raw", "send one frame (ID#DATA) or command (NAME=value)", Kind::plain, cmd_raw)
      ->add_option("frame", raw_text, "e.g. 000#0000000100000001 or ENABLE_SYS=1")
      ->required();
}

}  // namespace axon::app
