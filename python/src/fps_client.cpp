// axon.fps: the blocking array client (fps::Client) and the simulated focal plane
// (fps::sim::SimulatedPlane). Every blocking call releases the GIL and answers Ctrl-C by
// interrupting the client (every robot stopped, the array locked), then raising KeyboardInterrupt.
#include "bindings.hpp"
#include "axon/fps/plan/arm_name.hpp"

#include "axon/fps/host/client.hpp"
#include "axon/fps/sim/firmware_marker.hpp"
#include "axon/fps/sim/simulated_plane.hpp"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <fmt/format.h>

namespace axon::python {

namespace {

using fps::Angles;
using fps::Client;

// Angles as Python sees them: (alpha, beta) in degrees.
std::optional<std::pair<double, double>> pair_of(const std::optional<Angles>& a) {
  if (!a) return std::nullopt;
  return std::pair{a->alpha, a->beta};
}

std::map<std::uint16_t, Angles> angles_of(const std::map<std::uint16_t, std::pair<double, double>>& in) {
  std::map<std::uint16_t, Angles> out;
  for (const auto& [id, p] : in) out[id] = {p.first, p.second};
  return out;
}

// One arm's points from an (n, 2) array: degrees, seconds after the start.
std::vector<std::pair<double, double>> arm_of(const py::object& points) {
  std::vector<std::pair<double, double>> out;
  if (points.is_none()) return out;
  const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(points);
  if (a && a.size() == 0) return out;
  if (!a || a.ndim() != 2 || a.shape(1) != 2)
    throw Exception(Error(CoreErrc::invalid_argument, "a trajectory arm is an (n, 2) array: degrees, seconds"));
  const auto v = a.unchecked<2>();
  for (py::ssize_t i = 0; i < v.shape(0); ++i) out.emplace_back(v(i, 0), v(i, 1));
  return out;
}

// A client's blocking call from Python: GIL released, Ctrl-C stops the robots.
template <class F>
auto blocking(Client& c, F call) {
  return interruptible(std::move(call), [&c] { c.interrupt("interrupted from Python (KeyboardInterrupt)"); });
}

void bind_outcomes(py::module_& m) {
  py::class_<fps::RobotStatus>(m, "RobotStatus", "One robot's row of the status table.")
      .def_readonly("id", &fps::RobotStatus::id)
      .def_readonly("bus", &fps::RobotStatus::bus)
      .def_readonly("state", &fps::RobotStatus::state, "ready, moving, collision, no-datum, bootloader, no-reply ...")
      .def_readonly("ready", &fps::RobotStatus::ready)
      .def_readonly("firmware", &fps::RobotStatus::firmware)
      .def_readonly("flags", &fps::RobotStatus::flags)
      .def_property_readonly("position", [](const fps::RobotStatus& r) { return pair_of(r.position); },
                             "(alpha, beta) in degrees, None when the robot did not give it.")
      .def_readonly("error", &fps::RobotStatus::error)
      .def("__repr__", [](const fps::RobotStatus& r) {
        return fmt::format("RobotStatus(id={}, state='{}', firmware='{}')", r.id, r.state, r.firmware);
      });
  py::class_<fps::RobotMove>(m, "RobotMove", "One robot of a move.")
      .def_readonly("id", &fps::RobotMove::id)
      .def_readonly("ok", &fps::RobotMove::ok)
      .def_readonly("state", &fps::RobotMove::state)
      .def_property_readonly("target", [](const fps::RobotMove& r) { return pair_of(r.target); })
      .def_property_readonly("reached", [](const fps::RobotMove& r) { return pair_of(r.reached); })
      .def_readonly("detail", &fps::RobotMove::detail)
      .def("__repr__", [](const fps::RobotMove& r) { return fmt::format("RobotMove(id={}, state='{}')", r.id, r.state); });
  py::class_<fps::MoveOutcome>(m, "MoveOutcome", "What a move did: completed, and per robot its end.")
      .def_readonly("completed", &fps::MoveOutcome::completed)
      .def_readonly("summary", &fps::MoveOutcome::summary)
      .def_readonly("robots", &fps::MoveOutcome::robots)
      .def("__bool__", [](const fps::MoveOutcome& o) { return o.completed; })
      .def("__repr__", [](const fps::MoveOutcome& o) {
        return fmt::format("MoveOutcome(completed={}, robots={})", o.completed ? "True" : "False", o.robots.size());
      });
  py::class_<fps::PlanOutcome>(m, "PlanOutcome", "The plan plan_and_move ran.")
      .def_readonly("verified", &fps::PlanOutcome::verified)
      .def_readonly("robots", &fps::PlanOutcome::robots)
      .def_readonly("not_reached", &fps::PlanOutcome::not_reached)
      .def_readonly("move_s", &fps::PlanOutcome::move_s)
      .def_readonly("plan_s", &fps::PlanOutcome::plan_s)
      .def_readonly("min_clearance_mm", &fps::PlanOutcome::min_clearance_mm)
      .def_property_readonly("ends", [](const fps::PlanOutcome& o) {
        std::map<std::uint16_t, std::pair<double, double>> out;
        for (const auto& [id, a] : o.ends) out[id] = {a.alpha, a.beta};
        return out;
      }, "{id: (alpha, beta)} where the plan leaves each robot.")
      .def_readonly("notes", &fps::PlanOutcome::notes)
      .def_readonly("outside_safe_zone", &fps::PlanOutcome::outside_safe_zone,
                    "Robots whose targets leave their safe zones (spec section 11).")
      .def_readonly("safe_zone", &fps::PlanOutcome::safe_zone, "Why, one line per robot.");
  py::class_<fps::PlanAndMoveOutcome>(m, "PlanAndMoveOutcome")
      .def_readonly("plan", &fps::PlanAndMoveOutcome::plan)
      .def_readonly("moved", &fps::PlanAndMoveOutcome::moved)
      .def_readonly("move", &fps::PlanAndMoveOutcome::move);
  py::class_<fps::StopOutcome>(m, "StopOutcome")
      .def_readonly("reason", &fps::StopOutcome::reason)
      .def_readonly("robots_reached", &fps::StopOutcome::robots_reached)
      .def_readonly("buses_sent", &fps::StopOutcome::buses_sent)
      .def_readonly("buses", &fps::StopOutcome::buses)
      .def("__str__", [](const fps::StopOutcome& o) { return o.text; });
  py::class_<fps::UnlockOutcome>(m, "UnlockOutcome")
      .def_readonly("acknowledged", &fps::UnlockOutcome::acknowledged)
      .def_readonly("silent", &fps::UnlockOutcome::silent);
  py::class_<fps::BackOffMove>(m, "BackOffMove", "One robot moved out of a contact, or why it was not.")
      .def_readonly("id", &fps::BackOffMove::id)
      .def_readonly("moved", &fps::BackOffMove::moved)
      .def_property_readonly("arm", [](const fps::BackOffMove& b) {
        return std::string(fps::arm_name(b.arm));
      })
      .def_readonly("step_deg", &fps::BackOffMove::step_deg)
      .def_property_readonly("start", [](const fps::BackOffMove& b) { return std::pair{b.from.alpha, b.from.beta}; })
      .def_property_readonly("end", [](const fps::BackOffMove& b) { return std::pair{b.to.alpha, b.to.beta}; })
      .def_readonly("clearance_before_mm", &fps::BackOffMove::clearance_before_mm)
      .def_readonly("clearance_after_mm", &fps::BackOffMove::clearance_after_mm)
      .def_readonly("problem", &fps::BackOffMove::problem);
  py::class_<fps::BackOffOutcome>(m, "BackOffOutcome")
      .def_readonly("contacts_before", &fps::BackOffOutcome::contacts_before)
      .def_readonly("moves", &fps::BackOffOutcome::moves)
      .def_readonly("contacts_after", &fps::BackOffOutcome::contacts_after)
      .def_readonly("ok", &fps::BackOffOutcome::ok)
      .def_readonly("summary", &fps::BackOffOutcome::summary)
      .def("__bool__", [](const fps::BackOffOutcome& o) { return o.ok; });
}

std::unique_ptr<Client> make_client(double reply_timeout_s, double call_timeout_s, double poll_interval_s,
                                    double discover_window_s, double position_tolerance_deg, const std::string& plc_address) {
  return std::make_unique<Client>(fps::ClientConfig{reply_timeout_s, call_timeout_s, poll_interval_s, discover_window_s,
                                                    position_tolerance_deg, false, false, plc_address});
}

fps::PlanSettings plan_settings(double speed_deg_s, double buffer_mm, std::uint64_t seed, bool park_bad_targets,
                                bool allow_partial, bool refuse_outside_safe_zone, bool start_by_sync_line) {
  return {speed_deg_s, buffer_mm, seed, park_bad_targets, allow_partial, refuse_outside_safe_zone, start_by_sync_line};
}

char arm_letter(const std::string& arm) {
  if (const auto a = fps::arm_from_name(arm)) return *a;
  if (arm == "a" || arm == "b") return arm[0];
  throw Exception(Error(CoreErrc::invalid_argument, fmt::format("arm '{}': use 'alpha' or 'beta'", arm)));
}

// The troubleshooting results (host/troubleshoot_types.hpp): interface document 9.4.2 and 9.4.3.
void bind_troubleshoot(py::module_& m) {
  using namespace fps::host;
  py::class_<FrictionPoint>(m, "FrictionPoint", "The median current at one motor speed during the test moves.")
      .def_readonly("speed_rpm", &FrictionPoint::speed_rpm)
      .def_readonly("current_percent", &FrictionPoint::current_percent)
      .def_readonly("readings", &FrictionPoint::readings)
      .def_readonly("move_s", &FrictionPoint::move_s)
      .def_readonly("eta_s", &FrictionPoint::eta_s);
  py::class_<FrictionFit>(m, "FrictionFit", "current = stiction + viscous * rpm / 1000 (percent).")
      .def_readonly("stiction_percent", &FrictionFit::stiction_percent)
      .def_readonly("viscous_percent_per_krpm", &FrictionFit::viscous_percent_per_krpm)
      .def_readonly("rms_percent", &FrictionFit::rms_percent)
      .def("at", &FrictionFit::at, py::arg("rpm"), "The fitted current (percent) at a motor speed.");
  py::class_<FrictionFinding>(m, "FrictionFinding", "One arm's friction trend.")
      .def_readonly("id", &FrictionFinding::id)
      .def_property_readonly("arm", [](const FrictionFinding& f) { return std::string(fps::arm_name(f.arm)); })
      .def_property_readonly("verdict", [](const FrictionFinding& f) { return to_string(f.verdict); },
                             "ok, increased, baseline (the first record) or failed")
      .def_readonly("points", &FrictionFinding::points)
      .def_readonly("fit", &FrictionFinding::fit)
      .def_readonly("growth", &FrictionFinding::growth, "current at the reference speed against the first record, minus 1")
      .def_property_readonly("baseline_time_utc", [](const FrictionFinding& f) {
        return f.baseline ? std::optional<std::string>(f.baseline->time_utc) : std::nullopt;
      })
      .def_readonly("step_deg", &FrictionFinding::step_deg)
      .def_readonly("problem", &FrictionFinding::problem)
      .def_readonly("advice", &FrictionFinding::advice);
  py::class_<FrictionReport>(m, "FrictionReport")
      .def_readonly("time_utc", &FrictionReport::time_utc)
      .def_readonly("arms", &FrictionReport::arms)
      .def_property_readonly("ok", &FrictionReport::ok)
      .def_property_readonly("summary", &FrictionReport::summary)
      .def("__bool__", &FrictionReport::ok);
  py::class_<HallFinding>(m, "HallFinding", "One arm's hall sensor and motor test.")
      .def_readonly("id", &HallFinding::id)
      .def_property_readonly("arm", [](const HallFinding& f) { return std::string(fps::arm_name(f.arm)); })
      .def_property_readonly("verdict", [](const HallFinding& f) { return to_string(f.verdict); },
                             "ok, no_hall_change, inaccurate or failed")
      .def_readonly("step_deg", &HallFinding::step_deg)
      .def_readonly("hall_before_deg", &HallFinding::hall_before_deg)
      .def_readonly("hall_after_deg", &HallFinding::hall_after_deg)
      .def_readonly("position_before_deg", &HallFinding::position_before_deg)
      .def_readonly("position_after_deg", &HallFinding::position_after_deg)
      .def_readonly("tracking_error_deg", &HallFinding::tracking_error_deg)
      .def_readonly("restored", &HallFinding::restored, "closed loop with collision detection again afterwards")
      .def_readonly("problem", &HallFinding::problem)
      .def_readonly("advice", &HallFinding::advice);
  py::class_<HallTestReport>(m, "HallTestReport")
      .def_readonly("arms", &HallTestReport::arms)
      .def_property_readonly("ok", &HallTestReport::ok)
      .def_property_readonly("summary", &HallTestReport::summary)
      .def("__bool__", &HallTestReport::ok);
}

void bind_upgrade(py::module_& m) {
  py::class_<fps::SextantUpgrade>(m, "SextantUpgrade", "Where one sextant's firmware upgrade stands.")
      .def_readonly("sextant", &fps::SextantUpgrade::sextant)
      .def_readonly("robots", &fps::SextantUpgrade::robots)
      .def_readonly("done", &fps::SextantUpgrade::done)
      .def_readonly("failed", &fps::SextantUpgrade::failed)
      .def_readonly("bytes", &fps::SextantUpgrade::bytes)
      .def_readonly("seconds", &fps::SextantUpgrade::seconds)
      .def_readonly("finished", &fps::SextantUpgrade::finished)
      .def_readonly("text", &fps::SextantUpgrade::text)
      .def("__repr__", [](const fps::SextantUpgrade& p) { return "<SextantUpgrade " + p.text + ">"; });
  py::class_<fps::RobotUpgrade>(m, "RobotUpgrade", "One robot of a firmware upgrade.")
      .def_readonly("id", &fps::RobotUpgrade::id)
      .def_readonly("sextant", &fps::RobotUpgrade::sextant)
      .def_readonly("outcome", &fps::RobotUpgrade::outcome, "ok, failed or not_attempted")
      .def_readonly("attempts", &fps::RobotUpgrade::attempts)
      .def_readonly("reason", &fps::RobotUpgrade::reason)
      .def_readonly("half_written", &fps::RobotUpgrade::half_written)
      .def_readonly("before", &fps::RobotUpgrade::before)
      .def_readonly("after", &fps::RobotUpgrade::after);
  py::class_<fps::FirmwareOutcome>(m, "FirmwareOutcome")
      .def_readonly("ok", &fps::FirmwareOutcome::ok)
      .def_readonly("robots", &fps::FirmwareOutcome::robots)
      .def_readonly("summary", &fps::FirmwareOutcome::summary)
      .def("__bool__", [](const fps::FirmwareOutcome& o) { return o.ok; });
}

// The layout check and the cold policy: what check_layout() and apply_cold_policy() return.
void bind_checks(py::module_& m) {
  using fps::BusRef;
  using fps::LayoutCheck;
  auto buses = [](const std::vector<BusRef>& b) {
    std::vector<std::string> out;
    for (const auto& r : b) out.push_back(r.to_string());
    return out;
  };
  auto misplaced = [buses](const std::vector<fps::Misplaced>& v) {
    std::map<std::uint16_t, std::vector<std::string>> out;
    for (const auto& x : v) out[x.id] = buses(x.found);
    return out;
  };
  py::class_<LayoutCheck>(m, "LayoutCheck", "GET_ID on every bus against the layout; buses as 'gw2/3' (gateway/channel).")
      .def_readonly("matched", &LayoutCheck::matched, "robots that answered on their own bus only")
      .def_readonly("missing", &LayoutCheck::missing, "robots of the layout nobody heard")
      .def_property_readonly("wrong_bus", [buses](const LayoutCheck& c) {
        std::map<std::uint16_t, std::pair<std::string, std::vector<std::string>>> out;
        for (const auto& w : c.wrong_bus) out[w.id] = {w.expected.to_string(), buses(w.found)};
        return out;
      }, "{id: (expected bus, [buses it answered on])}")
      .def_property_readonly("unexpected", [misplaced](const LayoutCheck& c) { return misplaced(c.unexpected); },
                             "{id: [buses]}: robots that answered but are not in the layout")
      .def_property_readonly("duplicated", [misplaced](const LayoutCheck& c) { return misplaced(c.duplicated); },
                             "{id: [buses]}: one id answering on several buses")
      .def_readonly("offline_answered", &LayoutCheck::offline_answered)
      .def_readonly("offline_silent", &LayoutCheck::offline_silent)
      .def_readonly("not_checked", &LayoutCheck::not_checked)
      .def_property_readonly("failed_buses", [](const LayoutCheck& c) {
        std::map<std::string, std::string> out;
        for (const auto& [bus, why] : c.failed_buses) out[bus.to_string()] = why;
        return out;
      })
      .def_property_readonly("ok", &LayoutCheck::ok)
      .def("__bool__", &LayoutCheck::ok)
      .def("__str__", &LayoutCheck::to_text);
  py::class_<fps::ColdOutcome>(m, "ColdOutcome", "What the cold policy decided from the PLC's temperatures and sent.")
      .def_readonly("motor_rpm", &fps::ColdOutcome::motor_rpm)
      .def_readonly("alpha_holding_pct", &fps::ColdOutcome::alpha_holding_pct)
      .def_readonly("beta_holding_pct", &fps::ColdOutcome::beta_holding_pct)
      .def_readonly("coldest_c", &fps::ColdOutcome::coldest_c, "degrees Celsius; None when no sensor read")
      .def_readonly("coldest_sensor", &fps::ColdOutcome::coldest_sensor)
      .def_readonly("applied", &fps::ColdOutcome::applied, "robots that took both settings")
      .def_readonly("failed", &fps::ColdOutcome::failed, "{id: why} for the robots that did not")
      .def_readonly("text", &fps::ColdOutcome::text)
      .def("__bool__", [](const fps::ColdOutcome& o) { return o.failed.empty(); })
      .def("__str__", [](const fps::ColdOutcome& o) { return o.text; });
}

void bind_client_upgrade(py::class_<Client>& c) {
  c.def("upgrade_firmware", [](Client& c, const py::bytes& image, const std::string& expected_version,
                               const std::vector<int>& sextants, unsigned retries, double power_off_s,
                               const py::object& progress) {
         const std::string raw = image;
         const std::vector<std::uint8_t> bytes(raw.begin(), raw.end());
         const fps::UpgradeSettings s{expected_version, sextants, retries, power_off_s};
         // Called on the client's thread: the callback runs with the GIL, and what it raises is kept
         // for later (the upgrade goes on: robots half-way through an image must not be left there).
         std::function<void(const fps::SextantUpgrade&)> report;
         std::optional<py::error_already_set> raised;
         if (!progress.is_none())
           report = [&progress, &raised](const fps::SextantUpgrade& p) {
             py::gil_scoped_acquire gil;
             try {
               progress(p);
             } catch (py::error_already_set& e) {
               if (!raised) raised = std::move(e);
             }
           };
         auto out = blocking(c, [&c, &bytes, s, &report] { return c.upgrade_firmware(bytes, s, report); });
         if (raised) throw std::move(*raised);
         return out;
       }, py::arg("image"), py::kw_only(), py::arg("expected_version") = "", py::arg("sextants") = std::vector<int>{},
       py::arg("retries") = 1, py::arg("power_off_s") = 1.0, py::arg("progress") = py::none(),
       "Firmware of every robot, sextant by sextant through the PLC (Client(plc_address=...), open(layout)): "
       "image as bytes; progress(SextantUpgrade) about once a second per sextant and at its end. Returns an "
       "FirmwareOutcome; raise the call timeout first for a whole plane.");
  c.def("check_layout", [](Client& c) { return blocking(c, [&c] { return c.check_layout(); }); },
        "GET_ID on every bus of the layout (open(layout) first), the answers against it: LayoutCheck.")
      .def("apply_cold_policy", [](Client& c) { return blocking(c, [&c] { return c.apply_cold_policy(); }); },
           "The cold-temperature policy once: the PLC's temperatures (Client(plc_address=...)) decide every "
           "robot's speed and holding currents, sent to all of them: ColdOutcome.");
}

void bind_client_troubleshoot(py::class_<Client>& c) {
  c.def("friction_survey", [](Client& c, const std::vector<std::uint16_t>& ids, std::vector<double> speeds_rpm,
                              double step_deg, double growth_limit, double reference_rpm, bool alpha, bool beta,
                              const std::string& history_file) {
         fps::host::FrictionOptions o;
         o.speeds_rpm = std::move(speeds_rpm);
         o.step_deg = step_deg;
         o.growth_limit = growth_limit;
         o.reference_rpm = reference_rpm;
         o.alpha = alpha;
         o.beta = beta;
         return blocking(c, [&c, ids, o, history_file] { return c.friction_survey(ids, o, history_file); });
       }, py::arg("ids") = std::vector<std::uint16_t>{}, py::kw_only(),
       py::arg("speeds_rpm") = std::vector<double>{1000, 2000, 3000, 4000}, py::arg("step_deg") = 10.0,
       py::arg("growth_limit") = 0.25, py::arg("reference_rpm") = 3000.0, py::arg("alpha") = true, py::arg("beta") = true,
       py::arg("history_file") = "",
       "Friction trend (interface document 9.4.2): per arm, test moves there and back at each motor speed, the "
       "current fitted against speed and judged against the arm's first record in history_file (CSV; the new "
       "records are appended). Every test move is proven clear of the neighbours first. Needs the layout.")
      .def("hall_test", [](Client& c, std::uint16_t id, double step_deg, std::uint32_t speed_rpm, double tolerance_deg,
                           bool alpha, bool beta) {
         fps::host::HallTestOptions o;
         o.step_deg = step_deg;
         o.speed_rpm = speed_rpm;
         o.tolerance_deg = tolerance_deg;
         o.alpha = alpha;
         o.beta = beta;
         return blocking(c, [&c, id, o] { return c.hall_test(id, o); });
       }, py::arg("id"), py::kw_only(), py::arg("step_deg") = 5.0, py::arg("speed_rpm") = 1000,
       py::arg("tolerance_deg") = 0.04, py::arg("alpha") = true, py::arg("beta") = true,
       "Hall sensor and motor test (9.4.3): per arm, open loop without collision detection, hall and position "
       "around a slow move, then closed loop with detection again. Needs the layout.");
}

void bind_client_moves(py::class_<Client>& c) {
  c.def("goto", [](Client& c, const std::map<std::uint16_t, std::pair<double, double>>& targets) {
         const auto t = angles_of(targets);
         return blocking(c, [&c, t] { return c.goto_absolute(t); });
       }, py::arg("targets"), "Moves the robots {id: (alpha, beta)} (degrees) at once and waits for them.")
      .def("run_trajectories", [](Client& c, const py::dict& paths, bool by_sync_line) {
         std::map<std::uint16_t, fps::ArmPath> p;
         for (const auto& [id, arms] : paths) {
           const auto pair = arms.cast<py::sequence>();
           if (pair.size() != 2) throw Exception(Error(CoreErrc::invalid_argument, "each robot's path is (alpha, beta)"));
           p[id.cast<std::uint16_t>()] = {arm_of(pair[0]), arm_of(pair[1])};
         }
         return blocking(c, [&c, p, by_sync_line] { return c.run_trajectories(p, by_sync_line); });
       }, py::arg("paths"), py::kw_only(), py::arg("by_sync_line") = false,
       "{id: (alpha, beta)}: each arm an (n, 2) array of degrees and seconds after the start (the robot adds "
       "where it stands); uploads, starts every robot together, follows and checks the ends. by_sync_line: the "
       "start is a pulse of the PLC's sync line (open(layout) with plc_address), not the broadcast.")
      .def("plan_and_move", [](Client& c, const py::object& targets, double speed_deg_s, double buffer_mm,
                               std::uint64_t seed, bool park_bad_targets, bool allow_partial, bool refuse_outside_safe_zone,
                               bool start_by_sync_line) {
         const auto s = plan_settings(speed_deg_s, buffer_mm, seed, park_bad_targets, allow_partial, refuse_outside_safe_zone,
                                      start_by_sync_line);
         if (py::isinstance<py::str>(targets)) {
           const auto file = targets.cast<std::string>();
           return blocking(c, [&c, file, s] { return c.plan_and_move(file, s); });
         }
         const auto t = angles_of(targets.cast<std::map<std::uint16_t, std::pair<double, double>>>());
         return blocking(c, [&c, t, s] { return c.plan_and_move(t, s); });
       }, py::arg("targets"), py::kw_only(), py::arg("speed_deg_s") = 12.0, py::arg("buffer_mm") = 2.0,
       py::arg("seed") = 1, py::arg("park_bad_targets") = true, py::arg("allow_partial") = false,
       py::arg("refuse_outside_safe_zone") = false, py::arg("start_by_sync_line") = false,
       "Plans from where every robot of the layout stands to {id: (alpha, beta)} or a target file (robots not "
       "listed fold), verifies and runs it; targets outside their safe zones are reported, or refused.")
      .def("back_off", [](Client& c, const std::vector<std::uint16_t>& ids) {
         return blocking(c, [&c, ids] { return c.back_off(ids); });
       }, py::arg("ids") = std::vector<std::uint16_t>{},
       "Moves robots out of a contact: the listed ones (after a collision and unlock(), 2 degrees or more away), "
       "or every robot in contact; one arm at a time, each move certified against the neighbours. Needs the layout.")
      .def("emergency_stop", [](Client& c, const std::string& reason) {
         return blocking(c, [&c, reason] { return c.emergency_stop(reason); });
       }, py::arg("reason") = "emergency stop", "Locks the array and aborts every robot on every bus.")
      .def("stop", [](Client& c, bool clear_flags) { blocking(c, [&c, clear_flags] { c.stop(clear_flags); }); },
           py::arg("clear_flags") = false, "TRAJECTORY_ABORT on every bus, without locking.")
      .def("unlock", [](Client& c) { return blocking(c, [&c] { return c.unlock(); }); },
           "STOP_TRAJECTORY on every bus (clears collision flags), then unlocks.")
      .def("interrupt", &Client::interrupt, py::arg("reason"),
           "From any thread, without waiting: stops every robot and locks, as Ctrl-C does.");
}

void bind_client(py::module_& m) {
  py::class_<Client> c(m, "Client", "The robots of a focal plane (or of some buses), from blocking calls.");
  c.def(py::init(&make_client), py::kw_only(), py::arg("reply_timeout_s") = 1.0, py::arg("call_timeout_s") = 600.0,
        py::arg("poll_interval_s") = 0.25, py::arg("discover_window_s") = 0.5, py::arg("position_tolerance_deg") = 0.1,
        py::arg("plc_address") = "")
      .def("open", [](Client& c, const std::vector<std::string>& specs) { blocking(c, [&c, specs] { c.open(specs); }); },
           py::arg("bus_specs"), "Opens buses by spec (cannet://HOST:PORT/N, socketcand://..., socketcan:can0).")
      .def("open", [](Client& c, const fps::FocalPlane& plane, const std::map<std::uint16_t, std::string>& addresses) {
             blocking(c, [&c, plane, addresses] { c.open(plane, addresses); });
           }, py::arg("layout"), py::arg("gateway_addresses") = std::map<std::uint16_t, std::string>{},
           "Opens every gateway of a layout (at its address, or gateway_addresses[id]).")
      .def("set_layout", &Client::set_layout, py::arg("layout"))
      .def_property_readonly("is_open", &Client::is_open)
      .def("set_call_timeout", &Client::set_call_timeout, py::arg("seconds"))
      .def("discover", [](Client& c) { return blocking(c, [&c] { return c.discover(); }); },
           "GET_ID on every bus, then firmware and status of every robot found: [RobotStatus].")
      .def("status", [](Client& c) { return blocking(c, [&c] { return c.status(); }); },
           "Firmware, status and position of every known robot: [RobotStatus] (status_table(): numpy).")
      .def_property_readonly("robots", &Client::robots)
      .def_property_readonly("locked", &Client::locked)
      .def_property_readonly("lock_reason", &Client::lock_reason)
      .def("close", &Client::close, py::call_guard<py::gil_scoped_release>(),
           "Stops what this client set moving, closes the connections.")
      .def("__enter__", [](py::object self) { return self; })
      .def("__exit__", [](Client& c, py::args) {
        py::gil_scoped_release release;
        c.close();
      });
  bind_client_moves(c);
  bind_client_troubleshoot(c);
  bind_client_upgrade(c);
}

void bind_plane(py::module_& m) {
  using fps::sim::SimulatedPlane;
  m.def("simulated_firmware_image", [](const std::string& version, std::size_t size) {
         const auto bytes = fps::sim::make_firmware_image(fps::protocol::FirmwareVersion::parse(version).value(), size).value();
         return py::bytes(reinterpret_cast<const char*>(bytes.data()), bytes.size());
       }, py::arg("version"), py::arg("size") = 3000,
       "A firmware image the simulated robots accept and then report as `version` (XX.YY.ZZ): for trying "
       "Client.upgrade_firmware against a SimulatedPlane.");
  py::class_<SimulatedPlane>(m, "SimulatedPlane",
                             "A whole focal plane simulated in this process: its robots behind CAN@net gateway "
                             "emulators on loopback TCP, and the PLC emulator.")
      .def(py::init([](const py::object& layout, double time_scale, std::uint64_t seed, bool random_start, bool plc) {
             fps::sim::SimulatedPlaneOptions o{time_scale, seed, random_start, plc};
             if (py::isinstance<py::str>(layout)) {
               const auto name = layout.cast<std::string>();
               py::gil_scoped_release release;
               return std::make_unique<SimulatedPlane>(name, o);
             }
             const auto plane = layout.cast<fps::FocalPlane>();
             py::gil_scoped_release release;
             return std::make_unique<SimulatedPlane>(plane, o);
           }),
           py::arg("layout") = "benchtop", py::kw_only(), py::arg("time_scale") = 10.0, py::arg("seed") = 1,
           py::arg("random_start") = false, py::arg("plc") = true,
           "layout: 'benchtop' (6 robots), 'default' (500), a layout file or a Layout. time_scale: simulated "
           "seconds per wall second.")
      .def_property_readonly("layout", [](const SimulatedPlane& s) { return s.plane(); },
                             "The layout with the emulators' addresses (Client.open takes it).")
      .def_property_readonly("gateway_addresses", &SimulatedPlane::gateway_addresses)
      .def_property_readonly("bus_specs", &SimulatedPlane::bus_specs)
      .def_property_readonly("plc_address", &SimulatedPlane::plc_address)
      .def("arms", [](const SimulatedPlane& s, std::uint16_t id) { return pair_of(s.arms(id)); }, py::arg("id"),
           "(alpha, beta) where the robot's arms physically are; None for an unknown robot.")
      .def_property_readonly("collisions", &SimulatedPlane::collisions, "Collisions the simulator saw.")
      .def_property_readonly("sync_edges", &SimulatedPlane::sync_edges, "Rising edges of the sync line the PLC emulator drove.")
      .def("inject_collision", &SimulatedPlane::inject_collision, py::arg("id"),
           "Makes the robot report a collision of its beta arm now (it stops and sets the flag).")
      .def("set_friction_fault", [](SimulatedPlane& s, std::uint16_t id, const std::string& arm, int level) {
             const char a = arm_letter(arm);
             py::gil_scoped_release release;
             s.set_friction_fault(id, a, level);
           }, py::arg("id"), py::arg("arm"), py::arg("level"),
           "Extra friction on one arm ('alpha' or 'beta'), on the collision margin's scale (0 removes it).")
      .def("set_hall_fault", [](SimulatedPlane& s, std::uint16_t id, const std::string& arm, const std::string& fault) {
             const char a = arm_letter(arm);
             py::gil_scoped_release release;
             s.set_hall_fault(id, a, fault);
           }, py::arg("id"), py::arg("arm"), py::arg("fault"),
           "A hall sensor 'stuck', a motor 'dead', or 'none', on one arm.")
      .def("stop", &SimulatedPlane::stop, py::call_guard<py::gil_scoped_release>())
      .def("__enter__", [](py::object self) { return self; })
      .def("__exit__", [](SimulatedPlane& s, py::args) {
        py::gil_scoped_release release;
        s.stop();
      });
}

}  // namespace

void bind_fps_client(py::module_& m) {
  bind_outcomes(m);
  bind_troubleshoot(m);
  bind_upgrade(m);
  bind_checks(m);
  bind_client(m);
  bind_plane(m);
}

}  // namespace axon::python
