// `axon fps plane ...`: the whole focal plane of a layout at once (every gateway, every bus, the
// PLC): layout check, status of every robot, a coordinated move of every robot started by
// broadcast or by the sync line, firmware upgrade, the cold policy and correction iterations after
// a measurement of the fibres.
#include "commands.hpp"
#include "axon/fps/plan/arm_name.hpp"
#include "axon/fps/host/back_off.hpp"
#include "axon/fps/host/focal_plane_array.hpp"
#include "axon/fps/host/cold_control.hpp"
#include "axon/fps/host/plane_correct.hpp"
#include "axon/fps/host/plane_upgrade.hpp"
#include "axon/fps/host/trajectory_build.hpp"
#include "axon/fps/host/trajectory_speed.hpp"
#include "axon/fps/host/troubleshoot.hpp"
#include "axon/fps/host/troubleshoot_json.hpp"
#include "checks.hpp"
#include "id_list.hpp"
#include "fps_json.hpp"
#include "fps_stop.hpp"
#include "axon/fps/plan/layout_model.hpp"
#include "layout_name.hpp"
#include "axon/net/endpoint.hpp"
#include "axon/core/progress.hpp"
#include "axon/web/fps_host_page.hpp"
#include "axon/web/server.hpp"
#include "run.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/this_coro.hpp>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <map>
#include <memory>

