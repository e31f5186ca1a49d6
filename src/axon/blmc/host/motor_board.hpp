// MotorBoard: one motor driver board (two motors) behind a blocking API, for a plain main() or a
// notebook. It owns its event loop on a thread of its own (core::LoopThread) with the bus and the
// host::Board on it; every call waits for its result. The coroutine API underneath (board.hpp,
// control_run.hpp) stays for programs that run their own event loop.
//
//   axon::blmc::MotorBoard board("socketcand://127.0.0.1:29536/can0");  // or socketcan:can0 ...
//   board.enable();                                  // aligned and ready, or an exception
//   auto report = board.run_control(law, 5s, settings);   // the 1 kHz loop with your law
//   board.disable();                                 // also done by the destructor
//
// Errors: every failure throws axon::Exception (core/error.hpp) carrying an axon::Error whose code
// is a host::HostErrc (blmc/host/error.hpp: timeout, not_ready, board_error, invalid_argument,
// interrupted ...) or the bus's can::CanErrc; invalid settings also compare equal to
// std::errc::invalid_argument. A safety stop during control is not an exception: the
// ControlReport names the fault, and the board is left with zero current and the motors off.
//
// Time limits: opening waits at most connect_timeout, enable() ready_timeout (plus the frames'
// time), wait_status() status_timeout, disable() and stop_control() a few seconds, home() its
// timeout; interrupt() (from any thread) ends a wait at once with HostErrc::interrupted.
//
// Threads: use one MotorBoard from one thread at a time (interrupt() excepted). The control law
// runs on the loop's real-time thread; everything else runs on the event-loop thread.
//
// Lifetime: the destructor stops the control loop, disables the motors (IqRef = 0, ENABLE_MTR1/2
// = 0, ENABLE_SYS = 0) and closes the bus; it never throws. The board's receive timeout
// (MotorBoardOptions::recv_timeout_ms, set when control starts) is the backstop when the process
// dies with a current flowing.
#pragma once

#include "axon/blmc/host/homing_options.hpp"
#include "axon/blmc/host/loop_timing.hpp"
#include "axon/blmc/host/measurements.hpp"
#include "axon/blmc/host/onboard.hpp"
#include "axon/blmc/host/safety.hpp"
#include "axon/blmc/protocol/status.hpp"

#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace axon::blmc {

using namespace std::chrono_literals;

struct MotorBoardOptions {
  std::string name = "blmc";               // in logs and error texts
  std::array<bool, 2> motors{true, true};  // the motors to enable, drive and supervise
  std::chrono::milliseconds connect_timeout = 5s;
  std::chrono::milliseconds ready_timeout = 10s;    // the first enable aligns the motors (seconds)
  std::chrono::milliseconds status_timeout = 2500ms;  // the board sends its status once a second
  std::uint32_t recv_timeout_ms = 50;  // the board's own receive timeout during control (0: off)
};

// What the control law sees each cycle (SI-like units: motor revolutions, seconds, amperes).
struct ControlState {
  std::uint64_t cycle = 0;
  double time_s = 0;  // since the loop started
  double dt_s = 0;    // since the previous cycle
  std::array<double, 2> position_rev{};
  std::array<double, 2> velocity_rev_s{};
  std::array<double, 2> current_a{};
  std::array<double, 2> adc{};  // 0..1
  protocol::Status status{};    // the latest status frame
};

// What the law asks of one motor: a current plus, when kp or kd is not 0, a PD term
//   current_a + kp (position_rev - position) + kd (velocity_rev_s - velocity)
// computed in the same cycle from the fresh measurements. The safety limits apply to the sum.
struct MotorCommand {
  double current_a = 0;       // A (feed-forward, or the whole command when kp = kd = 0)
  double position_rev = 0;    // PD target position, motor revolutions
  double velocity_rev_s = 0;  // PD target velocity, rev/s
  double kp = 0;              // A per rev
  double kd = 0;              // A per (rev/s)

