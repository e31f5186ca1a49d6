// axon.c4g: serving a C4G robot controller's open interface from Python. The built-in
// applications (apps::make_app: monitor, echo, stream, correct, pid), the server that answers the
// controller with one of them (apps::ServeSession) and the controller simulated in this process
// (sim::SimulatedController). Python never runs inside the cycle: an application is built whole,
// its trajectory included, before the server starts; the cycle thread only reads its tables.
// Every blocking call releases the GIL; Ctrl-C during Server.run() ends the session the way the
// CLI's Ctrl-C does (the application leaves its open modes, drive off if the controller does not
// come back to mode 0 in time), then raises KeyboardInterrupt.
#include "bindings.hpp"
#include "axon/c4g/apps/contribute.hpp"
#include "axon/c4g/apps/handover.hpp"

#include "axon/c4g/apps/app_factory.hpp"
#include "axon/c4g/apps/correct.hpp"
#include "axon/c4g/apps/echo.hpp"
#include "axon/c4g/apps/monitor.hpp"
#include "axon/c4g/apps/pid.hpp"
#include "axon/c4g/apps/serve.hpp"
#include "axon/c4g/apps/stream.hpp"
#include "axon/c4g/apps/trajectory.hpp"
#include "axon/c4g/sim/simulated_controller.hpp"
#include "axon/net/endpoint.hpp"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <fmt/format.h>

#include <atomic>
#include <cmath>
#include <optional>
#include <span>