namespace axon::app {
namespace {

namespace host = fps::host;
namespace protocol = fps::protocol;
using json = nlohmann::json;

struct PlaneArgs {
  std::string layout;
  std::string plc;
  bool json = false;              // check, status, move: one JSON document on stdout, nothing else
  double window_s = 0.5;
  double alpha = 0;
  double beta = 180;
  double duration_s = 10;
  int points = 20;
  bool fit_duration = false;      // move: use the slowest robot's duration when --duration is too short
  double max_rpm = host::kMaxMotorRpm;  // move: motor speed limit
  double gear_ratio = host::kGearRatio;
  bool sync = false;
  double sync_hold_s = 0.5;       // move --sync: how long the sync line stays high
  bool approach = false;          // move: GO_TO_RELATIVE (0, 0) afterwards (interface document 7.3)
  std::string image;              // upgrade
  std::string version;            // upgrade: expected version
  std::vector<int> sextants;      // upgrade
  double power_off_s = 1.0;       // upgrade
  bool watch = false;             // cold
  double period_s = 60;           // cold --watch
  double for_s = 0;               // cold --watch: 0 until a signal
  std::string targets;            // correct
  std::vector<std::string> measured;  // correct: one file per round
  double tolerance_um = 5;        // correct
  int iterations = 3;             // correct
  double wait_s = 600;            // correct: for each measurement file to appear
  std::vector<std::string> backoff_ids;  // backoff: empty = every robot in contact
  bool unlock = false;                   // backoff: STOP_TRAJECTORY on every bus first
  std::vector<std::string> friction_ids; // friction: empty = every robot
  std::string history;                   // friction: the history CSV
  host::FrictionOptions friction;        // friction: speeds, step, growth limit, reference speed
  int hall_id = 0;                       // halltest
  host::HallTestOptions hall;            // halltest: step, speed, tolerance
  std::string arm = "both";              // friction, halltest: alpha, beta or both
  std::string http;                      // the host's view of the plane on HOST:PORT (empty: none)
  double http_linger_s = 0;              // with --http: keep serving this long after the action
};


std::vector<std::uint8_t> read_image(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Exception(usage(fmt::format("cannot open {}", path)));
  std::vector<std::uint8_t> image((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw Exception(usage(fmt::format("cannot read {}", path)));
  return image;
}

core::Duration to_duration(double s) { return std::chrono::duration_cast<core::Duration>(std::chrono::duration<double>(s)); }

host::FocalPlaneArrayOptions array_options(const PlaneArgs& a) {
  host::FocalPlaneArrayOptions o;
  o.check_window = to_duration(a.window_s);
  o.sync_hold = to_duration(a.sync_hold_s);
  if (!a.plc.empty()) o.plc = need(net::parse_endpoint(a.plc, 502));
  return o;
}

// --http: the host's view of the plane (web::FpsHostPage): its server on a thread of its own, the
// view reading and publishing on the array's executor.
std::unique_ptr<web::FpsHostPage> open_host_page(const std::string& address, host::FocalPlaneArray& fpa,
                                                 asio::any_io_executor ex, bool quiet_stdout) {
  web::FpsHostPageOptions po;
  po.server = web::server_address(address);
  auto page = std::make_unique<web::FpsHostPage>(po, fpa, ex);
  std::FILE* out = quiet_stdout ? stderr : stdout;  // --json: stdout carries the one document
  std::fprintf(out, "listening http %s\n", page->where().c_str());
  std::fflush(out);
  return page;
}

// --http-linger: the view goes on reading and publishing after the action, until the time is up
// or a stop signal, which is then the normal end (the robots are not moving any more).
asio::awaitable<void> linger_host_page(double seconds, const SignalHook& on_signal) {
  const auto stop = std::make_shared<bool>(false);
  on_signal([stop, on_signal] {
    on_signal.signal_ends_normally();
    *stop = true;
  });
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (!*stop && std::chrono::steady_clock::now() < until) co_await core::sleep_for(std::chrono::milliseconds(50));
}

// What the view may read during an action: nothing during a discovery (it replaces robot handles)
// or actions whose timing or measurements extra traffic would disturb; everything otherwise.
web::HostReading reading_for(const std::string& action) {
  if (action == "status" || action == "check" || action == "upgrade" || action == "friction" || action == "halltest")
    return web::HostReading::none;
  return web::HostReading::all;
}

double phase_s(core::Duration d) { return std::chrono::duration<double>(d).count(); }

void print_plane_json(const json& j) {
  std::fputs(j.dump(2).c_str(), stdout);
  std::fputc('\n', stdout);
}

// Per bus: robots that started (whatever happened next) and robots in the run.
std::map<std::size_t, std::pair<int, int>> started_per_bus(const host::TrajectoryReport& rep) {
  std::map<std::size_t, std::pair<int, int>> per_bus;
  for (const auto& rr : rep.robots) {
    auto& c = per_bus[rr.bus];
    ++c.second;
    const bool went = rr.state == host::RobotState::started || rr.state == host::RobotState::completed ||
                      rr.state == host::RobotState::position_mismatch || rr.state == host::RobotState::timeout ||
                      rr.state == host::RobotState::stopped || rr.state == host::RobotState::collided;
    c.first += went ? 1 : 0;
  }
  return per_bus;
}

json maybe_angles_json(const std::optional<host::ArmAngles>& a) {
  return a ? json{{"alpha", a->alpha}, {"beta", a->beta}} : json(nullptr);
}

json move_json(host::FocalPlaneArray& fpa, const host::TrajectoryReport& rep, double duration_s, bool sync) {
  auto& array = fpa.array();
  json j{{"started", rep.started}, {"completed", rep.completed}, {"outcome", rep.outcome}, {"duration_s", duration_s},
         {"start_by", sync ? "sync line" : "broadcast"},
         {"timings_s", {{"upload", phase_s(rep.timings.upload)}, {"start", phase_s(rep.timings.start)}, {"move", phase_s(rep.timings.move)}}},
         {"locked", array.lock_state().locked ? json(array.lock_state().reason) : json(nullptr)},
         {"link_stops", fpa.link_stops()}, {"buses", json::array()}, {"robots", json::array()}};
  for (const auto& [b, c] : started_per_bus(rep))
    j["buses"].push_back(json{{"bus", fpa.bus_ref(b).to_string()}, {"started", c.first}, {"robots", c.second}});
  for (const auto& r : rep.robots)
    j["robots"].push_back(json{{"id", r.id}, {"state", host::to_string(r.state)}, {"detail", r.detail},
                               {"target", maybe_angles_json(r.target)}, {"reached", maybe_angles_json(r.reached)}});
  return j;
}

// Robots per state ("no answer" for a robot that did not answer), problems, silent robots.
int plane_status(const host::FocalPlaneArray& fpa, const host::DiscoveryReport& found, bool as_json) {
  std::map<std::string, int> states;
  for (const auto& row : found.table.rows) ++states[row.error.empty() ? row.state() : "no answer"];
  const int rc = states.contains("no answer") || !found.problems.empty() ? 1 : 0;
  if (as_json) {
    json j{{"robots", found.table.rows.size()}, {"buses", fpa.bus_count()}, {"states", states},
           {"problems", found.problems}, {"silent", json::array()}};
    for (const auto& row : found.table.rows)
      if (!row.error.empty()) j["silent"].push_back(json{{"id", row.id}, {"error", row.error}});
    print_plane_json(j);
    return rc;
  }
  std::printf("%zu robots known on %zu buses\n", found.table.rows.size(), fpa.bus_count());
  for (const auto& [s, n] : states) std::printf("  %s: %d\n", s.c_str(), n);
  for (const auto& p : found.problems) std::printf("problem: %s\n", p.c_str());
  for (const auto& row : found.table.rows)
    if (!row.error.empty()) std::printf("  positioner %u: %s\n", unsigned{row.id}, row.error.c_str());
  return rc;
}

// Every known robot from where it is straight to (alpha, beta); robots without a position are told on stderr.
host::StraightMoves straight_moves(const host::StatusTable& table, const PlaneArgs& a, double duration_s) {
  auto moves = need(host::straight_moves(table, {a.alpha, a.beta}, a.points, duration_s));
  for (const auto& line : moves.left_out) std::fprintf(stderr, "%s; left out\n", line.c_str());
  return moves;
}

// The duration to use: --duration when every robot can make it, the slowest robot's with
// --fit-duration; otherwise a usage error that says what would do.
double move_duration(const host::StatusTable& table, const PlaneArgs& a, const fps::plan::SpeedLimits& limits) {
  const auto straight = straight_moves(table, a, a.duration_s);
  const auto& moves = straight.trajectories;
  const auto slowest = host::slowest_robot(moves, straight.starts, limits);
  if (!slowest || slowest->too_fast == 0) return a.duration_s;
  const double needed = host::feasible_duration_s(slowest->needed_s);
  const auto what = fmt::format("{} of {} robots cannot make {:g} s at {:g} deg/s (alpha) and {:g} deg/s (beta): the "
                                "slowest robot (positioner {}) needs {:.1f} s",
                                slowest->too_fast, moves.size(), a.duration_s, limits.alpha_deg_s, limits.beta_deg_s,
                                slowest->id, needed);
  if (!a.fit_duration) throw Exception(usage(fmt::format("{}; use --duration {:.1f} or --fit-duration", what, needed)));
  std::fprintf(stderr, "%s: using --duration %.1f\n", what.c_str(), needed);
  return needed;
}

// Progress of a move on stderr once the robots started (core::Progress: nothing for the first 2 s,
// then a line per second into a file or pipe, one line rewritten in place on a terminal).
struct MoveProgress {
  double total_s = 0;
  std::size_t robots = 0;
  bool started = false;
  bool finished = false;
  bool done = false;  // the progress coroutine has ended
};

asio::awaitable<void> show_progress(MoveProgress& p) {
  while (!p.started && !p.finished) co_await core::sleep_for(std::chrono::milliseconds(20));
  const auto t0 = std::chrono::steady_clock::now();
  core::Progress line(stderr);
  while (!p.finished) {
    const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    line.update(fmt::format("moving {} robots: {:.0f} of {:.1f} s ({:.0f}%)", p.robots, el, p.total_s,
                            std::min(100.0, 100.0 * el / p.total_s)));
    co_await core::sleep_for(std::chrono::milliseconds(100));
  }
  line.finish();
  p.done = true;
}

std::size_t approached(const host::TrajectoryReport& rep) {
  return static_cast<std::size_t>(std::count_if(rep.robots.begin(), rep.robots.end(), [](const auto& r) { return r.approached; }));
}

asio::awaitable<int> plane_move(host::FocalPlaneArray& fpa, const PlaneArgs& a, web::FpsHostView* view) {
  const auto limits = fps::plan::SpeedLimits::from_motor(a.max_rpm, a.gear_ratio);
  const auto table = co_await fpa.array().status_table(true);
  const double duration_s = move_duration(table, a, limits);
  auto t = straight_moves(table, a, duration_s).trajectories;
  if (t.empty()) throw Exception(Error(host::HostErrc::not_ready, "no robot reported its position: nothing to move"));
  host::TrajectoryOptions to;
  to.speed_limits = limits;
  to.final_approach = a.approach;
  MoveProgress progress{duration_s, t.size()};
  to.on_phase = [&progress, view](std::string_view phase) {
    progress.started = progress.started || phase == "started";
    // The page's reads: none from the check to the start (the upload is the bus's busiest time),
    // positions while the robots move (the move polls their status words), everything after.
    if (view && phase == "started") view->set_reading(web::HostReading::positions);
    if (view && phase == "finished") view->set_reading(web::HostReading::all);
  };
  if (view) view->set_reading(web::HostReading::none);
  asio::co_spawn(co_await asio::this_coro::executor, show_progress(progress), asio::detached);
  auto r = co_await fpa.run_trajectories(std::move(t), to, a.sync);
  if (view) view->set_reading(web::HostReading::all);
  progress.finished = true;
  while (!progress.done) co_await core::sleep_for(std::chrono::milliseconds(10));
  const auto rep = need(std::move(r));
  const auto& lock = fpa.array().lock_state();
  if (a.json) {
    auto j = move_json(fpa, rep, duration_s, a.sync);
    if (a.approach) j["approached"] = approached(rep);
    print_plane_json(j);
    co_return motion_exit_code(rep.completed, fpa.array());
  }
  for (const auto& [b, c] : started_per_bus(rep))
    std::printf("bus %s: %d of %d robots started\n", fpa.bus_ref(b).to_string().c_str(), c.first, c.second);
  std::printf("start by %s; upload %.3f s, start %.3f s, move %.3f s\n", a.sync ? "the sync line" : "broadcast",
              phase_s(rep.timings.upload), phase_s(rep.timings.start), phase_s(rep.timings.move));
  if (a.approach)
    std::printf("final approach (0.9 deg back and forth): %zu of %zu robots at their targets, %.3f s\n", approached(rep),
                rep.robots.size(), phase_s(rep.timings.approach));
  if (lock.locked) std::printf("locked: %s\n", lock.reason.c_str());
  for (const auto& l : fpa.link_stops()) std::printf("%s\n", l.c_str());
  std::fputs(rep.summary().c_str(), stdout);
  co_return motion_exit_code(rep.completed, fpa.array());
}

using SetOnSignal = SignalHook;

// Correction iterations: each round reads the next --measured file (waiting for it to appear),
// corrects the robots outside tolerance and waits for them to arrive.
asio::awaitable<int> plane_correct(host::FocalPlaneArray& fpa, const PlaneArgs& a, const fps::FocalPlane& plane,
                                   const SetOnSignal& set_on_signal) {
  const auto targets = need(fps::plan::load_targets(a.targets));
  const auto model = need(fps::plan::model_from_layout(plane));
  std::vector<std::int32_t> known;
  for (const auto& r : model.robots()) known.push_back(r.id());
  host::CorrectionRunOptions co;
  co.iterations = a.iterations;
  co.correction.tolerance_mm = a.tolerance_um / 1000.0;
  co.on_round = [](const host::CorrectionRound& r) {
    std::fputs(r.to_text().c_str(), stdout);
    std::fflush(stdout);
  };
  const auto source = host::measurement_files(a.measured, known, a.wait_s, [](const std::string& path) {
    std::fprintf(stderr, "waiting for %s\n", path.c_str());
    std::fflush(stderr);
  });
  stop_robots_on_signal(set_on_signal, fpa.array());
  auto run = co_await host::correct_positions(fpa.array(), model, targets, source, co);
  const auto& lock = fpa.array().lock_state();
  if (lock.locked) std::printf("locked: %s\n", lock.reason.c_str());
  std::fputs(run.summary().c_str(), stdout);
  co_return motion_exit_code(run.ok(), fpa.array());
}

// `fps plane cold`: the cold policy once, or with --watch every period until a signal (its normal
// end) or --for. A report is printed when settings went out (and always without --watch).
asio::awaitable<int> plane_cold(host::FocalPlaneArray& fpa, const PlaneArgs& a, const SetOnSignal& set_on_signal) {
  host::ColdControl cold(fpa);
  int rc = 0;
  const auto print = [&rc, watch = a.watch](const Result<host::ColdApplyReport>& r) {
    if (!r) {
      std::printf("cold policy: %s\n", r.error().message().c_str());
      rc = 1;
    } else if (r.value().sent || !watch) {
      std::fputs(r.value().to_text().c_str(), stdout);
      rc = r.value().failed.empty() ? 0 : 1;
    }
    std::fflush(stdout);
  };
  bool stop = false;
  set_on_signal([&stop, set_on_signal] {
    set_on_signal.signal_ends_normally();  // --watch runs until a signal: its normal end
    stop = true;
  });
  if (a.watch) {
    auto watching = cold.watch(to_duration(a.period_s), &stop, print, to_duration(a.for_s));
    co_await std::move(watching);
  } else {
    auto r = co_await cold.step(true);
    print(r);
  }
  set_on_signal([] {});
  co_return rc;
}

// `fps plane backoff`: robots out of a contact (host/back_off.hpp); 0 when none is left.
asio::awaitable<int> plane_back_off(host::FocalPlaneArray& fpa, const PlaneArgs& a, const fps::FocalPlane& plane) {
  const auto model = need(fps::plan::model_from_layout(plane));
  if (a.unlock) {
    auto u = co_await fpa.array().unlock();
    need(std::move(u));
  }
  host::BackOffRequest request;
  if (!a.backoff_ids.empty()) request.ids = need(parse_id_lists(a.backoff_ids));
  auto r = co_await host::back_off(fpa.array(), model, std::move(request));
  const auto rep = need(std::move(r));
  if (a.json) {
    nlohmann::json moves = nlohmann::json::array();
    for (const auto& s : rep.steps)
      moves.push_back({{"id", s.id}, {"moved", s.moved}, {"arm", fps::arm_name(s.plan.arm)},
                       {"step_deg", s.plan.step_deg}, {"from", {s.plan.from.alpha_deg, s.plan.from.beta_deg}},
                       {"to", {s.plan.to.alpha_deg, s.plan.to.beta_deg}}, {"clearance_before_mm", s.plan.clearance_before_mm},
                       {"clearance_after_mm", s.plan.clearance_after_mm}, {"problem", s.problem}});
    print_plane_json({{"ok", rep.ok()}, {"contacts_before", rep.contacts_before}, {"moves", moves},
                      {"contacts_after", rep.contacts_after}});
  } else {
    std::fputs(rep.summary().c_str(), stdout);
  }
  co_return rep.ok() ? 0 : 1;
}

void choose_arms(const std::string& arm, bool& alpha, bool& beta) {
  alpha = arm != "beta";
  beta = arm != "alpha";
}

// `fps plane friction` (interface document 9.4.2): the trend against the history file, which gets
// the new records; 0 when nothing increased or failed.
asio::awaitable<int> plane_friction(host::FocalPlaneArray& fpa, const PlaneArgs& a, const fps::FocalPlane& plane) {
  const auto model = need(fps::plan::model_from_layout(plane));
  auto o = a.friction;
  choose_arms(a.arm, o.alpha, o.beta);
  if (!a.history.empty()) o.history = need(host::load_friction_history(a.history));
  std::vector<std::uint16_t> ids;
  if (!a.friction_ids.empty()) ids = need(parse_id_lists(a.friction_ids));
  auto r = co_await host::friction_survey(fpa.array(), model, std::move(ids), std::move(o));
  const auto rep = need(std::move(r));
  if (!a.history.empty()) need(host::append_friction_history(a.history, rep.records()));
  if (a.json) print_plane_json(host::to_json(rep));
  else std::fputs(rep.summary().c_str(), stdout);
  co_return rep.ok() ? 0 : 1;
}

// `fps plane halltest ID` (9.4.3); 0 when every arm tested is ok.
asio::awaitable<int> plane_hall_test(host::FocalPlaneArray& fpa, const PlaneArgs& a, const fps::FocalPlane& plane) {
  const auto model = need(fps::plan::model_from_layout(plane));
  auto o = a.hall;
  choose_arms(a.arm, o.alpha, o.beta);
  auto r = co_await host::hall_test(fpa.array(), model, static_cast<std::uint16_t>(a.hall_id), o);
  const auto rep = need(std::move(r));
  if (a.json) print_plane_json(host::to_json(rep));
  else std::fputs(rep.summary().c_str(), stdout);
  co_return rep.ok() ? 0 : 1;
}

// One `fps plane` action on the connected plane; returns the exit code.
asio::awaitable<int> plane_action(host::FocalPlaneArray& fpa, const PlaneArgs& a, const std::string& action,
                                  const fps::FocalPlane& plane, const SetOnSignal& set_on_signal,
                                  const std::vector<std::uint8_t>& image, const host::PlaneUpgradeOptions& uo,
                                  web::FpsHostView* view) {
  int rc = 0;
  if (action == "check") {
    const auto check = co_await fpa.check_layout();
    if (a.json) print_plane_json(layout_check_json(check));
    else std::fputs(check.to_text().c_str(), stdout);
    rc = check.ok() ? 0 : 1;
  } else if (action == "status") {
    auto d = co_await fpa.discover();
    const auto found = need(std::move(d));
    rc = plane_status(fpa, found, a.json);
  } else if (action == "move") {
    stop_robots_on_signal(set_on_signal, fpa.array());
    rc = co_await plane_move(fpa, a, view);
  }
  if (action == "cold") rc = co_await plane_cold(fpa, a, set_on_signal);
  if (action == "backoff") {
    stop_robots_on_signal(set_on_signal, fpa.array());
    rc = co_await plane_back_off(fpa, a, plane);
  }
  if (action == "friction" || action == "halltest") {
    stop_robots_on_signal(set_on_signal, fpa.array());
    // Not one ?: with a co_await on each side: gcc 12 can destroy such temporaries twice.
    if (action == "friction") rc = co_await plane_friction(fpa, a, plane);
    else rc = co_await plane_hall_test(fpa, a, plane);
  }
  if (action == "correct") rc = co_await plane_correct(fpa, a, plane, set_on_signal);
  if (action == "upgrade") {
    if (!uo.expected_version) std::printf("no --version given: versions are reported, not checked\n");
    auto r = co_await host::upgrade_plane(fpa, image, uo);
    const auto rep = need(std::move(r));
    std::fputs(rep.summary().c_str(), stdout);
    rc = rep.ok() ? 0 : 1;
  }
  co_return rc;
}

int run_plane(const PlaneArgs& a, const std::string& action) {
  const auto plane = need(resolve_layout(a.layout));
  return run_command([&](asio::io_context& io, auto set_on_signal) -> asio::awaitable<int> {
    const auto ex = io.get_executor();
    std::vector<std::uint8_t> image;
    host::PlaneUpgradeOptions uo;
    if (action == "upgrade") {
      image = read_image(a.image);
      if (!a.version.empty()) uo.expected_version = need(protocol::FirmwareVersion::parse(a.version));
      uo.sextants = a.sextants;
      uo.power_off_time = std::chrono::duration_cast<core::Duration>(std::chrono::duration<double>(a.power_off_s));
      uo.progress = [](const host::SextantProgress& p) {
        std::fprintf(stderr, "%s\n", p.to_text().c_str());
        std::fflush(stderr);
      };
    }
    if (action == "correct") {
      // The first measurement must be there and readable before anything is connected.
      const auto model = need(fps::plan::model_from_layout(plane));
      std::vector<std::int32_t> known;
      for (const auto& r : model.robots()) known.push_back(r.id());
      need(host::load_measurements(a.measured.at(0), known));
      need(fps::plan::load_targets(a.targets));
    }
    auto connected = co_await host::FocalPlaneArray::connect(ex, plane, array_options(a));
    auto fpa = need(std::move(connected));
    const auto page = a.http.empty() ? nullptr : open_host_page(a.http, *fpa, ex, a.json);
    if (page) page->view().set_reading(reading_for(action));
    int rc = 0;
    std::exception_ptr failure;
    try {
      rc = co_await plane_action(*fpa, a, action, plane, set_on_signal, image, uo, page ? &page->view() : nullptr);
    } catch (...) {
      failure = std::current_exception();  // close first: the robots and connections are left tidy
      // The action's own hook may point into its finished frame (cold's stop flag): a signal
      // during the close stops the array instead.
      stop_robots_on_signal(set_on_signal, fpa->array());
    }
    std::fflush(stdout);
    if (page && !failure && a.http_linger_s > 0) {
      if (action != "move") page->view().set_reading(web::HostReading::all);  // the action's own traffic is over
      co_await linger_host_page(a.http_linger_s, set_on_signal);
      stop_robots_on_signal(set_on_signal, fpa->array());
    }
    if (page) page->stop();
    co_await fpa->close();
    if (page) co_await page->finish();  // the view reads the array: its last round ends before the array goes
    set_on_signal([] {});  // the array is closed: a later signal has nothing to stop
    report_signal_stop(fpa->array());
    if (failure) std::rethrow_exception(failure);
    co_return rc;
  });
}

}  // namespace

void add_fps_plane_commands(CLI::App& app, GlobalOptions& global) {
  CLI::App* fps_cmd = app.get_subcommand("fps");
  const auto args = std::make_shared<PlaneArgs>();  // shared with the callbacks
  auto& a = *args;
  auto* p = fps_cmd->add_subcommand("plane", "the whole focal plane of a layout: every gateway and bus, and the PLC");
  p->require_subcommand(1);
  p->add_option("--layout", a.layout, "layout: default, benchtop or FILE (gateway addresses from it)")->required();
  p->add_option("--plc", a.plc, "the PLC at HOST[:PORT] (needed for --sync)");
  p->add_flag("--json", a.json, "check, status, move, backoff, friction, halltest: one JSON document on stdout and nothing else");
  p->add_option("--http", a.http,
                "serve the host's view of the plane (what the robots' replies say), /api/state and /metrics on "
                "HOST:PORT (PORT alone: 127.0.0.1; port 0: any free port, printed as 'listening http HOST:PORT')");
  p->add_option("--http-linger", a.http_linger_s,
                "with --http: keep serving (and reading the robots) this many seconds after the action; a stop signal "
                "ends the wait")
      ->check(CLI::Range(0.0, 86400.0));
  p->fallthrough();  // --json may also follow the action
  p->add_subcommand("check", "GET_ID on every bus at once, compared with the layout")->callback([args, &global] {
    global.exit_code = run_plane(*args, "check");
  });
  auto* ck = p->get_subcommand("check");
  ck->add_option("--window", a.window_s, "seconds to collect GET_ID answers (default 0.5)")->check(positive());
  p->add_subcommand("status", "discovery: firmware and status of every robot")->callback([args, &global] {
    global.exit_code = run_plane(*args, "status");
  });
  auto* mv = p->add_subcommand("move", "every robot straight to one (alpha, beta) by a trajectory, all at once");
  mv->add_option("--alpha", a.alpha, "degrees (default 0)");
  mv->add_option("--beta", a.beta, "degrees (default 180: folded)");
  mv->add_option("--duration", a.duration_s, "seconds of the trajectory (default 10)")->check(positive());
  mv->add_flag("--fit-duration", a.fit_duration,
               "when a robot cannot make --duration within its speed limit, use the duration the slowest robot needs");
  mv->add_option("--max-rpm", a.max_rpm, "motor speed limit, rpm at the motor (default 5000, the actuators' requirement)")
      ->check(positive());
  mv->add_option("--gear-ratio", a.gear_ratio, "motor turns per arm turn (default 1000)")->check(positive());
  mv->add_option("--points", a.points, "points per arm (default 20)")->check(CLI::Range(1, 1000));
  mv->add_flag("--sync", a.sync, "start with the PLC's sync line instead of the START_TRAJECTORY broadcast");
  mv->add_option("--sync-hold", a.sync_hold_s,
                 "seconds the sync line stays high for the start (default 0.5, as in service; robots need a few ms)")
      ->check(CLI::Range(0.001, 10.0));
  mv->add_flag("--approach", a.approach,
               "afterwards GO_TO_RELATIVE (0, 0) on every robot that arrived: the 0.9 deg back-and-forth that leaves the "
               "arms outside the backlash, where correction iterations start (interface document 7.3)");
  mv->callback([args, &global] { global.exit_code = run_plane(*args, "move"); });
  auto* up = p->add_subcommand("upgrade",
                               "firmware of every robot, sextant by sextant: power-cycled into the bootloader by the PLC, "
                               "upgraded (one retry), powered back, version checked (needs --plc)");
  up->add_option("--image", a.image, "firmware image file")->required()->check(CLI::ExistingFile);
  up->add_option("--version", a.version, "version the robots must run afterwards (XX.YY.ZZ); without it, not checked");
  up->add_option("--sextant", a.sextants, "only these sextants (repeatable; default every sextant with robots)")
      ->check(CLI::Range(1, 6));
  up->add_option("--power-off", a.power_off_s, "seconds without positioner power before powering up (default 1)")
      ->check(CLI::Range(0.0, 60.0));
  auto* cd = p->add_subcommand("cold",
                               "cold-temperature policy: PLC temperatures -> speed and holding current of every robot "
                               "(needs --plc)");
  cd->add_flag("--watch", a.watch, "keep going: read every --period, send only when the decision changes");
  cd->add_option("--period", a.period_s, "seconds between readings with --watch (default 60)")->check(CLI::Range(0.05, 86400.0));
  cd->add_option("--for", a.for_s, "with --watch: stop after this many seconds (default: at a signal)")->check(non_negative());
  cd->callback([args, &global] {
    if (args->plc.empty()) throw Exception(usage("fps plane cold needs --plc"));
    global.exit_code = run_plane(*args, "cold");
  });
  auto* cr = p->add_subcommand("correct",
                               "correction iterations: robots whose measured fibre is outside tolerance get a correction "
                               "move (GO_TO_ABSOLUTE_POSITION), one round per --measured file");
  cr->add_option("--targets", a.targets, "target file (.yaml/.csv, docs/fps-plan.md)")->required()->check(CLI::ExistingFile);
  cr->add_option("--measured", a.measured,
                 "measured fibre positions, CSV robot,x,y[,fibre] in mm (repeatable, one per round, in order; "
                 "files after the first are waited for)")
      ->required();
  cr->add_option("--tolerance-um", a.tolerance_um, "robots closer than this to their target are left alone (default 5)")
      ->check(CLI::Range(0.0, 10000.0));
  cr->add_option("--iterations", a.iterations, "most rounds that send corrections (default 3)")->check(CLI::Range(1, 100));
  cr->add_option("--wait", a.wait_s, "seconds to wait for each later --measured file to appear (default 600)")
      ->check(CLI::Range(0.0, 86400.0));
  cr->callback([args, &global] { global.exit_code = run_plane(*args, "correct"); });
  auto* bo = p->add_subcommand("backoff",
                               "move robots out of a contact, one arm by 2 degrees or more, each move certified against the "
                               "neighbours (after a collision and unlock, or a power loss mid-move)");
  bo->add_option("ids", a.backoff_ids, "robots to move (3, 1-6, 1,4,9); default: every robot in contact");
  bo->add_flag("--unlock", a.unlock, "first STOP_TRAJECTORY on every bus, which clears the collision flags (9.4.1)");
  bo->callback([args, &global] { global.exit_code = run_plane(*args, "backoff"); });
  auto* fr = p->add_subcommand("friction",
                               "friction trend (interface document 9.4.2): per arm, test moves there and back at several "
                               "speeds, current against speed fitted and compared with the arm's first record in --history");
  fr->add_option("ids", a.friction_ids, "robots to measure (3, 1-6, 1,4,9); default: every robot");
  fr->add_option("--history", a.history, "CSV history of earlier fits; the new ones are appended (created when missing)");
  fr->add_option("--speeds", a.friction.speeds_rpm, "motor speeds in rpm (default 1000 2000 3000 4000)")->delimiter(',');
  fr->add_option("--step", a.friction.step_deg, "test move in degrees at the arm (default 10)")->check(CLI::Range(2.01, 45.0));
  fr->add_option("--growth-limit", a.friction.growth_limit, "increased beyond this growth, e.g. 0.25 = +25 % (default)")
      ->check(positive());
  fr->add_option("--reference-rpm", a.friction.reference_rpm, "speed the trend compares the current at (default 3000)")
      ->check(positive());
  fr->add_option("--arm", a.arm, "alpha, beta or both (default)")->check(CLI::IsMember({"alpha", "beta", "both"}));
  fr->callback([args, &global] { global.exit_code = run_plane(*args, "friction"); });
  auto* ht = p->add_subcommand("halltest",
                               "hall sensor and motor test of one robot (interface document 9.4.3): open loop without "
                               "collision detection, a slow move, hall against position; closed loop restored");
  ht->add_option("id", a.hall_id, "the robot")->required()->check(CLI::Range(1, 2047));
  ht->add_option("--step", a.hall.step_deg, "test move in degrees (default 5)")->check(CLI::Range(0.51, 45.0));
  ht->add_option("--speed", a.hall.speed_rpm, "motor speed in rpm (default 1000)")->check(CLI::Range(1, 10000));
  ht->add_option("--tolerance", a.hall.tolerance_deg, "hall against position after the move, degrees (default 0.04)")
      ->check(positive());
  ht->add_option("--arm", a.arm, "alpha, beta or both (default)")->check(CLI::IsMember({"alpha", "beta", "both"}));
  ht->callback([args, &global] { global.exit_code = run_plane(*args, "halltest"); });
  up->callback([args, &global] {
    if (args->plc.empty()) throw Exception(usage("fps plane upgrade needs --plc"));
    global.exit_code = run_plane(*args, "upgrade");
  });
}

}  // namespace axon::app
