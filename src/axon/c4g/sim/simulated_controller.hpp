// A simulated C4G controller with a blocking face: start it against a PC server's address with a
// robot program, it plays the program on a thread of its own (the open interface's UDP exchange,
// one packet per period, as `axon sim c4g` does), and afterwards tells what it saw.
//
//   auto sim = axon::c4g::sim::SimulatedController::start({.server = "127.0.0.1:11000", .scenario_yaml = yaml});
//   auto report = sim.wait();             // until the program ends (or the run's duration)
//   report.stats.misses == 0 ...          // every cycle answered
//
// Lifetime: start() opens the socket and starts the thread; wait() blocks until the run ends
// (with a timeout: wait_for); stop() ends it early. The destructor stops and joins; it never
// throws. The report is a plain value, valid once the run has ended.
// Errors: start() throws axon::Exception (its Error carries the std::error_code: a bad robot name
// or scenario CoreErrc::invalid_argument, a socket failure the system's errno) naming the cause.
// Events: in the report once the run ended, and live through the options' on_event (its thread).
// Live state (a page beside the run): with live_period_s > 0 the controller's thread copies its
// state (live_state.hpp) into a lock-free queue every that many seconds, and its events too;
// take_live() hands them to one other thread.
#pragma once

#include "axon/c4g/protocol/packet.hpp"
#include "axon/c4g/sim/controller.hpp"
#include "axon/c4g/sim/events.hpp"
#include "axon/c4g/sim/live_state.hpp"
#include "axon/c4g/sim/reply_window.hpp"
#include "axon/c4g/sim/robots.hpp"

#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace axon::c4g::sim {

struct SimulatedControllerOptions {
  std::string server = "127.0.0.1:11000";  // the PC server, HOST[:PORT] (a host alone: port 1000)
  std::string bind{};                      // the controller's local HOST:PORT (empty: any)
  std::string robot = "six-axis";          // robots.hpp: a name, or a robot file (robot_file.hpp)
  // The robot program (scenario.hpp): YAML text, or a file; neither: the default program.
  std::string scenario_yaml{};
  std::string scenario_file{};
  ControllerOptions controller{};         // numbering, sync packets, period...
  double duration_s = 0;                   // 0: until the program ends
  // How long after each send a reply may come (reply_window.hpp): the manual's 500 us by default;
  // ReplyWindow::period is the lenient whole period for slow or loaded machines; reply_deadline > 0
  // sets the window outright.
  ReplyWindow reply_window = ReplyWindow::manual;
  std::chrono::nanoseconds reply_deadline{0};
  // Soft control switching, overriding the robot's (negative: the robot's own).
  double switch_t1_s = -1, switch_t2_s = -1, switch_t3_s = -1;
  double switch_tolerance = -1;  // [motor turns]
  bool pc_reduces_current = false;  // the PC scales its current while switching, not the controller
  // Called for each event as it happens, on the controller's thread (between ticks: keep it short).
  std::function<void(const Event&)> on_event{};
  // A live snapshot for take_live() every this many seconds of the controller's ticks (0: none).
  double live_period_s = 0;
};

// What the controller saw, once the run ended.
struct SimulatedControllerReport {
  enum class Outcome { completed, communication_error, scenario_error, incomplete };
  Outcome outcome = Outcome::incomplete;
  std::string outcome_text;   // "completed", "communication error", "scenario error: ...", "scenario incomplete"
  std::string robot;
  int period_ms = 0;
  ControllerStats stats;      // packets, replies, misses by kind
  std::uint64_t overruns = 0; // ticks more than a period late
  double reply_window_us = 0; // the window the replies were held to
  double elapsed_s = 0;
  bool stopped = false;       // ended by stop() or the duration rather than by the program
  // Round-trip times of the accepted replies [us].
  std::uint64_t rtt_count = 0;
  double rtt_min_us = 0, rtt_mean_us = 0, rtt_p50_us = 0, rtt_p99_us = 0, rtt_p999_us = 0, rtt_max_us = 0;
  std::vector<Event> events;  // in order
  // Joint positions of each arm at the end [deg, link side] (index 0 unused; empty: no such arm).
  std::vector<std::vector<double>> joint_degrees;
  // The exit code `axon sim c4g` gives for this outcome (exit_codes: 0, 1 failed, 4 safety stop).
  [[nodiscard]] int exit_code() const noexcept;
};

class SimulatedController {
 public:
  // Builds the controller, opens its socket and starts playing on a thread of its own.
  static SimulatedController start(SimulatedControllerOptions options);
  SimulatedController(SimulatedController&&) noexcept;
  SimulatedController& operator=(SimulatedController&&) noexcept;
  ~SimulatedController();  // stop(); never throws

  // Blocks until the run ends; returns the report.
  SimulatedControllerReport wait();
  // Blocks until the run ends or the timeout passes; nullopt on the timeout (the run goes on).
  std::optional<SimulatedControllerReport> wait_for(std::chrono::nanoseconds timeout);
  // Ends the run (as Ctrl-C ends `axon sim c4g`) and returns the report. Idempotent.
  SimulatedControllerReport stop();
  [[nodiscard]] bool running() const noexcept;
  // The controller's local address, e.g. "127.0.0.1:40211".
  [[nodiscard]] std::string local_address() const;
  // One line: robot, open axes, period, program, server and local address.
  [[nodiscard]] std::string describe() const;
  // The program's steps in words ("go_open (program.yaml:4:5)"), in order.
  [[nodiscard]] std::vector<std::string> program_steps() const;
  [[nodiscard]] const RobotConfig& robot() const noexcept;

  // With options.live_period_s > 0: what the controller's thread queued since the last call, the
  // latest snapshot into `state` (true when there was one; the last one a run takes has ended set)
  // and each event, in order, to `on_event`. One thread only may call it; it may go on after the
  // run ended, until the queues are empty. Without live_period_s: false, nothing.
  bool take_live(LiveState& state, const std::function<void(const LiveEvent&)>& on_event = {});
  // Snapshots and events the controller's thread could not queue (the reader was too slow).
  [[nodiscard]] std::uint64_t live_dropped() const noexcept;

 private:
  struct Impl;
  explicit SimulatedController(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

}  // namespace axon::c4g::sim
