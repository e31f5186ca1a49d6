// axon.blmc: a motor driver board (blmc::MotorBoard) with the control loop split into a Python
// front end and the C++ back end (blmc::FrontEnd: the 1 kHz law stays on its real-time thread and
// never calls into Python), and the board simulated in this process (blmc::sim::SimulatedBoard).
// Every blocking call releases the GIL; Ctrl-C ends it, disables the motors and raises
// KeyboardInterrupt.
#include "bindings.hpp"

#include "axon/blmc/host/error.hpp"
#include "axon/blmc/host/front_end.hpp"
#include "axon/blmc/host/motor_board.hpp"
#include "axon/blmc/sim/simulated_board.hpp"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <cmath>
#include <optional>

namespace axon::python {

namespace {

using blmc::ControlReport;
using blmc::FrontEnd;
using blmc::MotorBoard;
using blmc::host::HostErrc;
using Pair = std::array<double, 2>;

[[noreturn]] void invalid(const std::string& text) { throw Exception(Error(HostErrc::invalid_argument, text)); }

// Seconds from Python as a duration (finite, >= 0, or > 0 when `positive`).
template <class D>
D duration_of(double seconds, const char* what, bool positive = true) {
  if (!std::isfinite(seconds) || seconds < 0 || (positive && seconds == 0))
    invalid(fmt::format("{} must be a number of seconds {} 0, got {}", what, positive ? ">" : ">=", seconds));
  return std::chrono::duration_cast<D>(std::chrono::duration<double>(seconds));
}

// One value per motor from any sequence or array of two numbers.
Pair pair_of(const py::object& values, const char* what) {
  const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(values);
  if (!a || a.ndim() != 1 || a.size() != 2)
    invalid(fmt::format("{}: one number per motor, two in all (a sequence or array)", what));
  return {a.at(0), a.at(1)};
}

py::array_t<double> array_of(const Pair& p) { return py::array_t<double>(2, p.data()); }
blmc::protocol::MotorPair motor_pair(const Pair& p) { return {p[0], p[1]}; }

// A MotorBoard as Python holds it: closable (the destructor disables), with the front end of the
// latest run.
struct Board {
  std::unique_ptr<MotorBoard> board;
  std::optional<FrontEnd> front_end;