  static MotorCommand current(double amperes) noexcept { return {amperes, 0, 0, 0, 0}; }
  static MotorCommand pd(double position_rev, double velocity_rev_s, double kp, double kd, double feed_forward_a = 0) noexcept {
    return {feed_forward_a, position_rev, velocity_rev_s, kp, kd};
  }
};
using Command = std::array<MotorCommand, 2>;

// The user's control law. It runs on the real-time thread once per cycle and must not allocate,
// lock, throw, log, print or do I/O (an exception ends the process: the loop calls it noexcept).
// Anything it captures is shared with the caller's thread only through atomics. A motor that is
// not in use gets zero current whatever the law says.
using ControlLaw = std::function<Command(const ControlState&)>;

struct ControlSettings {
  host::SafetyLimits limits;  // per cycle: faults, velocity limit, current clamp (safety.hpp);
                              // its `motors` is narrowed to MotorBoardOptions::motors
  std::chrono::microseconds period = 1000us;  // 1 kHz; at most 10 kHz and under recv_timeout_ms
  bool realtime = true;                       // ask for SCHED_FIFO and mlockall (refusals are logged)
  std::vector<int> cpus;                      // pin the loop thread (empty: no pinning)
  bool pace_measurements = false;             // start a cycle when the board's data burst arrived
  std::chrono::milliseconds refresh = 10ms;   // how often the event-loop thread drains the records
  std::string csv;                            // write one line per cycle to this file (host::CycleCsv)
};

// Why a control run ended.
enum class ControlEnd : std::uint8_t {
  requested,        // its duration passed, or stop_control() / disable() / the destructor
  fault,            // a safety stop (ControlReport::fault)
  no_first_action,  // a FrontEnd's first action did not come in time: the motors were disabled
};
const char* to_string(ControlEnd e) noexcept;

// What a FrontEnd's back end (front_end.hpp) did in a run; zeros for a plain ControlLaw.
struct ActionStats {
  std::uint64_t cycles = 0;          // cycles the back end ran
  std::uint64_t actions = 0;         // distinct actions it applied (a faster front end overwrites some)
  std::uint64_t idle_cycles = 0;     // cycles with the idle action (waiting, stale or gave up)
  std::uint64_t stale_cycles = 0;    // idle because the latest action was older than stale_after
  std::uint64_t stale_episodes = 0;  // times the action went stale
  double first_action_s = -1;        // when it first took an action, since the start (-1: never)
};

// A control run's timing as it goes, from the loop's records as the event-loop thread drains them
// (at most ControlSettings::refresh behind the loop; nothing is added to the real-time cycle).
// ControlReport::stats gives the exact figures, percentiles included, at the end.
struct LoopFigures {
  std::uint64_t cycles = 0;
  std::uint64_t overruns = 0;  // cycles that ended after the next one was due
  double period_max_s = 0;     // longest start-to-start period
  double jitter_max_s = 0;     // largest |period - the nominal period|
  double compute_max_s = 0;    // longest cycle, start to end
  bool running = false;        // the run has not ended
};

struct ControlReport {
  host::LoopStats stats;            // cycles, period, jitter, overruns, missed deadlines
  std::optional<host::Fault> fault; // the safety stop that ended the loop, if any
  std::string fault_text;           // its description, e.g. "stale data: no velocity frame for ..."
  std::uint64_t csv_lines = 0;
  ControlEnd end = ControlEnd::requested;
  ActionStats actions;              // with a FrontEnd
};

struct HomingReport {
  ControlReport control;
  std::array<host::MotorHoming, 2> motors{};  // index_rev: each found motor's offset
  bool all_found = false;
};

class FrontEnd;  // front_end.hpp

class MotorBoard {
 public:
  // Opens the bus (a spec as can::parse_bus_spec reads it: socketcan:can0,
  // socketcand://HOST:PORT/CHANNEL, cannet://HOST/N) and starts decoding the board's frames.
  explicit MotorBoard(const std::string& bus_spec, MotorBoardOptions options = {});
  ~MotorBoard();
  MotorBoard(const MotorBoard&) = delete;
  MotorBoard& operator=(const MotorBoard&) = delete;
  // A moved-from MotorBoard may only be destroyed or assigned to.
  MotorBoard(MotorBoard&&) noexcept;
  MotorBoard& operator=(MotorBoard&&) noexcept;

