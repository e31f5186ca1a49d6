// `axon blmc ...`: one motor driver board (two motors) on one CAN bus, through the host driver
// (docs/blmc-host.md). Motion commands run the real-time ControlLoop with the safety limits given
// by flags; every command that enabled the motors disables them when it ends (also on Ctrl-C or
// a fault). Tables and results go to stdout, logs to stderr.
#include "blmc/host/board.hpp"
#include "blmc/host/control_loop.hpp"
#include "blmc/host/error.hpp"
#include "blmc/host/homing.hpp"
#include "blmc/host/pd_controller.hpp"
#include "blmc/protocol/command.hpp"
#include "blmc/protocol/frames.hpp"
#include "can/bus_spec.hpp"
#include "can/candump_log.hpp"
#include "can/open.hpp"
#include "commands.hpp"
#include "core/wakeup.hpp"
#include "run.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>

namespace axon::app {
namespace {

using namespace std::chrono_literals;
namespace bh = blmc::host;
namespace bp = blmc::protocol;

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
};

BlmcOptions& opts() {
  static BlmcOptions o;
  return o;
}

std::string bus_text(const BlmcOptions& o) {
  int given = !o.bus.empty() + !o.socketcand.empty() + !o.socketcan.empty();
  if (given > 1) throw Exception(Error(CoreErrc::invalid_argument, "give one of --bus, --socketcand, --socketcan"));
  if (!o.socketcand.empty()) return "socketcand://" + o.socketcand;
  if (!o.socketcan.empty()) return "socketcan:" + o.socketcan;
  if (!o.bus.empty()) return o.bus;
  return "socketcan:can0";
}

std::array<bool, 2> motor_set(const std::string& m) {
  if (m == "1") return {true, false};
  if (m == "2") return {false, true};
  if (m == "both" || m == "1,2") return {true, true};
  throw Exception(Error(CoreErrc::invalid_argument, fmt::format("--motors {}: use 1, 2 or both", m)));
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

std::string status_line(const bp::Status& s) { return s.to_string(); }

// One session: bus, board, optional candump log, Ctrl-C handling.
struct Session {
  std::unique_ptr<can::Bus> bus;
  std::unique_ptr<bh::Board> board;
  std::optional<can::CandumpWriter> log;
  std::string iface;
  bool stop = false;
};

asio::awaitable<std::unique_ptr<Session>> open_session(asio::io_context& io,
                                                       const std::function<void(std::function<void()>)>& on_signal) {
  const auto& o = opts();
  auto s = std::make_unique<Session>();
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
  on_signal([raw] { raw->stop = true; });
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

void print_table_header() {
  std::printf("%8s | %8s %8s | %9s %9s | %8s %8s | %6s %6s | %s\n", "t[s]", "I1[A]", "I2[A]", "pos1[rev]", "pos2[rev]",
              "v1[krpm]", "v2[krpm]", "adcA", "adcB", "status");
}

void print_row(double t, const bh::Measurements& m) {
  std::printf("%8.3f | %8.3f %8.3f | %9.4f %9.4f | %8.4f %8.4f | %6.3f %6.3f | %s\n", t, m.current.value.motor1,
              m.current.value.motor2, m.position.value.motor1, m.position.value.motor2, m.velocity.value.motor1,
              m.velocity.value.motor2, m.adc.value.motor1, m.adc.value.motor2,
              m.status.received() ? status_line(m.status.value).c_str() : "(no status yet)");
  std::fflush(stdout);
}

// Runs `controller` in the real-time loop until `duration` (0: until the controller says done or
// Ctrl-C), printing a row at the refresh rate. Returns the exit code (4 on a safety fault).
asio::awaitable<int> run_loop(Session& s, bh::Controller& controller, double duration_s,
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
  const auto refresh = seconds(1.0 / std::max(0.5, o.refresh_hz));
  print_table_header();
  bh::CycleRecord rec{}, last{};
  bool have = false;
  while (loop.running() && !s.stop) {
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
      print_row(t, m);
    }
    if (duration_s > 0 && t >= duration_s) break;
    if (done && done()) break;
  }
  loop.stop();
  auto r1 = co_await s.board->stop_cyclic();
  (void)r1;
  const auto st = loop.stats();
  spdlog::info("blmc: {} cycles, period {:.1f} us mean, jitter p99 {} us max {} us, {} overruns, {} missed",
               st.cycles, std::chrono::duration<double, std::micro>(st.period_mean).count(),
               std::chrono::duration_cast<std::chrono::microseconds>(st.jitter_p99).count(),
               std::chrono::duration_cast<std::chrono::microseconds>(st.jitter_max).count(), st.overruns, st.missed);
  if (auto f = loop.fault()) {
    spdlog::error("blmc: safety stop: {}", f->fault.describe());
    co_return 4;
  }
  co_return 0;
}

int run_blmc(std::function<asio::awaitable<int>(Session&)> body) {
  return run_command([body](asio::io_context& io, auto set_on_signal) -> asio::awaitable<int> {
    auto s = co_await open_session(io, set_on_signal);
    int rc = 0;
    std::exception_ptr failure;
    try {
      rc = co_await body(*s);
    } catch (...) {
      failure = std::current_exception();
    }
    co_await close_session(*s);
    if (failure) std::rethrow_exception(failure);
    co_return rc;
  });
}

// Enables, runs `f`, and disables whatever happened.
asio::awaitable<int> with_enabled(Session& s, std::function<asio::awaitable<int>(Session&)> f) {
  auto r = co_await s.board->enable();
  if (!r) {
    spdlog::error("blmc: enable: {}", r.error().message());
    auto d = co_await s.board->disable();
    (void)d;
    co_return 3;
  }
  int rc = 0;
  std::exception_ptr failure;
  try {
    rc = co_await f(s);
  } catch (...) {
    failure = std::current_exception();
  }
  auto d = co_await s.board->disable();
  if (!d) spdlog::error("blmc: disable: {}", d.error().message());
  if (failure) std::rethrow_exception(failure);
  co_return rc;
}

// ---- subcommands ------------------------------------------------------------------------------

asio::awaitable<int> cmd_status(Session& s) {
  const auto& o = opts();
  const auto t0 = core::SteadyClock::instance().now();
  int printed = 0;
  while (!s.stop) {
    auto st = co_await s.board->wait_status(s.board->options().status_timeout);
    if (!st) {
      if (st.error() == bh::HostErrc::closed) co_return 1;
      spdlog::error("blmc: {}", st.error().message());
      co_return 3;
    }
    const auto& v = st.value();
    std::printf("%s  (byte 0x%02X)\n", v.to_string().c_str(), v.to_byte());
    std::fflush(stdout);
    ++printed;
    if (o.duration_s <= 0 && printed >= 1) break;
    if (o.duration_s > 0 && core::SteadyClock::instance().now() - t0 >= seconds(o.duration_s)) break;
  }
  co_return 0;
}

asio::awaitable<int> cmd_monitor(Session& s) {
  const auto& o = opts();
  const auto t0 = core::SteadyClock::instance().now();
  print_table_header();
  while (!s.stop && !s.board->closed()) {
    co_await core::sleep_for(seconds(1.0 / std::max(0.5, o.refresh_hz)));
    const double t = std::chrono::duration<double>(core::SteadyClock::instance().now() - t0).count();
    print_row(t, s.board->latest());
    if (o.duration_s > 0 && t >= o.duration_s) break;
  }
  const auto& m = s.board->latest();
  spdlog::info("blmc: {} board frames, {} rejected, {} foreign", m.frames, m.rejected, m.foreign);
  co_return 0;
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

void add(CLI::App* parent, const char* name, const char* help, std::function<asio::awaitable<int>(Session&)> body,
         CLI::App** out = nullptr) {
  auto* c = parent->add_subcommand(name, help);
  c->callback([body] { exit_code() = run_blmc(body); });
  if (out) *out = c;
}

}  // namespace

void add_blmc_commands(CLI::App& app, GlobalOptions& /*global*/) {
  auto& o = opts();
  auto* b = app.add_subcommand("blmc", "motor driver board: status, monitor, enable, current, PD, homing, record, raw");
  b->require_subcommand(1);
  b->add_option("--bus", o.bus, "bus spec: socketcan:can0, socketcand://HOST[:PORT]/CH, cannet://HOST/N, virtual:NAME");
  b->add_option("--socketcand", o.socketcand, "socketcand server as HOST:PORT/CHANNEL");
  b->add_option("--socketcan", o.socketcan, "SocketCAN interface (default can0)");
  b->add_option("--log", o.log, "write every frame of the session to this candump log");
  b->add_option("--motors", o.motors, "motors to use: 1, 2 or both (default both)");
  b->add_option("--max-current", o.max_current, "safety: current clamp, A (default 2)");
  b->add_option("--max-velocity", o.max_velocity, "safety: zero current above this speed, krpm (default 2)");
  b->add_option("--stale-ms", o.stale_ms, "safety: stop when a measurement is older than this (default 20 ms)");
  b->add_option("--recv-timeout-ms", o.recv_timeout_ms, "board receive timeout set when control starts (default 50)");
  b->add_option("--ready-timeout", o.ready_timeout_s, "seconds to wait for alignment (default 10)");
  b->add_option("--rate", o.rate_hz, "control loop rate, Hz (default 1000)");
  b->add_option("--refresh", o.refresh_hz, "table refresh rate, Hz (default 10)");
  b->add_flag("!--no-realtime", o.realtime, "do not ask for SCHED_FIFO / mlockall");
  b->add_option("--cpu", o.cpus, "pin the control thread to these CPUs")->delimiter(',');
  b->add_flag("--pace-measurements", o.pace_measurements, "start each cycle when the board's data burst arrived");

  add(b, "status", "decoded status frames (one, or live with --duration)", cmd_status);
  b->get_subcommand("status")->add_option("--duration", o.duration_s, "seconds to keep printing");

  CLI::App* mon = nullptr;
  add(b, "monitor", "live table of currents, positions, velocities, ADC", cmd_monitor, &mon);
  mon->add_option("--duration", o.duration_s, "seconds (default: until Ctrl-C)");

  add(b, "enable", "enable the system and motors and wait until they are aligned", [](Session& s) -> asio::awaitable<int> {
    auto r = co_await s.board->enable();
    if (!r) {
      spdlog::error("blmc: {}", r.error().message());
      co_return 3;
    }
    std::printf("%s\n", s.board->latest().status.value.to_string().c_str());
    co_return 0;
  });
  add(b, "disable", "zero currents, disable the motors and the system", [](Session& s) -> asio::awaitable<int> {
    auto r = co_await s.board->disable();
    need(std::move(r));
    co_return 0;
  });

  CLI::App* cur = nullptr;
  add(b, "current", "apply a constant current to one motor for a while (safety limits apply)",
      [](Session& s) -> asio::awaitable<int> {
        const std::function<asio::awaitable<int>(Session&)> inner = [](Session& s2) -> asio::awaitable<int> {
          const auto a = current_args;
          bh::FunctionController ctl([a](const bh::ControlInput&, std::span<bh::MotorPair> out) {
            out[0] = a.motor == 1 ? bh::MotorPair{a.amps, 0} : bh::MotorPair{0, a.amps};
          });
          const int rc = co_await run_loop(s2, ctl, a.duration_s);
          co_return rc;
        };
        const int rc = co_await with_enabled(s, inner);
        co_return rc;
      },
      &cur);
  cur->add_option("motor", current_args.motor, "1 or 2")->required()->check(CLI::Range(1, 2));
  cur->add_option("amperes", current_args.amps, "current, A (clamped to --max-current)")->required();
  cur->add_option("--duration", current_args.duration_s, "seconds (default 1)");

  CLI::App* pd = nullptr;
  add(b, "pd", "host-side PD: hold the start position, or track a sine around it",
      [](Session& s) -> asio::awaitable<int> {
        const std::function<asio::awaitable<int>(Session&)> inner = [](Session& s2) -> asio::awaitable<int> {
          const auto m = motor_set(opts().motors);
          std::array<bh::PdTarget, 2> t;
          for (std::size_t i = 0; i < 2; ++i) t[i] = {m[i], pd_args.amplitude, pd_args.frequency, 0};
          bh::PdController ctl(1, {pd_args.kp, pd_args.kd}, t);
          const int rc = co_await run_loop(s2, ctl, pd_args.duration_s);
          for (int k = 0; k < 2; ++k) {
            if (!m[static_cast<std::size_t>(k)]) continue;
            const auto& ts = ctl.tracking(0, k);
            std::printf("motor %d: tracking error rms %.5f rev, max %.5f rev (%llu samples)\n", k + 1, ts.rms_rev(),
                        ts.max_abs_error_rev, static_cast<unsigned long long>(ts.samples));
          }
          co_return rc;
        };
        const int rc = co_await with_enabled(s, inner);
        co_return rc;
      },
      &pd);
  pd->add_option("--kp", pd_args.kp, "A per motor revolution (default 5)");
  pd->add_option("--kd", pd_args.kd, "A per rev/s (default 0.05)");
  pd->add_option("--amplitude", pd_args.amplitude, "sine amplitude, motor rev (default 0: hold)");
  pd->add_option("--frequency", pd_args.frequency, "sine frequency, Hz (default 0.5)");
  pd->add_option("--duration", pd_args.duration_s, "seconds (default 5)");

  CLI::App* home = nullptr;
  add(b, "home", "find the encoder index of each motor and report its position (the offset)",
      [](Session& s) -> asio::awaitable<int> {
        const std::function<asio::awaitable<int>(Session&)> inner = [](Session& s2) -> asio::awaitable<int> {
          auto ho = home_args;
          ho.motors = motor_set(opts().motors);
          bh::HomingController ctl(1, ho);
          const std::function<bool()> done = [&] { return ctl.done(); };
          int rc = co_await run_loop(s2, ctl, home_timeout_s, done);
          for (int k = 0; k < 2; ++k) {
            const auto& r = ctl.result(0, k);
            if (r.state == bh::MotorHoming::State::idle) continue;
            if (r.state == bh::MotorHoming::State::found)
              std::printf("motor %d: index at %.6f rev (started at %.6f)\n", k + 1, r.index_rev, r.start_rev);
            else
              std::printf("motor %d: %s (no index within %.2f rev)\n", k + 1, bh::to_string(r.state), ho.max_travel_rev);
          }
          if (rc == 0 && !ctl.all_found()) rc = 5;
          co_return rc;
        };
        const int rc = co_await with_enabled(s, inner);
        co_return rc;
      },
      &home);
  home->add_option("--speed", home_args.speed_rev_s, "motor rev/s, sign gives the direction (default 0.5)");
  home->add_option("--kp", home_args.kp, "A per rev (default 2)");
  home->add_option("--kd", home_args.kd, "A per rev/s (default 0.02)");
  home->add_option("--current", home_args.max_current_a, "current limit while homing, A (default 0.5)");
  home->add_option("--travel", home_args.max_travel_rev, "give up after this many motor rev (default 2)");
  home->add_option("--timeout", home_timeout_s, "seconds (default 20)");

  CLI::App* rec = nullptr;
  static std::string record_file;
  add(b, "record", "write a candump log of the bus (everything the board sends and receives)",
      [](Session& s) -> asio::awaitable<int> {
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
        co_return 0;
      },
      &rec);
  rec->add_option("file", record_file, "candump log file")->required();
  rec->add_option("--duration", o.duration_s, "seconds (default: until Ctrl-C)");

  CLI::App* raw = nullptr;
  add(b, "raw", "send one frame (ID#DATA) or command (NAME=value)", [](Session& s) -> asio::awaitable<int> {
    can::Frame f;
    if (raw_text.find('#') != std::string::npos) f = need(can::Frame::parse(raw_text));
    else f = need(bp::encode(need(bp::Command::parse(raw_text))));
    auto r = co_await s.board->send_frame(f);
    need(std::move(r));
    auto m = bp::decode_to_board(f);
    std::printf("sent %s%s\n", f.to_string().c_str(), m ? (" (" + bp::to_string(m.value()) + ")").c_str() : "");
    co_return 0;
  }, &raw);
  raw->add_option("frame", raw_text, "e.g. 000#0000000100000001 or ENABLE_SYS=1")->required();
}

}  // namespace axon::app