namespace axon::python {

namespace {

using namespace c4g;
using apps::App;

[[noreturn]] void invalid(const std::string& text) { throw Exception(Error(CoreErrc::invalid_argument, text)); }

double finite_seconds(double s, const char* what) {
  if (!std::isfinite(s) || s < 0) invalid(fmt::format("{} must be a number of seconds >= 0, got {}", what, s));
  return s;
}

// A table of angles from Python: a 2-D array of real numbers, rows = samples, columns = axes.
// The shape and the element type are checked here (nothing else can read the buffer); the rest
// (at least one row and one axis, finite values) by Trajectory::from_table.
std::shared_ptr<const apps::Trajectory> trajectory_of(const py::object& values, const char* what, double row_step) {
  const auto raw = py::array::ensure(values);
  const char kind = raw ? raw.dtype().kind() : 'O';
  if (!raw || raw.ndim() != 2 || (kind != 'f' && kind != 'i' && kind != 'u'))
    invalid(fmt::format("{}: a 2-D array of real numbers (rows = samples, columns = axes) in degrees, got {}", what,
                        raw ? fmt::format("{} dimension(s) of dtype {}", raw.ndim(), std::string(py::str(raw.dtype())))
                            : std::string(py::str(py::type::of(values)))));
  const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(raw);
  const auto axes = static_cast<std::size_t>(a.shape(1));
  const std::span<const double> flat(a.data(), static_cast<std::size_t>(a.size()));
  auto t = apps::Trajectory::from_table(flat, axes, row_step, apps::AngleUnit::deg);
  if (!t) invalid(fmt::format("{}: {}", what, t.error().detail));
  return std::make_shared<apps::Trajectory>(std::move(t).value());
}

// An application by name through apps::make_app (the CLI's path), as the subclass Python shows.
template <class T>
std::shared_ptr<T> make(const apps::AppConfig& c) {
  std::unique_ptr<App> app = apps::make_app(c);
  return std::shared_ptr<T>(static_cast<T*>(app.release()));
}

apps::AppConfig config(const char* app) {
  apps::AppConfig c;
  c.app = app;
  return c;
}

std::vector<double> per_axis(const py::object& values) {
  if (values.is_none()) return {};
  const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(values);
  if (!a || a.ndim() > 1) invalid("one number for every axis, or one number per axis");
  return std::vector<double>(a.data(), a.data() + a.size());
}

// {motion type: (rows, axes) array} as the segments of a stream (StreamOptions::segments).
std::vector<apps::StreamSegment> segments_of(const py::object& segments, std::optional<double> dt_s) {
  std::vector<apps::StreamSegment> out;
  if (segments.is_none()) return out;
  if (!py::isinstance<py::dict>(segments)) invalid("segments: a dict {motion type 1..255: positions_deg array}");
  for (const auto& [key, table] : segments.cast<py::dict>()) {
    const auto type = py::isinstance<py::int_>(key) ? key.cast<long>() : 0L;
    if (type < 1 || type > 255) invalid("segments: each key is a motion type 1..255 (the arm's CMD byte)");
    const auto what = fmt::format("segments[{}]", type);
    out.push_back({static_cast<std::uint8_t>(type), trajectory_of(py::reinterpret_borrow<py::object>(table), what.c_str(),
                                                                  dt_s.value_or(1.0))});
  }
  if (out.empty()) invalid("segments: at least one motion type");
  return out;
}

// A trajectory or segments (not both) into the config of stream or handover.
void set_motion(apps::AppConfig& c, const py::object& positions_deg, const py::object& segments, std::optional<double> dt_s) {
  if (!positions_deg.is_none() && !segments.is_none()) invalid("give positions_deg or segments, not both");
  c.per_cycle = !dt_s;
  if (!positions_deg.is_none()) c.trajectory = trajectory_of(positions_deg, "positions_deg", dt_s.value_or(1.0));
  c.segment_tables = segments_of(segments, dt_s);
}

void bind_apps(py::module_& m) {
  py::class_<App, std::shared_ptr<App>>(m, "App", "A built-in application: runs on the server's cycle thread once per packet.")
      .def_property_readonly("name", [](const App& a) { return std::string(a.name()); })
      .def_property_readonly("status", &App::status, "One line: cycles, modes, what the app is doing.")
      .def_property_readonly("summary", &App::summary)
      .def_property_readonly("finished", &App::finished, "The app did its job and its axes are back in mode 0.")
      .def_property_readonly("error", [](const App& a) -> std::optional<std::string> {
        if (!a.has_error()) return std::nullopt;
        return a.error();
      }, "Why the app refused to go on (start point away from the robot, wrong axis count ...), None without.")
      .def_property_readonly("cycles", &App::cycles, "Packets the app answered.")
      .def("__repr__", [](const App& a) { return fmt::format("<axon.c4g.{} {}>", a.name(), a.status()); });
  using apps::OpenModeApp;
  py::class_<OpenModeApp, App, std::shared_ptr<OpenModeApp>>(m, "OpenModeApp", "An application serving one open mode of one arm.")
      .def_property_readonly("phase", [](const OpenModeApp& a) { return std::string(apps::to_string(a.phase())); },
                             "waiting, running, fading, holding, idle, exiting, done, refused")
      .def_property_readonly("runs", &OpenModeApp::runs)
      .def_property_readonly("elapsed_s", &OpenModeApp::elapsed_s, "The current run's time.");

  py::class_<apps::MonitorApp, App, std::shared_ptr<apps::MonitorApp>>(m, "Monitor", "Mode 0: the PC only answers (the safe reply) and watches.")
      .def(py::init([] { return make<apps::MonitorApp>(config("monitor")); }))
      .def_property_readonly("drives_on_cycles", &apps::MonitorApp::drives_on_cycles)
      .def_property_readonly("non_mode0_cycles", &apps::MonitorApp::non_mode0_cycles);
  py::class_<apps::EchoApp, App, std::shared_ptr<apps::EchoApp>>(m, "Echo", "Mode 0' (the communication test): targets echoed unchanged.")
      .def(py::init([] { return make<apps::EchoApp>(config("echo")); }))
      .def_property_readonly("echoed", &apps::EchoApp::echoed, "Cycles echoed.");

  py::class_<apps::StreamApp, OpenModeApp, std::shared_ptr<apps::StreamApp>>(m, "Stream", "Mode 4 or 5: a joint trajectory played on one arm.")
      .def(py::init([](const py::object& positions_deg, const py::object& segments, std::optional<double> dt_s, int mode,
                       std::size_t arm, bool relative, double start_tolerance_deg, double max_motor_speed, double stop_ramp_s,
                       bool rearm) {
             auto c = config("stream");
             if (positions_deg.is_none() && segments.is_none()) invalid("give positions_deg or segments");
             set_motion(c, positions_deg, segments, dt_s);
             c.mode = mode;
             c.arm = arm;
             c.relative = relative;
             c.start_tolerance_deg = start_tolerance_deg;
             c.max_motor_speed = max_motor_speed;
             c.ramp_s = finite_seconds(stop_ramp_s, "stop_ramp_s");
             c.rearm = rearm;
             return make<apps::StreamApp>(c);
           }),
           py::arg("positions_deg") = py::none(), py::kw_only(), py::arg("segments") = py::none(), py::arg("dt_s") = py::none(),
           py::arg("mode") = 4, py::arg("arm") = 1,
           py::arg("relative") = false, py::arg("start_tolerance_deg") = 0.5, py::arg("max_motor_speed") = 100.0,
           py::arg("stop_ramp_s") = 0.3, py::arg("rearm") = false,
           "positions_deg: (rows, axes) array of joint angles (link side, degrees), one column per axis of the arm. "
           "dt_s=None: one row per controller cycle; else rows dt_s apart, sampled each cycle by linear interpolation. "
           "relative: rows are offsets from where the arm stands (the first row must be 0); else the first row must "
           "match the arm within start_tolerance_deg. max_motor_speed: motor turns/s between two cycles. The table is "
           "copied: later changes to the array do not reach the app. rearm: play it again at every open phase (the "
           "program's next GO OPEN), not once. segments: instead of positions_deg, {motion type: array}: the robot "
           "program picks the table by the arm's motion type (its CMD byte), each starting with the start-point check "
           "(relative segments chain from where the last one ended); a motion type without a table holds; motion type 0 "
           "after a segment ends the stream.")
      .def_property_readonly("rows", &apps::StreamApp::table_rows, "Cycles the trajectory takes (known once the controller's initialization packet came).")
      .def_property_readonly("progress", &apps::StreamApp::progress, "Rows played so far.")
      .def_property_readonly("segment", &apps::StreamApp::segment, "Motion type of the segment played last (0: none yet, or no segments).");

  py::class_<apps::CorrectApp, OpenModeApp, std::shared_ptr<apps::CorrectApp>>(m, "Correct", "Mode 7: a sine correction added to the robot program's path.")
      .def(py::init([](const py::object& amplitude_deg, const py::object& frequency_hz, double open_time_s, double ramp_s,
                       std::size_t arm, const py::object& max_correction_deg, const py::object& max_step_deg,
                       const std::string& file, const std::string& feed, const std::string& feed_from, std::size_t feed_axes,
                       double feed_timeout_ms, bool rearm) {
             auto c = config("correct");
             c.file = file;
             c.feed = feed;
             c.feed_from = feed_from;
             c.feed_axes = feed_axes;
             c.feed_timeout_ms = feed_timeout_ms;
             c.rearm = rearm;
             c.amplitude = per_axis(amplitude_deg);
             c.frequency_hz = per_axis(frequency_hz);
             c.open_time_s = finite_seconds(open_time_s, "open_time_s");
             c.ramp_s = finite_seconds(ramp_s, "ramp_s");
             c.arm = arm;
             if (!max_correction_deg.is_none()) c.max_correction_deg = per_axis(max_correction_deg);
             if (!max_step_deg.is_none()) c.max_correction_step_deg = per_axis(max_step_deg);
             return make<apps::CorrectApp>(c);
           }),
           py::kw_only(), py::arg("amplitude_deg") = py::none(), py::arg("frequency_hz") = py::none(), py::arg("open_time_s") = 0.0,
           py::arg("ramp_s") = 0.5, py::arg("arm") = 1, py::arg("max_correction_deg") = py::none(), py::arg("max_step_deg") = py::none(),
           py::arg("file") = "", py::arg("feed") = "", py::arg("feed_from") = "", py::arg("feed_axes") = 6,
           py::arg("feed_timeout_ms") = 100.0, py::arg("rearm") = false,
           "The correction, from one source: a sine (amplitude_deg, frequency_hz: one value for every axis or one per "
           "axis, link side), a table of correction values (file: CSV, docs/c4g-cli.md), or a live feed of a sensor "
           "over UDP (feed: HOST:PORT to listen on; feed_from: only that sender; feed_axes values a datagram; a feed "
           "silent for feed_timeout_ms holds the last correction and is reported). open_time_s=0: until the session "
           "stops. Corrections beyond max_correction_deg (default 5) or steps beyond max_step_deg per cycle (default "
           "0.1) are refused. rearm: serve every open phase, not only the first.")
      .def("applied_turns", &apps::CorrectApp::applied, py::arg("axis_index"), "The sum of the increments sent on the arm's axis (0-based), motor turns.");

  py::class_<apps::PidApp, OpenModeApp, std::shared_ptr<apps::PidApp>>(m, "Pid", "Modes 1 and 2: the PC closes the arm's loops and sends currents.")
      .def(py::init([](const py::object& kp, const py::object& kv, const py::object& ki, const py::object& amplitude_deg,
                       const py::object& frequency_hz, double open_time_s, double ramp_s, std::size_t arm, bool dynamic_model,
                       bool reduce_in_pc) {
             auto c = config("pid");
             c.kp = per_axis(kp);
             c.kv = per_axis(kv);
             c.ki = per_axis(ki);
             c.amplitude = per_axis(amplitude_deg);
             c.frequency_hz = per_axis(frequency_hz);
             c.open_time_s = finite_seconds(open_time_s, "open_time_s");
             c.ramp_s = finite_seconds(ramp_s, "ramp_s");
             c.arm = arm;
             c.no_dynamic_model = !dynamic_model;
             c.reduce_in_pc = reduce_in_pc;
             return make<apps::PidApp>(c);
           }),
           py::kw_only(), py::arg("kp") = py::none(), py::arg("kv") = py::none(), py::arg("ki") = py::none(),
           py::arg("amplitude_deg") = py::none(), py::arg("frequency_hz") = py::none(), py::arg("open_time_s") = 0.0,
           py::arg("ramp_s") = 0.5, py::arg("arm") = 1, py::arg("dynamic_model") = true, py::arg("reduce_in_pc") = false,
           "Gains per axis or one for all: kp [1/s], kv [A per turn/s], ki [1/s] (defaults 20, 0.5, 10). Mode 1 holds the "
           "arm, or swings it by amplitude_deg at frequency_hz; open_time_s=0: until the session stops.")
      .def_property_readonly("max_following_error_turns", &apps::PidApp::max_following_error,
                             "Largest |reference - position| on any axis so far (motor turns).")
      .def_property_readonly("saturated_cycles", &apps::PidApp::saturated_cycles, "Cycles in which a current hit its limit.");

  py::class_<apps::ContributeApp, OpenModeApp, std::shared_ptr<apps::ContributeApp>>(
      m, "Contribute", "Modes 8 and 9: a sine added to the controller's own velocity (8) or current (9) references.")
      .def(py::init([](int mode, const py::object& amplitude, const py::object& frequency_hz, double open_time_s, double ramp_s,
                       std::size_t arm, double max_motor_speed) {
             auto c = config("contribute");
             c.mode = mode;
             c.amplitude = per_axis(amplitude);
             c.frequency_hz = per_axis(frequency_hz);
             c.open_time_s = finite_seconds(open_time_s, "open_time_s");
             c.ramp_s = finite_seconds(ramp_s, "ramp_s");
             c.arm = arm;
             c.max_motor_speed = max_motor_speed;
             return make<apps::ContributeApp>(c);
           }),
           py::kw_only(), py::arg("mode") = 9, py::arg("amplitude") = py::none(), py::arg("frequency_hz") = py::none(),
           py::arg("open_time_s") = 0.0, py::arg("ramp_s") = 0.5, py::arg("arm") = 1, py::arg("max_motor_speed") = 100.0,
           "amplitude: per axis or one for all, motor side: turns/s in mode 8, amperes in mode 9 (the server's Safety "
           "saturates currents to the initialization packet's limits); a mode 8 amplitude above max_motor_speed is "
           "refused. open_time_s=0: until the session stops.")
      .def("last", &apps::ContributeApp::last, py::arg("axis_index"), "The contribution sent last on the arm's axis (0-based), in the mode's unit.")
      .def("peak", &apps::ContributeApp::peak, py::arg("axis_index"), "The largest contribution sent on that axis so far.");

  py::class_<apps::HandoverApp, App, std::shared_ptr<apps::HandoverApp>>(
      m, "Handover", "The manual's hand-over: a trajectory (or a hold) in modes 4/5, a correction in mode 7, as the program asks.")
      .def(py::init([](const py::object& positions_deg, const py::object& segments, std::optional<double> dt_s, bool relative,
                       double start_tolerance_deg, const py::object& amplitude_deg, const py::object& frequency_hz,
                       const std::string& correct_file, double hold_s, double ramp_s, std::size_t arm) {
             auto c = config("handover");
             set_motion(c, positions_deg, segments, dt_s);
             c.relative = relative;
             c.start_tolerance_deg = start_tolerance_deg;
             c.amplitude = per_axis(amplitude_deg);
             c.frequency_hz = per_axis(frequency_hz);
             c.correct_file = correct_file;
             c.open_time_s = finite_seconds(hold_s, "hold_s");
             c.ramp_s = finite_seconds(ramp_s, "ramp_s");
             c.arm = arm;
             return make<apps::HandoverApp>(c);
           }),
           py::arg("positions_deg") = py::none(), py::kw_only(), py::arg("segments") = py::none(), py::arg("dt_s") = py::none(),
           py::arg("relative") = false, py::arg("start_tolerance_deg") = 0.5, py::arg("amplitude_deg") = py::none(), py::arg("frequency_hz") = py::none(),
           py::arg("correct_file") = "", py::arg("hold_s") = 0.5, py::arg("ramp_s") = 0.5, py::arg("arm") = 1,
           "Serves whichever open mode the program enters, phase after phase: modes 4/5 play positions_deg or segments (as Stream; "
           "none: hold the arm for hold_s), mode 7 adds the correction (a sine of amplitude_deg at frequency_hz, or the "
           "values of correct_file; none: a zero correction for hold_s). Each phase ends with exit from open.")
      .def_property_readonly("phases", &apps::HandoverApp::phases, "Open phases entered so far.");
}

void bind_report(py::module_& m) {
  using apps::ServeTiming;
  py::class_<ServeTiming>(m, "ServeTiming", "The server's timing figures (seconds).")
      .def_readonly("cycles", &ServeTiming::cycles)
      .def_readonly("nominal_period_s", &ServeTiming::nominal_period_s, "The controller's period (0 while unknown).")
      .def_readonly("cycle_time_p50_s", &ServeTiming::cycle_time_p50_s, "Processing time of a packet: receive to reply sent.")
      .def_readonly("cycle_time_p99_s", &ServeTiming::cycle_time_p99_s)
      .def_readonly("cycle_time_p999_s", &ServeTiming::cycle_time_p999_s)
      .def_readonly("cycle_time_max_s", &ServeTiming::cycle_time_max_s)
      .def_readonly("worst_cycle_time_s", &ServeTiming::worst_cycle_time_s)
      .def_readonly("missed_deadlines", &ServeTiming::missed_deadlines, "Replies later than deadline_s after their packet.")
      .def_readonly("deadline_s", &ServeTiming::deadline_s)
      .def_readonly("inter_packet_min_s", &ServeTiming::inter_packet_min_s)
      .def_readonly("inter_packet_max_s", &ServeTiming::inter_packet_max_s)
      .def_readonly("jitter_min_s", &ServeTiming::jitter_min_s)
      .def_readonly("jitter_max_s", &ServeTiming::jitter_max_s)
      .def("__repr__", [](const ServeTiming& t) {
        return fmt::format("ServeTiming(cycles={}, cycle_time_p50_us={:.1f}, p99_us={:.1f}, max_us={:.1f}, missed_deadlines={})", t.cycles,
                           t.cycle_time_p50_s * 1e6, t.cycle_time_p99_s * 1e6, t.cycle_time_max_s * 1e6, t.missed_deadlines);
      });
  using apps::ServeStats;
  py::class_<ServeStats>(m, "ServeStats", "The server's counters.")
      .def_readonly("controller", &ServeStats::controller, "The session's controller HOST:PORT ('' : none came).")
      .def_readonly("packets", &ServeStats::packets, "Datagrams from the controller (every one answered but those of no known size).")
      .def_readonly("init_packets", &ServeStats::init_packets)
      .def_readonly("cyclic_packets", &ServeStats::cyclic_packets)
      .def_readonly("protocol_errors", &ServeStats::protocol_errors)
      .def_readonly("safe_replies", &ServeStats::safe_replies, "Cycles answered with the safe reply instead of the app's.")
      .def_readonly("controller_late", &ServeStats::controller_late, "Cycles the app took longer than its budget (400 us).")
      .def_readonly("refused_mode_changes", &ServeStats::refused_mode_changes)
      .def_readonly("foreign", &ServeStats::foreign, "Datagrams from others than the session's controller (ignored).")
      .def_readonly("freezes", &ServeStats::freezes)
      .def_readonly("frozen_cycles", &ServeStats::frozen_cycles)
      .def_readonly("safety_fault", &ServeStats::safety_fault, "'none', or what latched drive off.")
      .def_readonly("controller_errors", &ServeStats::controller_errors,
                    "'none', or the controller's errors the packets showed by the manual's names (docs/c4g-errors.md).")
      .def_readonly("currents_clamped", &ServeStats::currents_clamped)
      .def_readonly("timing", &ServeStats::timing)
      .def("__repr__", [](const ServeStats& s) {
        return fmt::format("ServeStats(packets={}, cyclic_packets={}, safe_replies={}, controller_late={}, missed_deadlines={}, safety_fault='{}')",
                           s.packets, s.cyclic_packets, s.safe_replies, s.controller_late, s.timing.missed_deadlines, s.safety_fault);
      });
  using apps::ServeReport;
  py::class_<ServeReport>(m, "ServeReport", "How a session ended.")
      .def_readonly("app", &ServeReport::app)
      .def_readonly("reason", &ServeReport::reason, "'application finished', 'duration reached', 'signal' (Ctrl-C), 'stopped', "
                                                     "'application error', 'controller ended the exchange (504)', 'safety stop: ...'")
      .def_readonly("finished", &ServeReport::finished, "The app did its job.")
      .def_readonly("error", &ServeReport::error, "The app's error ('' : none).")
      .def_readonly("safety_fault", &ServeReport::safety_fault)
      .def_readonly("app_cycles", &ServeReport::app_cycles)
      .def_readonly("stats", &ServeReport::stats)
      .def_property_readonly("exit_code", &ServeReport::exit_code, "axon c4g serve's: 0 done, 1 the app failed, 4 a safety stop.")
      .def_property_readonly("ok", [](const ServeReport& r) { return r.exit_code() == 0; })
      .def("text", &ServeReport::text, "What axon c4g serve prints at the end.")
      .def("json", &ServeReport::json)
      .def("__repr__", [](const ServeReport& r) {
        return fmt::format("ServeReport(app='{}', reason='{}', finished={}, error='{}', packets={}, safety_fault='{}')", r.app, r.reason,
                           r.finished ? "True" : "False", r.error, r.stats.packets, r.stats.safety_fault);
      });
}

// A ServeSession as Python holds it: the app kept alive with it, the report of its run.
struct Session {
  std::shared_ptr<App> app;
  std::unique_ptr<apps::ServeSession> session;
  std::string address;
  std::uint16_t port = 0;
  std::atomic<int> interrupts{0};
  std::optional<apps::ServeReport> report;