  MotorBoard& get() {
    if (!board) throw Exception(Error(HostErrc::closed, "blmc: the board was closed"));
    return *board;
  }
  FrontEnd& running(const char* what) {
    if (!front_end || !get().control_running())
      throw Exception(Error(HostErrc::not_cyclic, fmt::format("blmc: {}: no control running (start() first)", what)));
    return *front_end;
  }
  void close() {
    py::gil_scoped_release release;
    board.reset();  // stops control, disables, closes the bus
  }
};

// A blocking board call from Python (GIL released). Ctrl-C interrupts the board's wait (and calls
// `also`), then the motors are disabled before KeyboardInterrupt leaves.
template <class F>
auto guarded(Board& b, F call, const std::function<void()>& also = {}) {
  MotorBoard& m = b.get();
  try {
    return interruptible(std::move(call), [&m, &also] {
      if (also) also();
      m.interrupt();
    });
  } catch (py::error_already_set&) {
    py::gil_scoped_release release;
    try {
      m.clear_interrupt();
      m.disable();
    } catch (const std::exception& e) {
      spdlog::error("blmc: disabling the board after the interrupt: {}", e.what());
    }
    throw;
  }
}

// The latest decoded measurements of a board, in the units of ControlState.
struct Measurements {
  Pair position_rev{}, velocity_rev_s{}, current_a{}, adc{};
  std::optional<blmc::protocol::Status> status;
  std::uint64_t frames = 0;
};

Measurements measurements_of(const blmc::host::Measurements& m) {
  Measurements out;
  out.position_rev = {m.position.value.motor1, m.position.value.motor2};
  out.velocity_rev_s = {blmc::host::krpm_to_rev_per_s(m.velocity.value.motor1), blmc::host::krpm_to_rev_per_s(m.velocity.value.motor2)};
  out.current_a = {m.current.value.motor1, m.current.value.motor2};
  out.adc = {m.adc.value.motor1, m.adc.value.motor2};
  if (m.status.received()) out.status = m.status.value;
  out.frames = m.frames;
  return out;
}

double seconds(core::Duration d) { return std::chrono::duration<double>(d).count(); }

void bind_values(py::module_& m) {
  using blmc::protocol::Status;
  py::class_<Status>(m, "Status", "The board's status frame: switches, readiness and its error code.")
      .def_readonly("system_enabled", &Status::system_enabled)
      .def_property_readonly("motor_enabled", [](const Status& s) { return std::array<bool, 2>{s.motor1_enabled, s.motor2_enabled}; })
      .def_property_readonly("motor_ready", [](const Status& s) { return std::array<bool, 2>{s.motor1_ready, s.motor2_ready}; },
                             "(motor 1, motor 2): aligned (the first enable after power-up aligns them).")
      .def_property_readonly("error", [](const Status& s) { return std::string(blmc::protocol::name(s.error)); },
                             "The board's error code: NONE, ENCODER, CAN_RECV_TIMEOUT, POS_CONVERTER, POS_ROLLOVER, OTHER ...")
      .def("__repr__", [](const Status& s) { return fmt::format("Status({})", s.to_string()); });
  py::class_<Measurements>(m, "Measurements", "The latest measurements: one value per motor as numpy arrays.")
      .def_property_readonly("position_rev", [](const Measurements& x) { return array_of(x.position_rev); })
      .def_property_readonly("velocity_rev_s", [](const Measurements& x) { return array_of(x.velocity_rev_s); })
      .def_property_readonly("current_a", [](const Measurements& x) { return array_of(x.current_a); })
      .def_property_readonly("adc", [](const Measurements& x) { return array_of(x.adc); }, "0..1")
      .def_readonly("status", &Measurements::status, "The latest Status, None before the first.")
      .def_readonly("frames", &Measurements::frames)
      .def("__repr__", [](const Measurements& x) {
        return fmt::format("Measurements(position_rev=[{:.4f}, {:.4f}], velocity_rev_s=[{:.3f}, {:.3f}], current_a=[{:.3f}, {:.3f}])",
                           x.position_rev[0], x.position_rev[1], x.velocity_rev_s[0], x.velocity_rev_s[1], x.current_a[0], x.current_a[1]);
      });
  using blmc::ControlState;
  py::class_<ControlState>(m, "ControlState", "What the back end saw in its latest cycle (revolutions, seconds, amperes).")
      .def_readonly("cycle", &ControlState::cycle)
      .def_readonly("time_s", &ControlState::time_s, "Since the loop started.")
      .def_readonly("dt_s", &ControlState::dt_s)
      .def_property_readonly("position_rev", [](const ControlState& s) { return array_of(s.position_rev); })
      .def_property_readonly("velocity_rev_s", [](const ControlState& s) { return array_of(s.velocity_rev_s); })
      .def_property_readonly("current_a", [](const ControlState& s) { return array_of(s.current_a); })
      .def_property_readonly("adc", [](const ControlState& s) { return array_of(s.adc); })
      .def_readonly("status", &ControlState::status)
      .def("__repr__", [](const ControlState& s) {
        return fmt::format("ControlState(cycle={}, time_s={:.3f}, position_rev=[{:.4f}, {:.4f}], current_a=[{:.3f}, {:.3f}])", s.cycle,
                           s.time_s, s.position_rev[0], s.position_rev[1], s.current_a[0], s.current_a[1]);
      });
  using blmc::MotorCommand;
  py::class_<MotorCommand>(m, "MotorCommand", "One motor's action: current_a + kp (position_rev - x) + kd (velocity_rev_s - v).")
      .def_readonly("current_a", &MotorCommand::current_a)
      .def_readonly("position_rev", &MotorCommand::position_rev)
      .def_readonly("velocity_rev_s", &MotorCommand::velocity_rev_s)
      .def_readonly("kp", &MotorCommand::kp, "A/rev")
      .def_readonly("kd", &MotorCommand::kd, "A/(rev/s)")
      .def("__repr__", [](const MotorCommand& c) {
        return fmt::format("MotorCommand(current_a={:g}, position_rev={:g}, velocity_rev_s={:g}, kp={:g}, kd={:g})", c.current_a,
                           c.position_rev, c.velocity_rev_s, c.kp, c.kd);
      });
  using blmc::AppliedAction;
  py::class_<AppliedAction>(m, "AppliedAction", "What the back end applied in its latest cycle (before the safety clamp).")
      .def_readonly("cycle", &AppliedAction::cycle)
      .def_readonly("time_s", &AppliedAction::time_s)
      .def_readonly("command", &AppliedAction::command, "(MotorCommand, MotorCommand)")
      .def_property_readonly("current_a", [](const AppliedAction& a) { return array_of(Pair{a.command[0].current_a, a.command[1].current_a}); },
                             "The commands' current terms (the whole command without PD gains).")
      .def_property_readonly("source", [](const AppliedAction& a) { return std::string(blmc::to_string(a.source)); },
                             "'action' (the latest set_*), or idle: 'waiting' (none yet), 'stale', 'gave_up'.")
      .def_property_readonly("idle", [](const AppliedAction& a) { return a.source != blmc::ActionSource::action; })
      .def_readonly("action", &AppliedAction::action, "The latest set_* call taken (counting from 1; 0: none); applied when source is 'action'.")
      .def_readonly("age_s", &AppliedAction::age_s)
      .def("__repr__", [](const AppliedAction& a) {
        return fmt::format("AppliedAction(cycle={}, source='{}', action={}, current_a=[{:g}, {:g}], age_s={:.3f})", a.cycle,
                           blmc::to_string(a.source), a.action, a.command[0].current_a, a.command[1].current_a, a.age_s);
      });
}

void bind_report(py::module_& m) {
  using blmc::host::LoopStats;
  py::class_<LoopStats>(m, "LoopStats", "The loop's timing (seconds).")
      .def_readonly("cycles", &LoopStats::cycles)
      .def_readonly("overruns", &LoopStats::overruns, "Cycles that ended after the next cycle's deadline.")
      .def_readonly("missed", &LoopStats::missed, "Deadlines skipped to catch up.")
      .def_property_readonly("period_mean_s", [](const LoopStats& s) { return seconds(s.period_mean); })
      .def_property_readonly("period_max_s", [](const LoopStats& s) { return seconds(s.period_max); })
      .def_property_readonly("jitter_p50_s", [](const LoopStats& s) { return seconds(s.jitter_p50); })
      .def_property_readonly("jitter_p99_s", [](const LoopStats& s) { return seconds(s.jitter_p99); })
      .def_property_readonly("jitter_max_s", [](const LoopStats& s) { return seconds(s.jitter_max); })
      .def_property_readonly("compute_max_s", [](const LoopStats& s) { return seconds(s.compute_max); });
  using blmc::ActionStats;
  py::class_<ActionStats>(m, "ActionStats", "What the back end did with the front end's actions.")
      .def_readonly("cycles", &ActionStats::cycles)
      .def_readonly("actions", &ActionStats::actions, "Distinct actions applied.")
      .def_readonly("idle_cycles", &ActionStats::idle_cycles, "Cycles with zero current: waiting, stale or gave up.")
      .def_readonly("stale_cycles", &ActionStats::stale_cycles)
      .def_readonly("stale_episodes", &ActionStats::stale_episodes)
      .def_readonly("first_action_s", &ActionStats::first_action_s, "-1: no action came.")
      .def("__repr__", [](const ActionStats& a) {
        return fmt::format("ActionStats(cycles={}, actions={}, idle_cycles={}, stale_cycles={}, stale_episodes={})", a.cycles, a.actions,
                           a.idle_cycles, a.stale_cycles, a.stale_episodes);
      });
  using blmc::LoopFigures;
  py::class_<LoopFigures>(m, "LoopFigures",
                          "The control run's timing so far (seconds), from the loop's records as they are drained "
                          "(at most 10 ms behind); ControlReport.stats has the exact figures at the end.")
      .def_readonly("cycles", &LoopFigures::cycles)
      .def_readonly("overruns", &LoopFigures::overruns, "Cycles that ended after the next cycle's deadline.")
      .def_readonly("period_max_s", &LoopFigures::period_max_s)
      .def_readonly("jitter_max_s", &LoopFigures::jitter_max_s, "Largest |period - nominal period|.")
      .def_readonly("compute_max_s", &LoopFigures::compute_max_s)
      .def_readonly("running", &LoopFigures::running, "The run has not ended.")
      .def("__repr__", [](const LoopFigures& f) {
        return fmt::format("LoopFigures(cycles={}, overruns={}, jitter_max_us={:.0f}, running={})", f.cycles, f.overruns,
                           f.jitter_max_s * 1e6, f.running ? "True" : "False");
      });
  py::class_<ControlReport>(m, "ControlReport", "How a control run went.")
      .def_readonly("stats", &ControlReport::stats)
      .def_property_readonly("cycles", [](const ControlReport& r) { return r.stats.cycles; })
      .def_property_readonly("overruns", [](const ControlReport& r) { return r.stats.overruns; })
      .def_property_readonly("end", [](const ControlReport& r) { return std::string(blmc::to_string(r.end)); },
                             "'requested' (time or stop()), 'fault' (a safety stop), 'no_first_action' (motors disabled).")
      .def_property_readonly("fault", [](const ControlReport& r) -> std::optional<std::string> {
        if (!r.fault) return std::nullopt;
        return std::string(blmc::host::to_string(r.fault->kind));
      }, "The safety stop's kind ('board error', 'stale data' ...; fault_text says more), None without one.")
      .def_readonly("fault_text", &ControlReport::fault_text)
      .def_readonly("actions", &ControlReport::actions)
      .def_readonly("csv_lines", &ControlReport::csv_lines)
      .def("__repr__", [](const ControlReport& r) {
        return fmt::format("ControlReport(end='{}', cycles={}, overruns={}, missed={}, jitter_p99_us={:.0f}, fault={}, actions={})",
                           blmc::to_string(r.end), r.stats.cycles, r.stats.overruns, r.stats.missed, seconds(r.stats.jitter_p99) * 1e6,
                           r.fault ? fmt::format("'{}'", r.fault_text) : "None", r.actions.actions);
      });
}

std::unique_ptr<Board> open_board(const std::string& spec, const std::string& name, std::array<bool, 2> motors,
                                  double connect_timeout_s, double ready_timeout_s, double status_timeout_s, std::uint32_t recv_timeout_ms) {
  blmc::MotorBoardOptions o;
  o.name = name;
  o.motors = motors;
  o.connect_timeout = duration_of<std::chrono::milliseconds>(connect_timeout_s, "connect_timeout_s");
  o.ready_timeout = duration_of<std::chrono::milliseconds>(ready_timeout_s, "ready_timeout_s");
  o.status_timeout = duration_of<std::chrono::milliseconds>(status_timeout_s, "status_timeout_s");
  o.recv_timeout_ms = recv_timeout_ms;
  auto b = std::make_unique<Board>();
  py::gil_scoped_release release;  // bounded by connect_timeout_s
  b->board = std::make_unique<MotorBoard>(spec, o);
  return b;
}

struct StartArgs {
  double max_current_a, max_velocity_krpm, stale_data_s, first_action_timeout_s, stale_after_s, period_s;
  bool realtime;
  std::string csv;
};

void start(Board& b, const StartArgs& a) {
  blmc::ControlSettings s;
  s.limits.max_current_a = a.max_current_a;
  s.limits.max_velocity_krpm = a.max_velocity_krpm;
  s.limits.stale_after = duration_of<core::Duration>(a.stale_data_s, "stale_data_s");
  s.period = duration_of<std::chrono::microseconds>(a.period_s, "period_s");
  s.realtime = a.realtime;
  s.csv = a.csv;
  FrontEnd fe({duration_of<std::chrono::milliseconds>(a.first_action_timeout_s, "first_action_timeout_s"),
               duration_of<std::chrono::milliseconds>(a.stale_after_s, "stale_after_s")});
  auto& m = b.get();
  guarded(b, [&m, &fe, &s] { m.start_control(fe, s); });
  b.front_end = fe;
}

// Waits until the run ends by itself or `duration_s` passed (Ctrl-C: the motors are disabled).
void wait_control(Board& b, double duration_s) {
  auto& m = b.get();
  const auto end = std::chrono::steady_clock::now() + duration_of<std::chrono::milliseconds>(duration_s, "duration_s", false);
  auto quit = std::make_shared<std::atomic<bool>>(false);
  guarded(b, [&m, quit, end] {
    while (!*quit && m.control_running() && std::chrono::steady_clock::now() < end) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }, [quit] { *quit = true; });
}

// set_pd's gains: (kp, kd) for both motors, or [[kp1, kd1], [kp2, kd2]].
std::array<Pair, 2> gains_of(const py::object& gains) {
  const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(gains);
  if (a && a.ndim() == 1 && a.size() == 2) return {Pair{a.at(0), a.at(1)}, Pair{a.at(0), a.at(1)}};
  if (a && a.ndim() == 2 && a.shape(0) == 2 && a.shape(1) == 2) return {Pair{a.at(0, 0), a.at(0, 1)}, Pair{a.at(1, 0), a.at(1, 1)}};
  invalid("set_pd: gains are (kp, kd) for both motors or [[kp1, kd1], [kp2, kd2]] (A/rev, A per rev/s)");
}

void set_pd(Board& b, const py::object& targets, const py::object& gains, const py::object& velocities, const py::object& feed_forward) {
  auto& fe = b.running("set_pd");
  const auto pos = pair_of(targets, "set_pd: targets (rev)");
  const auto g = gains_of(gains);
  const auto vel = velocities.is_none() ? Pair{} : pair_of(velocities, "set_pd: velocities_rev_s");
  const auto ff = feed_forward.is_none() ? Pair{} : pair_of(feed_forward, "set_pd: feed_forward_a");
  blmc::Command c;
  for (std::size_t k = 0; k < 2; ++k) c[k] = blmc::MotorCommand::pd(pos[k], vel[k], g[k][0], g[k][1], ff[k]);
  fe.set(c);
}

FrontEnd& last_front_end(Board& b) {
  if (!b.front_end) throw Exception(Error(HostErrc::not_cyclic, "blmc: no control run yet (start() first)"));
  return *b.front_end;
}

void bind_board_control(py::class_<Board>& c) {
  c.def("start", [](Board& b, double max_current_a, double max_velocity_krpm, double stale_data_s, double first_action_timeout_s,
                    double stale_after_s, double period_s, bool realtime, const std::string& csv) {
         start(b, {max_current_a, max_velocity_krpm, stale_data_s, first_action_timeout_s, stale_after_s, period_s, realtime, csv});
       }, py::kw_only(), py::arg("max_current_a") = 2.0, py::arg("max_velocity_krpm") = 2.0, py::arg("stale_data_s") = 0.01,
       py::arg("first_action_timeout_s") = 1.0, py::arg("stale_after_s") = 0.1, py::arg("period_s") = 0.001, py::arg("realtime") = true,
       py::arg("csv") = "",
       "Starts the 1 kHz loop (motors enabled first) with the front end's back end as the law; returns once it runs. Until the "
       "first set_* and while the latest is older than stale_after_s the motors get zero current; no action within "
       "first_action_timeout_s ends the run with the motors disabled. Currents are clamped to max_current_a.")
      .def("set_currents", [](Board& b, const py::object& amperes) { b.running("set_currents").set_currents(pair_of(amperes, "set_currents (A)")); },
           py::arg("amperes"), "The next action: these currents (A), one per motor.")
      .def("set_pd", &set_pd, py::arg("targets"), py::arg("gains"), py::kw_only(), py::arg("velocities_rev_s") = py::none(),
           py::arg("feed_forward_a") = py::none(),
           "The next action: PD towards targets (rev) with gains (kp A/rev, kd A per rev/s), evaluated every cycle.")
      .def_property_readonly("applied", [](Board& b) { return last_front_end(b).applied(); }, "AppliedAction of the latest cycle.")
      .def_property_readonly("state", [](Board& b) { return last_front_end(b).state(); }, "ControlState of the latest cycle.")
      .def_property_readonly("running", [](Board& b) { return b.get().control_running(); })
      .def_property_readonly("loop", [](Board& b) { return b.get().loop_figures(); },
                             "LoopFigures of the run going on (cycles, overruns, jitter so far); after stop(), the last run's.")
      .def("_wait_control", &wait_control, py::arg("duration_s"))
      .def("stop", [](Board& b) {
        auto& m = b.get();
        return guarded(b, [&m] { return m.stop_control(); });
      }, "Stops the loop (its last frame is zero current) and returns the ControlReport; the motors stay enabled.");
}

void bind_board_onboard(py::class_<Board>& c) {
  c.def("set_onboard_gains", [](Board& b, const py::object& kp, const py::object& kd) {
         const blmc::host::OnboardGains g{motor_pair(pair_of(kp, "kp_a_per_rev")), motor_pair(pair_of(kd, "kd_a_per_krpm"))};
         auto& m = b.get();
         guarded(b, [&m, g] { m.set_onboard_gains(g); });
       }, py::arg("kp_a_per_rev"), py::arg("kd_a_per_krpm"), "The board's own P/D controller gains, per motor.")
      .def("set_onboard_references", [](Board& b, const py::object& pos, const py::object& vel) {
         const blmc::host::OnboardReferences r{motor_pair(pair_of(pos, "position_rev")),
                                               vel.is_none() ? blmc::protocol::MotorPair{} : motor_pair(pair_of(vel, "velocity_krpm"))};
         auto& m = b.get();
         guarded(b, [&m, r] { m.set_onboard_references(r); });
       }, py::arg("position_rev"), py::arg("velocity_krpm") = py::none())
      .def("set_onboard_current_limits", [](Board& b, const py::object& p, const py::object& d) {
         const blmc::host::OnboardCurrentLimits l{motor_pair(pair_of(p, "p_a")), motor_pair(pair_of(d, "d_a"))};
         auto& m = b.get();
         guarded(b, [&m, l] { m.set_onboard_current_limits(l); });
       }, py::arg("p_a"), py::arg("d_a"), "Bounds (A) of the on-board controller's P and D terms (0: off).")
      .def("set_rollover_error", [](Board& b, bool on) {
         auto& m = b.get();
         guarded(b, [&m, on] { m.set_rollover_error(on); });
       }, py::arg("on"))
      .def("set_virtual_springs", [](Board& b, std::array<bool, 2> on) {
         auto& m = b.get();
         guarded(b, [&m, on] { m.set_virtual_springs(on); });
       }, py::arg("on"));
}

// Homing on the encoder index (MotorBoard::home): the motors must be enabled.
struct HomeArgs {
  double speed_rev_s, kp, kd, max_current_a, max_travel_rev, timeout_s, max_velocity_krpm, stale_data_s;
  std::array<bool, 2> motors;
  bool realtime;
};

blmc::HomingReport home(Board& b, const HomeArgs& a) {
  blmc::host::HomingOptions o;
  o.motors = a.motors;
  o.speed_rev_s = a.speed_rev_s;
  o.kp = a.kp;
  o.kd = a.kd;
  o.max_current_a = a.max_current_a;
  o.max_travel_rev = a.max_travel_rev;
  blmc::ControlSettings s;
  s.limits.max_velocity_krpm = a.max_velocity_krpm;
  s.limits.stale_after = duration_of<core::Duration>(a.stale_data_s, "stale_data_s");
  s.realtime = a.realtime;
  const auto timeout = duration_of<std::chrono::milliseconds>(a.timeout_s, "timeout_s");
  auto& m = b.get();
  return guarded(b, [&m, &o, &s, timeout] { return m.home(o, s, timeout); });
}

void bind_homing(py::module_& m, py::class_<Board>& c) {
  using blmc::host::MotorHoming;
  py::class_<MotorHoming>(m, "MotorHoming", "What homing found for one motor.")
      .def_property_readonly("state", [](const MotorHoming& h) { return std::string(blmc::host::to_string(h.state)); },
                             "'found', 'failed' (no index within max_travel_rev), 'idle' (not asked or not used), 'searching'.")
      .def_readonly("start_rev", &MotorHoming::start_rev, "Where the motor was when the search began (rev).")
      .def_readonly("index_rev", &MotorHoming::index_rev, "The encoder index: the motor's offset (rev; valid when found).")
      .def("__repr__", [](const MotorHoming& h) {
        return fmt::format("MotorHoming(state='{}', start_rev={:.5f}, index_rev={:.5f})", blmc::host::to_string(h.state), h.start_rev, h.index_rev);
      });
  py::class_<blmc::HomingReport>(m, "HomingReport", "How homing went: the control run and each motor's result.")
      .def_readonly("control", &blmc::HomingReport::control)
      .def_readonly("motors", &blmc::HomingReport::motors)
      .def_readonly("all_found", &blmc::HomingReport::all_found)
      .def("__repr__", [](const blmc::HomingReport& r) {
        return fmt::format("HomingReport(all_found={}, motors=[{}, {}], end='{}')", r.all_found ? "True" : "False",
                           blmc::host::to_string(r.motors[0].state), blmc::host::to_string(r.motors[1].state), blmc::to_string(r.control.end));
      });
  c.def("home", [](Board& b, double speed_rev_s, std::array<bool, 2> motors, double kp, double kd, double max_current_a,
                   double max_travel_rev, double timeout_s, double max_velocity_krpm, double stale_data_s, bool realtime) {
         return home(b, {speed_rev_s, kp, kd, max_current_a, max_travel_rev, timeout_s, max_velocity_krpm, stale_data_s, motors, realtime});
       }, py::kw_only(), py::arg("speed_rev_s") = 0.5, py::arg("motors") = std::array<bool, 2>{true, true}, py::arg("kp") = 2.0,
       py::arg("kd") = 0.02, py::arg("max_current_a") = 0.5, py::arg("max_travel_rev") = 2.0, py::arg("timeout_s") = 20.0,
       py::arg("max_velocity_krpm") = 2.0, py::arg("stale_data_s") = 0.01, py::arg("realtime") = true,
       "Finds each motor's encoder index under the 1 kHz loop and its safety limits (the motors must be enabled): "
       "HomingReport. Ctrl-C: the motors are disabled.");
}

void bind_board(py::module_& m) {
  py::class_<Board> c(m, "MotorBoard", "One motor driver board (two motors) from blocking calls.");
  c.def(py::init(&open_board), py::arg("bus_spec"), py::kw_only(), py::arg("name") = "blmc",
        py::arg("motors") = std::array<bool, 2>{true, true}, py::arg("connect_timeout_s") = 5.0, py::arg("ready_timeout_s") = 10.0,
        py::arg("status_timeout_s") = 2.5, py::arg("recv_timeout_ms") = 50,
        "Opens the bus (socketcan:can0, socketcand://HOST:PORT/can0, cannet://HOST/N) and decodes the board's frames. "
        "recv_timeout_ms: the board's own receive timeout during control (0: off).")
      .def("enable", [](Board& b) {
        auto& m = b.get();
        guarded(b, [&m] { m.enable(); });
      }, "Enables the system and the motors and waits until they are aligned and ready.")
      .def("disable", [](Board& b) {
        auto& m = b.get();
        guarded(b, [&m] { m.disable(); });
      }, "Stops control if it runs; zero current, motors and system off.")
      .def_property_readonly("enabled", [](Board& b) { return b.get().enabled(); })
      .def("recover", [](Board& b) {
        auto& m = b.get();
        guarded(b, [&m] { m.recover(); });
      }, "After the board disabled itself on an error: the recovery sequence, then waits until ready.")
      .def("status", [](Board& b) {
        auto& m = b.get();
        return guarded(b, [&m] { return m.wait_status(); });
      }, "Waits for the board's next status frame (it sends one a second).")
      .def("measurements", [](Board& b) {
        auto& m = b.get();
        py::gil_scoped_release release;
        return measurements_of(m.measurements());
      }, "The latest measurements (during control: the latest cycle's).")
      .def("interrupt", [](Board& b) { b.get().interrupt(); }, "From any thread: the wait in progress ends (Interrupted).")
      .def("clear_interrupt", [](Board& b) {
        auto& m = b.get();
        py::gil_scoped_release release;
        m.clear_interrupt();
      })
      .def("close", &Board::close, "Stops control, disables the motors and closes the bus (also at the end of a with block).")
      .def("__enter__", [](py::object self) { return self; })
      .def("__exit__", [](Board& b, py::args) { b.close(); });
  bind_board_control(c);
  bind_board_onboard(c);
  bind_homing(m, c);
}

blmc::sim::FaultKind fault_kind(const std::string& name) {
  using blmc::sim::FaultKind;
  for (auto k : {FaultKind::encoder, FaultKind::pos_converter, FaultKind::transmit, FaultKind::over_current, FaultKind::undocumented})
    if (blmc::sim::name(k) == name) return k;
  invalid(fmt::format("unknown fault '{}': encoder, pos_converter, transmit, over_current or undocumented", name));
}

void bind_sim(py::module_& m) {
  using blmc::sim::SimulatedBoard;
  using blmc::sim::SimulatedBoardReport;
  py::class_<SimulatedBoardReport>(m, "SimulatedBoardReport", "A simulated board's state now.")
      .def_readonly("status", &SimulatedBoardReport::status)
      .def_property_readonly("motor_enabled", [](const SimulatedBoardReport& r) { return std::array<bool, 2>{r.motors[0].enabled, r.motors[1].enabled}; })
      .def_property_readonly("iq_ref_a", [](const SimulatedBoardReport& r) { return array_of(Pair{r.motors[0].iq_ref_a, r.motors[1].iq_ref_a}); },
                             "The last current reference each motor received (A).")
      .def_property_readonly("position_rev", [](const SimulatedBoardReport& r) { return array_of(r.position_rev); })
      .def_property_readonly("iq_refs", [](const SimulatedBoardReport& r) { return r.stats.iq_refs; }, "Current reference frames applied.")
      .def("__repr__", [](const SimulatedBoardReport& r) {
        return fmt::format("SimulatedBoardReport({}, iq_ref_a=[{:g}, {:g}])", r.status.to_string(), r.motors[0].iq_ref_a, r.motors[1].iq_ref_a);
      });
  py::class_<SimulatedBoard>(m, "SimulatedBoard",
                             "Motor driver boards simulated in this process (1 kHz firmware model, motors), served over socketcand "
                             "on loopback: MotorBoard(sim.bus_spec) reaches board 0.")
      .def(py::init([](unsigned boards, double alignment_time_s, std::array<double, 2> index_offset_rev) {
             blmc::sim::SimulatedBoardOptions o;
             o.boards = boards;
             o.config.alignment_time = duration_of<core::Duration>(alignment_time_s, "alignment_time_s", false);
             for (std::size_t k = 0; k < 2; ++k) o.config.motors[k].index_offset_rev = index_offset_rev[k];
             py::gil_scoped_release release;
             return std::make_unique<SimulatedBoard>(o);
           }),
           py::kw_only(), py::arg("boards") = 1, py::arg("alignment_time_s") = 2.0,
           py::arg("index_offset_rev") = std::array<double, 2>{blmc::sim::MotorConfig{}.index_offset_rev, blmc::sim::MotorConfig{}.index_offset_rev},
           "alignment_time_s: how long the first enable after power-up aligns the motors; index_offset_rev: where "
           "each motor's encoder index mark sits within its turn (rev).")
      .def_property_readonly("bus_spec", [](const SimulatedBoard& s) { return s.bus_spec(0); }, "Board 0's bus spec.")
      .def("bus_spec_of", [](const SimulatedBoard& s, unsigned board) { return s.bus_spec(board); }, py::arg("board"),
           py::call_guard<py::gil_scoped_release>())
      .def_property_readonly("endpoint", &SimulatedBoard::endpoint, "The socketcand server, HOST:PORT.")
      .def("inject", [](SimulatedBoard& s, const std::string& kind, unsigned board, double duration_s) {
             s.inject(fault_kind(kind), board, duration_of<core::Duration>(duration_s, "duration_s", false));
           }, py::arg("kind"), py::arg("board") = 0, py::arg("duration_s") = 0.0, py::call_guard<py::gil_scoped_release>(),
           "The firmware raises this fault at its next cycle and disables itself: encoder, pos_converter, transmit, "
           "over_current, undocumented (duration_s: how long its cause lasts; 0: a glitch).")
      .def("power_cycle", &SimulatedBoard::power_cycle, py::arg("board") = 0, py::call_guard<py::gil_scoped_release>())
      .def("report", &SimulatedBoard::report, py::arg("board") = 0, py::call_guard<py::gil_scoped_release>())
      .def("stop", &SimulatedBoard::stop, py::call_guard<py::gil_scoped_release>())
      .def("__enter__", [](py::object self) { return self; })
      .def("__exit__", [](SimulatedBoard& s, py::args) {
        py::gil_scoped_release release;
        s.stop();
      });
}

}  // namespace

void bind_blmc(py::module_& m) {
  bind_values(m);
  bind_report(m);
  bind_board(m);
  bind_sim(m);
}

}  // namespace axon::python