  // Zero currents, ENABLE_SYS, SEND_ALL, ENABLE_MTRx, then waits until the motors are aligned and
  // ready. On failure the board is disabled again before the exception leaves.
  void enable();
  // Stops control if it runs, then IqRef = 0, ENABLE_MTR1/2 = 0, ENABLE_SYS = 0.
  void disable();
  [[nodiscard]] bool enabled() const noexcept;
  // After the board disabled itself on an error (a safety stop naming a board error): the spec's
  // recovery, ENABLE_SYS=1, IqRef=0, ENABLE_MTRx=1, then waits until ready. Throws
  // HostErrc::board_error while the error's cause remains (the motors stay off), or not_ready.
  void recover();

  // The next status frame (HostErrc::timeout after status_timeout).
  protocol::Status wait_status();
  // The latest measurements: decoded frames, or during control the latest cycle's (then without
  // time stamps; at most ControlSettings::refresh old).
  host::Measurements measurements();

  // Starts the real-time loop with `law` (the motors must be enabled: HostErrc::not_enabled
  // otherwise; settings are checked first: HostErrc::invalid_argument). Returns once the loop runs.
  void start_control(ControlLaw law, ControlSettings settings = {});
  // False once the loop ended by itself (a safety stop) or was never started.
  [[nodiscard]] bool control_running();
  // The current run's figures so far; after stop_control, the last run's; zeros before any.
  [[nodiscard]] LoopFigures loop_figures();
  // Stops the loop (its last frame is IqRef = 0) and tells how it went. The motors stay enabled
  // (at zero current) unless a fault disabled them; disable() or the destructor turns them off.
  ControlReport stop_control();
  // start_control, wait `duration` (or until a safety stop), stop_control.
  ControlReport run_control(ControlLaw law, std::chrono::milliseconds duration, ControlSettings settings = {});
  // The same with a FrontEnd's back end as the law (front_end.hpp; the board keeps a copy of the
  // handle). The run also ends when the front end gives up (no first action in time): then the
  // motors are disabled at once and the report says ControlEnd::no_first_action.
  void start_control(const FrontEnd& front_end, ControlSettings settings = {});
  ControlReport run_control(const FrontEnd& front_end, std::chrono::milliseconds duration, ControlSettings settings = {});

  // Homing on the encoder index (host::HomingController under the same loop and safety), for
  // the motors in options.motors that the board uses. The motors must be enabled.
  HomingReport home(host::HomingOptions options = {}, ControlSettings settings = {},
                    std::chrono::milliseconds timeout = 20s);

  // The board's own controller and switches, for work without the host in the loop: the optional
  // on-board P/D controller (gains, references, its current limits), the rollover error and the
  // virtual springs. host/onboard.hpp says what the board does with them, their units (the spec's:
  // A/rev, A/krpm, rev, krpm, A) and why a position reference must lie on the counter's current
  // turn. Each call checks its values before anything is sent (HostErrc::invalid_argument, in
  // words), sends the frames and returns; HostErrc::cyclic_active while control runs. After one of
  // the controller or spring calls, disable() also sets the controller's limits to 0 and the
  // springs off, so that the next enable does not chase an old reference. The controller is absent
  // from the firmware in service: such a board ignores these frames (the rollover error and the
  // springs it has).
  void set_onboard_gains(const host::OnboardGains& gains);
  void set_onboard_references(const host::OnboardReferences& references);
  void set_onboard_current_limits(const host::OnboardCurrentLimits& limits);
  // On: the board raises POS_ROLLOVER and disables itself when a motor's position counter rolls
  // over at +-100 rev (off after power-up, as the spec's default).
  void set_rollover_error(bool on);
  void set_virtual_springs(std::array<bool, 2> on);  // index 0 = motor 1

  // From any thread: the wait in progress (enable, wait_status, home) ends with
  // HostErrc::interrupted, and so do later ones until clear_interrupt().
  void interrupt();
  void clear_interrupt();

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace axon::blmc