  apps::ServeSession& get() {
    if (!session) throw Exception(Error(CoreErrc::closed, "c4g: the server was closed"));
    if (report) throw Exception(Error(CoreErrc::closed, "c4g: this server's session already ran (a Server serves one session)"));
    return *session;
  }
  void close() {
    py::gil_scoped_release release;
    session.reset();  // the graceful stop if run() did not end the session
  }
};

std::unique_ptr<Session> open_session(const std::shared_ptr<App>& app, const std::string& listen, const std::string& controller,
                                      double duration_s, bool until_controller_ends, double stop_timeout_s, int rt_priority,
                                      bool verify_reply_fields, const std::string& csv, int moni, std::size_t samples) {
  if (samples > 0 && !csv.empty())
    invalid("samples and csv both take the recorded cycles: give one (the CSV has every cycle too)");
  apps::ServeOptions o;
  o.server.listen = net::parse_endpoint(listen, host::kManualPort).value();
  if (!controller.empty()) o.server.controller = net::parse_endpoint(controller, 0).value();
  o.server.cycle.realtime.fifo_priority = rt_priority;
  o.server.cycle.realtime.lock_memory = rt_priority > 0;
  o.server.verify_reply_fields = verify_reply_fields;
  o.duration_s = finite_seconds(duration_s, "duration_s");
  o.until_controller_ends = until_controller_ends;
  o.stop_timeout_s = finite_seconds(stop_timeout_s, "stop_timeout_s");
  o.csv = csv;
  o.moni = moni;
  auto s = std::make_unique<Session>();
  s->app = app;
  if (samples > 0) s->app->record_samples(samples);
  py::gil_scoped_release release;
  s->session = std::make_unique<apps::ServeSession>(*s->app, o);
  s->session->start();
  s->address = s->session->local_address();
  s->port = s->session->server().local_address().port;
  return s;
}

// run(): the session's wait on a helper thread (GIL released). `until`, a Python callable, is
// polled between the session's polls (~20 ms, on that thread, with the GIL): true ends the run.
// Ctrl-C counts as the CLI's signal: the graceful stop runs, then KeyboardInterrupt.
apps::ServeReport run(Session& s, const py::object& until) {
  auto& session = s.get();
  py::object raised;  // what `until` raised (touched with the GIL only)
  apps::ServeSession::Hooks hooks;
  hooks.interruptions = [&s] { return s.interrupts.load(); };
  if (!until.is_none())
    hooks.on_poll = [&session, &until, &raised] {
      py::gil_scoped_acquire gil;
      if (raised) return;
      try {
        if (until().cast<bool>()) session.stop();
      } catch (py::error_already_set& e) {
        raised = e.value();
        session.stop();
      }
    };
  std::optional<apps::ServeReport> done;  // written by the helper thread, read once it was joined
  try {
    interruptible([&] { done.emplace(session.run(hooks)); }, [&s] { ++s.interrupts; });
  } catch (py::error_already_set&) {
    s.report = std::move(done);
    throw;
  }
  s.report = done;
  if (raised) {
    PyErr_SetObject(reinterpret_cast<PyObject*>(Py_TYPE(raised.ptr())), raised.ptr());
    throw py::error_already_set();
  }
  return *done;
}

// Server.samples(): what the cycle thread recorded since the last call, as numpy arrays.
py::dict drain_samples(Session& s) {
  if (!s.app) throw Exception(Error(CoreErrc::closed, "c4g: the server was closed"));
  std::vector<apps::Sample> got;
  {
    py::gil_scoped_release release;
    s.app->drain_samples([&got](const apps::Sample& x) { got.push_back(x); });
  }
  std::size_t axes = 0;
  for (const auto& x : got) axes = std::max(axes, std::min(x.request.count, protocol::kMaxAxes));
  const auto n = static_cast<py::ssize_t>(got.size()), k = static_cast<py::ssize_t>(axes);
  py::array_t<std::uint64_t> cycle(n);
  py::array_t<std::int64_t> wall(n);
  py::array_t<std::int32_t> mode({n, k});
  py::array_t<float> request({n, k, py::ssize_t{5}}), reply({n, k, py::ssize_t{5}});
  auto c = cycle.mutable_unchecked<1>();
  auto w = wall.mutable_unchecked<1>();
  auto md = mode.mutable_unchecked<2>();
  auto rq = request.mutable_unchecked<3>();
  auto rp = reply.mutable_unchecked<3>();
  for (py::ssize_t i = 0; i < n; ++i) {
    const auto& x = got[static_cast<std::size_t>(i)];
    c(i) = x.cycle;
    w(i) = x.wall_ns;
    for (py::ssize_t j = 0; j < k; ++j) {
      const auto& a = x.request.axes[static_cast<std::size_t>(j)];
      const auto& b = x.reply.axes[static_cast<std::size_t>(j)];
      md(i, j) = a.mode;
      const float qa[5] = {a.d1, a.d2, a.d3, a.d4, a.d5}, qb[5] = {b.d1, b.d2, b.d3, b.d4, b.d5};
      for (py::ssize_t f = 0; f < 5; ++f) {
        rq(i, j, f) = qa[f];
        rp(i, j, f) = qb[f];
      }
    }
  }
  py::dict d;
  d["cycle"] = cycle;
  d["wall_ns"] = wall;
  d["mode"] = mode;
  d["request"] = request;
  d["reply"] = reply;
  d["dropped"] = s.app->samples_dropped();
  return d;
}

void bind_server(py::module_& m) {
  py::class_<Session>(m, "Server",
                      "Answers one robot controller with an application, from the first packet on. Construction binds and "
                      "starts answering (the address is readable at once); run() waits for the end and stops cleanly.")
      .def(py::init(&open_session), py::arg("app"), py::kw_only(), py::arg("listen") = "127.0.0.1:0", py::arg("controller") = "",
           py::arg("duration_s") = 0.0, py::arg("until_controller_ends") = false, py::arg("stop_timeout_s") = 5.0,
           py::arg("rt_priority") = 0, py::arg("verify_reply_fields") = false, py::arg("csv") = "", py::arg("moni") = 0,
           py::arg("samples") = 0,
           "listen: HOST[:PORT] (a host alone: port 1000; port 0: any free one). controller: only this HOST[:PORT] may "
           "start the session. duration_s: run() ends after this long (0: when the app is done). until_controller_ends: "
           "once the app is done, answer the robot program to its end (504). rt_priority: SCHED_FIFO 1..99 for the cycle "
           "thread (0: none). csv/moni: record every cycle (docs/c4g-cli.md). samples: keep up to this many cycles "
           "for samples() (0: none).")
      .def_property_readonly("address", [](const Session& s) { return s.address; }, "HOST:PORT the server answers on.")
      .def_property_readonly("port", [](const Session& s) { return s.port; })
      .def_property_readonly("app", [](const Session& s) { return s.app; })
      .def_property_readonly("status", [](Session& s) {
        if (!s.session) throw Exception(Error(CoreErrc::closed, "c4g: the server was closed"));
        return s.session->status_line();
      }, "A status line: app, server state, cycle times.")
      .def_property_readonly("stats", [](Session& s) {
        if (!s.session) throw Exception(Error(CoreErrc::closed, "c4g: the server was closed"));
        return apps::serve_stats(s.session->server());
      }, "The server's counters and timing figures as they stand (ServeStats), while it runs: read them from "
         "run()'s until callable or another thread; the report has the final ones.")
      .def("samples", &drain_samples,
           "The cycles recorded since the last call (Server(..., samples=N) keeps up to N; more are dropped and "
           "counted in dropped): a dict of numpy arrays, one row a cycle: cycle, wall_ns (the packet's arrival), "
           "mode (rows, axes) of the request, request and reply (rows, axes, 5): D1..D5 of each axis as the "
           "packets carry them (the manual's units per mode), and dropped. Call it from one thread (while run() "
           "runs, from its until callable or another thread; after it, once more for the rest).")
      .def_property_readonly("report", [](const Session& s) { return s.report; }, "The ServeReport once run() ended (also after Ctrl-C), else None.")
      .def("run", &run, py::arg("until") = py::none(),
           "Blocks (GIL released) until the app is done or failed, the controller ends the exchange, duration_s passed, "
           "stop() was called, or until() (a callable polled every ~20 ms off the cycle) returns true; then the app leaves "
           "its open modes (drive off after stop_timeout_s) and the ServeReport comes back. Ctrl-C does the same, then "
           "raises KeyboardInterrupt (the report stays in .report).")
      .def("stop", [](Session& s) { if (s.session) s.session->stop(); }, "From any thread: run() ends (cleanly).")
      .def("close", &Session::close, "Ends the session (cleanly if run() did not) and closes the socket; also at the end of a with block.")
      .def("__enter__", [](py::object self) { return self; })
      .def("__exit__", [](Session& s, py::args) { s.close(); });
}

void bind_sim_report(py::module_& m) {
  using sim::ControllerStats;
  py::class_<ControllerStats>(m, "ControllerStats", "What the simulated controller counted.")
      .def_readonly("ticks", &ControllerStats::ticks)
      .def_readonly("packets_sent", &ControllerStats::packets_sent)
      .def_readonly("cyclic_sent", &ControllerStats::cyclic_sent)
      .def_readonly("replies_ok", &ControllerStats::replies_ok, "Replies in time with the right number.")
      .def_readonly("misses", &ControllerStats::misses, "Cyclic packets without a good reply in the reply window.")
      .def_readonly("max_consecutive_misses", &ControllerStats::max_consecutive_misses)
      .def_readonly("late_replies", &ControllerStats::late_replies)
      .def_readonly("wrong_number", &ControllerStats::wrong_number)
      .def_readonly("malformed", &ControllerStats::malformed)
      .def_readonly("refused_requests", &ControllerStats::refused_requests)
      .def("__repr__", [](const ControllerStats& s) {
        return fmt::format("ControllerStats(packets_sent={}, replies_ok={}, misses={}, late_replies={})", s.packets_sent, s.replies_ok,
                           s.misses, s.late_replies);
      });
  py::class_<sim::Event>(m, "ControllerEvent", "An event of the simulated controller (the manual's error names, mode changes ...).")
      .def_readonly("time_s", &sim::Event::time_s)
      .def_readonly("cycle", &sim::Event::cycle)
      .def_property_readonly("level", [](const sim::Event& e) { return std::string(sim::to_string(e.level)); })
      .def_readonly("name", &sim::Event::name)
      .def_readonly("text", &sim::Event::text)
      .def("__repr__", [](const sim::Event& e) { return fmt::format("ControllerEvent({:.3f} s, {}: {})", e.time_s, e.name, e.text); });
  using Report = sim::SimulatedControllerReport;
  py::class_<Report>(m, "SimulatedControllerReport", "What the simulated controller saw, once its run ended.")
      .def_property_readonly("outcome", [](const Report& r) {
        using O = Report::Outcome;
        return r.outcome == O::completed ? "completed" : r.outcome == O::communication_error ? "communication_error"
                                       : r.outcome == O::scenario_error                       ? "scenario_error"
                                                                                              : "incomplete";
      }, "completed, communication_error, scenario_error, incomplete")
      .def_readonly("outcome_text", &Report::outcome_text)
      .def_readonly("robot", &Report::robot)
      .def_readonly("period_ms", &Report::period_ms)
      .def_readonly("stats", &Report::stats)
      .def_readonly("overruns", &Report::overruns)
      .def_readonly("reply_window_us", &Report::reply_window_us)
      .def_readonly("elapsed_s", &Report::elapsed_s)
      .def_readonly("stopped", &Report::stopped, "Ended by stop() or its duration rather than by the program.")
      .def_readonly("rtt_p50_us", &Report::rtt_p50_us)
      .def_readonly("rtt_p99_us", &Report::rtt_p99_us)
      .def_readonly("rtt_max_us", &Report::rtt_max_us)
      .def_readonly("events", &Report::events)
      .def_property_readonly("exit_code", &Report::exit_code)
      .def("joints_deg", [](const Report& r, std::size_t arm) {
        if (arm == 0 || arm >= r.joint_degrees.size() || r.joint_degrees[arm].empty())
          invalid(fmt::format("the robot has no arm {}", arm));
        return py::array_t<double>(static_cast<py::ssize_t>(r.joint_degrees[arm].size()), r.joint_degrees[arm].data());
      }, py::arg("arm") = 1, "Where the arm's joints ended (link side, degrees): a numpy array.")
      .def("__repr__", [](const Report& r) {
        return fmt::format("SimulatedControllerReport('{}', packets_sent={}, misses={}, elapsed_s={:.2f})", r.outcome_text,
                           r.stats.packets_sent, r.stats.misses, r.elapsed_s);
      });
}

// The simulated controller as Python holds it.
struct Simulated {
  std::optional<sim::SimulatedController> controller;
  std::optional<sim::SimulatedControllerReport> report;

