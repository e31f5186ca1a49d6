// web::C4gSimView: the c4g simulator page's data (`axon sim c4g --http`): the simulated
// controller's own truth, not what a PC server believes. Per arm the joints at the link and their
// targets [deg], the drives, and the open mode the robot program's GO OPEN asked for; per open axis
// the mode it is in and the mode the PC's last reply asked for, the motor position, target and
// current; the program's step; the packets sent and the PC's replies judged (in time, late, missed,
// wrong number / size, malformed), the misses in a row that lead to the communication error; the
// round trip; the controller's events (ERR_C4GOPEN_* by the manual's names, mode changes, steps).
//
// Where the data comes from: c4g::sim::LiveState snapshots and LiveEvent records that the
// controller's thread queues lock-free (SimulatedController::take_live); the owner hands them in
// with update() and add_event() on its own thread. Nothing here reads the controller itself.
//
// Threading: one thread (the owner's); throws nothing but std::bad_alloc.
#pragma once

#include "axon/c4g/sim/live_state.hpp"
#include "axon/web/source.hpp"

#include <memory>
#include <string>
#include <vector>

namespace axon::web {

struct C4gSimViewOptions {
  std::string command;               // what the process runs ("sim c4g --robot six-axis")
  std::string robot;                 // the robot's name
  std::string program;               // the robot program's name
  std::string server;                // the PC server it talks to
  int period_ms = 2;
  std::vector<std::string> steps;    // the program's steps in words (SimulatedController::program_steps)
  std::size_t event_log = 60;        // the last events kept for the page
};

class C4gSimView {
 public:
  explicit C4gSimView(C4gSimViewOptions options);
  ~C4gSimView();
  C4gSimView(const C4gSimView&) = delete;
  C4gSimView& operator=(const C4gSimView&) = delete;

  // The latest snapshot; `dropped`: snapshots and events the controller could not queue so far.
  void update(const c4g::sim::LiveState& state, std::uint64_t dropped = 0);
  // Each event, in order.
  void add_event(const c4g::sim::LiveEvent& event);

  // What does not change: {family, view: "simulator", command, robot, program, server, period_ms,
  // steps: [...], modes: [...]}.
  [[nodiscard]] std::string info_json() const;
  // {t_s, time_s, phase, ended, communication_error, scenario: {...}, arms: [...], axes: [...],
  // counters: {...}, rtt: {...}, events_seen, events_dropped, events: [...]} (docs/dashboard.md).
  [[nodiscard]] std::string state_json() const;
  // Prometheus text: axon_c4g_sim_* (docs/dashboard.md).
  [[nodiscard]] std::string metrics() const;

  // The state to `source`; the metrics too every `metrics_every`-th call.
  void publish(Source& source, unsigned metrics_every = 10);

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace axon::web