  sim::SimulatedControllerReport stop() {
    if (!report && controller) {
      py::gil_scoped_release release;
      report = controller->stop();
    }
    if (!report) throw Exception(Error(CoreErrc::closed, "c4g: the simulated controller never started"));
    return *report;
  }
};

std::unique_ptr<Simulated> start_sim(const py::object& server, const std::string& robot, const std::string& program,
                                     const std::string& program_file, double duration_s, const std::string& reply_window,
                                     const std::string& bind) {
  sim::SimulatedControllerOptions o;
  o.server = py::isinstance<Session>(server) ? server.cast<Session&>().address : server.cast<std::string>();
  o.robot = robot;
  o.scenario_yaml = program;
  o.scenario_file = program_file;
  o.duration_s = finite_seconds(duration_s, "duration_s");
  if (reply_window == "period") o.reply_window = sim::ReplyWindow::period;
  else if (reply_window != "manual") invalid(fmt::format("reply_window must be 'manual' or 'period', got '{}'", reply_window));
  o.bind = bind;
  auto s = std::make_unique<Simulated>();
  py::gil_scoped_release release;
  s->controller.emplace(sim::SimulatedController::start(std::move(o)));
  return s;
}

// wait(): polls the run's end on a helper thread (GIL released); Ctrl-C stops the controller.
std::optional<sim::SimulatedControllerReport> wait_sim(Simulated& s, std::optional<double> timeout_s) {
  if (s.report) return s.report;
  auto& c = *s.controller;
  const auto bound = timeout_s ? std::chrono::steady_clock::now() +
                                     std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::duration<double>(finite_seconds(*timeout_s, "timeout_s")))
                               : std::chrono::steady_clock::time_point::max();
  auto quit = std::make_shared<std::atomic<bool>>(false);
  try {
    auto seen = interruptible([&c, quit, bound]() -> std::optional<sim::SimulatedControllerReport> {
      while (!*quit && std::chrono::steady_clock::now() < bound)
        if (auto r = c.wait_for(std::chrono::milliseconds(20))) return r;
      return std::nullopt;
    }, [quit] { *quit = true; });
    if (seen) s.report = seen;
    return seen;
  } catch (py::error_already_set&) {
    s.stop();
    throw;
  }
}

void bind_sim(py::module_& m) {
  py::class_<Simulated>(m, "SimulatedController",
                        "A C4G controller simulated in this process: plays a robot program against a server, one packet per "
                        "period on a thread of its own, and holds the server to the manual's reply window.")
      .def(py::init(&start_sim), py::arg("server"), py::kw_only(), py::arg("robot") = "six-axis", py::arg("program") = "",
           py::arg("program_file") = "", py::arg("duration_s") = 0.0, py::arg("reply_window") = "manual", py::arg("bind") = "",
           "server: a Server or its HOST:PORT. program: the robot program as YAML text (docs/c4g-simulator.md), or "
           "program_file; neither: the default program. reply_window: 'manual' (500 us after each send) or 'period' "
           "(lenient, for loaded machines). duration_s: stop after this long (0: when the program ends).")
      .def("wait", &wait_sim, py::arg("timeout_s") = py::none(),
           "Blocks (GIL released) until the program ended: the SimulatedControllerReport; None if timeout_s passed first. "
           "Ctrl-C stops the controller and raises KeyboardInterrupt.")
      .def("stop", &Simulated::stop, "Ends the run now; the report.")
      .def_property_readonly("running", [](const Simulated& s) { return s.controller && s.controller->running(); })
      .def_property_readonly("address", [](const Simulated& s) { return s.controller->local_address(); }, "The controller's own HOST:PORT.")
      .def("__repr__", [](const Simulated& s) { return fmt::format("<axon.c4g.SimulatedController {}>", s.controller->describe()); })
      .def("__enter__", [](py::object self) { return self; })
      .def("__exit__", [](Simulated& s, py::args) { s.stop(); });
}

}  // namespace

void bind_c4g(py::module_& m) {
  bind_apps(m);
  bind_report(m);
  bind_server(m);
  bind_sim_report(m);
  bind_sim(m);
}

}  // namespace axon::python
