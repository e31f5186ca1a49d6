// `axon demo`, fps section: the default focal plane (500 simulated robots on 24 buses behind 6
// CAN@net gateway emulators, plus the PLC emulator) driven over loopback TCP by the host: layout
// check, discovery, the cold policy from the PLC, status sweep, a fold, then a collision-free random reconfiguration of every
// robot from the path planner, both started by the PLC's sync line, final positions and the
// simulator's collision count verified, each phase timed against the wire time of its busiest bus.
// The simulated plane runs on a thread of its own (core::LoopThread), the host on the caller's.
#include "demo_fps.hpp"
#include "axon/core/progress.hpp"

#include "axon/fps/host/cold_control.hpp"
#include "axon/fps/host/focal_plane_array.hpp"
#include "axon/fps/host/trajectory_build.hpp"
#include "axon/fps/plan/layout_model.hpp"
#include "axon/fps/plan/planner.hpp"
#include "axon/fps/plan/problems.hpp"
#include "axon/fps/sim/focal_plane_sim.hpp"
#include "layout_name.hpp"
#include "fps_stop.hpp"
#include "run.hpp"
#include "axon/core/loop_thread.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <sys/resource.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>

namespace axon::app {

namespace host = fps::host;

namespace {

// The report's summary plus the detail of the first robots that did not complete.
std::string failure_text(const host::TrajectoryReport& rep) {
  std::string out = rep.summary();
  int shown = 0;
  for (const auto& r : rep.robots) {
    if (r.state == host::RobotState::completed || r.state == host::RobotState::withdrawn) continue;
    if (shown++ == 10) break;
    out += fmt::format("\n  robot {}: {}: {}", r.id, host::to_string(r.state), r.detail);
  }
  return out;
}

constexpr double kTimeScale = 10.0;  // simulated seconds per real second

using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;
double seconds(core::Duration d) { return std::chrono::duration<double>(d).count(); }

// CPU time of the calling thread (s).
double thread_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) / 1e9;
}

// Exact wire bits carried so far by each bus of the simulated plane.
std::map<fps::BusRef, std::uint64_t> wire_bits(const fps::sim::FocalPlaneSimulator& sim, const fps::FocalPlane& plane) {
  std::map<fps::BusRef, std::uint64_t> out;
  for (const auto& b : plane.buses()) out[b] = sim.medium(b)->stats().bits;
  return out;
}

// Wire time (s, 1 Mbit/s) of the busiest bus between two snapshots.
double floor_s(const std::map<fps::BusRef, std::uint64_t>& before, const std::map<fps::BusRef, std::uint64_t>& after) {
  std::uint64_t most = 0;
  for (const auto& [b, bits] : after) most = std::max(most, bits - before.at(b));
  return static_cast<double>(most) / 1e6;
}

struct Phase {
  std::string name;
  double seconds = 0;
  double floor = 0;  // wire time of the busiest bus; 0: not a bus-bound phase
};

// The largest distance of one arm from its planned end, over the robots' final readings.
double worst_reading(const host::TrajectoryReport& run, const std::map<std::uint16_t, host::ArmAngles>& ends) {
  double worst = 0;
  for (const auto& rr : run.robots)
    if (rr.reached) {
      const auto& end = ends.at(rr.id);
      worst = std::max({worst, std::abs(rr.reached->alpha - end.alpha), std::abs(rr.reached->beta - end.beta)});
    }
  return worst;
}

// Step 7: each phase against its floor (or, for the move, the trajectory's real-time duration).
void print_timings(const std::vector<Phase>& phases, double move_wall_s) {
  fmt::print("7. timings (floor: wire time of the busiest bus for the frames the phase put on it, 1 Mbit/s):\n");
  for (const auto& p : phases) {
    if (p.floor > 0) {
      fmt::print("   {:<12} {:7.3f} s   floor {:7.4f} s   ratio {:5.2f}\n", p.name, p.seconds, p.floor, p.seconds / p.floor);
    } else if (p.name == "move") {
      fmt::print("   {:<12} {:7.3f} s   trajectory {:.3f} s (real time)   ratio {:5.2f}\n", p.name, p.seconds, move_wall_s,
                 p.seconds / move_wall_s);
    } else {
      fmt::print("   {:<12} {:7.3f} s\n", p.name, p.seconds);
    }
  }
}

using Bits = std::map<fps::BusRef, std::uint64_t>;

// The steps of the demo, sharing the simulated plane (on its own thread), the host's array and the
// rows of the timing table.
class FpsDemo {
 public:
  FpsDemo(const fps::FocalPlane& plane, core::LoopThread& sim_thread, fps::sim::FocalPlaneSimulator& sim,
          host::FocalPlaneArray& fpa, std::uint64_t seed)
      : plane_(plane), sim_thread_(sim_thread), sim_(sim), fpa_(fpa), array_(fpa.array()), seed_(seed) {}

  asio::awaitable<void> run(asio::any_io_executor ex, const host::FocalPlaneArrayOptions& ao);

 private:
  Bits wire_now() { return sim_thread_.call([&] { return wire_bits(sim_, plane_); }); }
  asio::awaitable<void> discover(const host::FocalPlaneArrayOptions& ao);
  asio::awaitable<void> apply_cold_policy();
  asio::awaitable<host::StatusTable> status_sweep();
  asio::awaitable<bool> fold(const host::StatusTable& table);
  fps::plan::Plan plan_random(const fps::plan::CollisionModel& model);
  asio::awaitable<std::optional<host::TrajectoryReport>> move(asio::any_io_executor ex,
                                                              const fps::plan::CollisionModel& model,
                                                              const fps::plan::Plan& plan);
  asio::awaitable<void> show_progress(const bool& moving, const bool& finished, double move_s, bool& done);
  std::uint64_t verify(const host::TrajectoryReport& run, const fps::plan::CollisionModel& model,
                       const fps::plan::Plan& plan);
  void print_resources();
  asio::awaitable<void> stopped_by_signal();

  const fps::FocalPlane& plane_;
  core::LoopThread& sim_thread_;
  fps::sim::FocalPlaneSimulator& sim_;
  host::FocalPlaneArray& fpa_;
  host::Array& array_;
  std::uint64_t seed_;
  std::vector<Phase> phases_;
};

// Step 2: the layout check and discovery, then the cold policy.
asio::awaitable<void> FpsDemo::discover(const host::FocalPlaneArrayOptions& ao) {
  auto t0 = Clock::now();
  const auto check = co_await fpa_.check_layout();
  fmt::print("2. layout check (GET_ID broadcast on all {} buses at once, {:.1f} s window): {} matched, {} missing, "
             "{} unexpected, {} on the wrong bus ({:.2f} s)\n",
             fpa_.bus_count(), seconds(ao.check_window), check.matched.size(), check.missing.size(),
             check.unexpected.size(), check.wrong_bus.size(), seconds(Clock::now() - t0));
  if (!check.ok()) throw Exception(Error(host::HostErrc::sequence_failed, "layout check failed:\n" + check.to_text()));
  const auto bits0 = wire_now();
  t0 = Clock::now();
  auto disc = co_await fpa_.discover();
  const auto found = need(std::move(disc));
  phases_.push_back({"discovery", seconds(Clock::now() - t0), floor_s(bits0, wire_now())});
  fmt::print("   discovery (GET_ID until every robot of the bus answered, then firmware and status of each): "
             "{} robots, {} problems ({:.2f} s)\n",
             found.table.rows.size(), found.problems.size(), phases_.back().seconds);
  co_await apply_cold_policy();
}

// The cold policy once, from the PLC's temperatures (speed and holding current are volatile in the
// robots, so a host sets them after every power-up).
asio::awaitable<void> FpsDemo::apply_cold_policy() {
  const auto t0 = Clock::now();
  host::ColdControl cold(fpa_);
  auto applied = co_await cold.step(true);
  if (!applied) {
    fmt::print("   cold policy not applied: {}\n", applied.error().message());
    co_return;
  }
  const auto& rep = applied.value();
  std::string line = rep.decision.report();
  line = line.substr(0, line.find('\n'));
  const std::string why = rep.decision.notes.empty() ? std::string() : " (" + rep.decision.notes.front() + ")";
  fmt::print("   {}{}: applied to {} robots, {} failed ({:.2f} s)\n", line, why, rep.applied.size(), rep.failed.size(),
             seconds(Clock::now() - t0));
}

// Step 3: firmware, status and position of every robot.
asio::awaitable<host::StatusTable> FpsDemo::status_sweep() {
  const auto bits0 = wire_now();
  const auto t0 = Clock::now();
  auto table = co_await array_.status_table(true);
  phases_.push_back({"status sweep", seconds(Clock::now() - t0), floor_s(bits0, wire_now())});
  std::size_t ready = 0;
  for (const auto& row : table.rows) ready += row.error.empty() && row.position ? 1 : 0;
  fmt::print("3. status sweep: {} of {} robots answered with status and position ({:.2f} s)\n", ready, table.rows.size(),
             phases_.back().seconds);
  co_return table;
}

// Step 4: fold every robot to alpha 0 (beta stays folded: the arms never leave their cells), every
// robot the same trajectory at the same instant, so neighbours stay translated copies of each
// other. False: stopped by a signal.
asio::awaitable<bool> FpsDemo::fold(const host::StatusTable& table) {
  auto moves = need(host::straight_moves(table, {0, 180}, 20, 16.0));
  auto r = co_await fpa_.run_trajectories(std::move(moves.trajectories), {}, true);
  const auto folded = need(std::move(r));
  fmt::print("4. fold (20 points per arm, 16 s simulated, started by the PLC's sync line): {}\n", folded.outcome);
  if (received_stop_signal().load() != 0) co_return false;
  if (!folded.completed) throw Exception(Error(host::HostErrc::sequence_failed, failure_text(folded)));
  co_return true;
}

// Step 5, planning: a random reconfiguration of every robot, collision-free from the folded
// lattice (docs/fps-plan.md) and verified by the planner's independent checker.
fps::plan::Plan FpsDemo::plan_random(const fps::plan::CollisionModel& model) {
  fps::plan::PlanRequest req;
  req.frozen = fps::plan::frozen_robots(plane_);
  req.current.assign(model.size(), fps::plan::Pose{0, 180});
  req.target = fps::plan::random_poses(model, seed_);
  for (std::size_t i = 0; i < model.size(); ++i)
    if (req.frozen[i] || !array_.find(static_cast<std::uint16_t>(model.robot(i).id()))) {
      req.frozen[i] = true;
      req.target[i] = req.current[i];
    }
  fps::plan::PlannerOptions po;
  po.seed = seed_;
  auto plan = need(fps::plan::plan_moves(model, req, po));
  fmt::print("5. planned a random reconfiguration of {} robots in {:.2f} s (engine {:.2f} s, checker {:.2f} s): "
             "{} reach their targets, {} parked or held; {:.1f} s move, {} points per arm (median, max {}); "
             "checker {} (min clearance {:.3f} mm at the full buffer)\n",
             model.size(), plan.stats.plan_s, plan.stats.search_s, plan.stats.check_s, model.size() - plan.not_reached,
             plan.not_reached, plan.stats.duration_s, plan.stats.median_points, plan.stats.max_points,
             plan.verified ? "verified" : "REJECTED", plan.check.min_clearance_mm);
  if (!plan.verified) throw Exception(Error(host::HostErrc::sequence_failed, "the planner's checker rejected the plan"));
  if (plan.not_reached > 0) fmt::print("{}", plan.summary(model));
  return plan;
}

// A progress line while the robots move: the host's view of one robot per sextant.
asio::awaitable<void> FpsDemo::show_progress(const bool& moving, const bool& finished, double move_s, bool& done) {
  while (!moving && !finished) co_await core::sleep_for(20ms);
  const auto start = Clock::now();
  std::vector<std::uint16_t> sample;
  for (const auto& [s, ids] : sim_thread_.call([&] { return sim_.sextants(); }))
    if (!ids.empty()) sample.push_back(ids.front());
  core::ProgressOptions po;
  po.quiet_for = {};
  core::Progress line(stdout, po);  // rewritten in place on a terminal, a line a second into a file
  while (!finished) {
    std::string where;
    for (auto id : sample) {
      auto p = co_await array_.find(id)->read_position();
      if (p) where += fmt::format(" {}:{:.0f}/{:.0f}", id, p.value().alpha, p.value().beta);
    }
    const double el = seconds(Clock::now() - start), total = move_s / kTimeScale;
    line.update(fmt::format("   moving {:4.1f} of {:.1f} s ({:3.0f}%), alpha/beta of one robot per sextant:{}", el, total,
                            std::min(100.0, 100.0 * el / total), where));
    co_await core::sleep_for(250ms);
  }
  line.finish();
  done = true;
}

// Step 5, the move: the planned trajectories started by the sync line, with a progress line and
// the upload, start and move timed. Empty: stopped by a signal.
asio::awaitable<std::optional<host::TrajectoryReport>> FpsDemo::move(asio::any_io_executor ex,
                                                                     const fps::plan::CollisionModel& model,
                                                                     const fps::plan::Plan& plan) {
  const double move_s = plan.stats.duration_s;
  auto moves = need(host::plan_trajectories(model, plan));
  std::map<std::string, Bits> marks;
  bool moving = false, finished = false, progress_done = false;
  host::TrajectoryOptions to;
  to.on_phase = [&](std::string_view phase) {
    marks[std::string(phase)] = wire_now();
    if (phase == "started") moving = true;
    if (phase == "finished") finished = true;
  };
  asio::co_spawn(ex, show_progress(moving, finished, move_s, progress_done), asio::detached);
  auto r = co_await fpa_.run_trajectories(std::move(moves), to, true);
  finished = true;
  while (!progress_done) co_await core::sleep_for(20ms);  // let the progress line end (it reads these locals)
  const auto run = need(std::move(r));
  if (received_stop_signal().load() != 0) {
    fmt::print("   planned move: {}\n", run.outcome);
    co_return std::nullopt;
  }
  fmt::print("   planned move of {} robots ({:.1f} s simulated), started by the sync line: {}\n", run.robots.size(),
             move_s, run.outcome);
  if (marks.contains("checked") && marks.contains("uploaded"))
    phases_.push_back({"upload", seconds(run.timings.upload), floor_s(marks["checked"], marks["uploaded"])});
  if (marks.contains("uploaded") && marks.contains("started")) phases_.push_back({"sync start", seconds(run.timings.start), 0});
  phases_.push_back({"move", seconds(run.timings.move), 0});
  co_return run;
}

// Step 6: the host's final reading of every robot and the simulator's own arms against the planned
// ends. Returns the simulator's collision count.
std::uint64_t FpsDemo::verify(const host::TrajectoryReport& run, const fps::plan::CollisionModel& model,
                              const fps::plan::Plan& plan) {
  std::map<std::uint16_t, host::ArmAngles> ends;
  for (std::size_t i = 0; i < model.size(); ++i)
    ends[static_cast<std::uint16_t>(model.robot(i).id())] = {plan.robots[i].end.alpha_deg, plan.robots[i].end.beta_deg};
  const double worst_host = worst_reading(run, ends);
  double worst_sim = 0;
  std::size_t at_target = 0;
  sim_thread_.call([&] {  // the simulator's own arms, read on its thread
    for (const auto& rr : run.robots) {
      if (const auto* m = sim_.simulator().find(rr.id)) {
        const auto& target = ends.at(rr.id);
        const double e = std::max(std::abs(m->physical_deg(fps::sim::Arm::alpha) - target.alpha),
                                  std::abs(m->physical_deg(fps::sim::Arm::beta) - target.beta));
        worst_sim = std::max(worst_sim, e);
        at_target += e < 0.1 ? 1 : 0;
      }
    }
  });
  const auto st = sim_thread_.call([&] { return sim_.simulator().stats(); });
  const std::uint64_t collisions = st.neighbour_collisions + st.obstacle_collisions;
  fmt::print("6. verified: {} of {} robots at their planned end; worst error {:.4f} deg (host reading), {:.4f} deg "
             "(simulated arms); {} collisions\n",
             at_target, run.robots.size(), worst_host, worst_sim, collisions);
  return collisions;
}

// CPU of both threads, peak memory and the host's request counters.
void FpsDemo::print_resources() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  const auto totals = array_.client_totals();
  const double host_cpu = thread_cpu_s();
  const double sim_cpu = sim_thread_.call([] { return thread_cpu_s(); });
  const auto overflows = sim_thread_.call([&] { return sim_.simulator().receive_overflows(); });
  fmt::print("   CPU: host thread {:.1f} s, simulator thread {:.1f} s; peak memory {} MB; {} requests, {} timeouts, "
             "{} receive overflows\n",
             host_cpu, sim_cpu, u.ru_maxrss / 1024, totals.sent, totals.timeouts, overflows);
}

// A signal stopped a move: every robot was stopped; the demo ends here.
asio::awaitable<void> FpsDemo::stopped_by_signal() {
  co_await fpa_.close();
  report_signal_stop(array_);
}

asio::awaitable<void> FpsDemo::run(asio::any_io_executor ex, const host::FocalPlaneArrayOptions& ao) {
  co_await discover(ao);
  const auto table = co_await status_sweep();
  if (!co_await fold(table)) {
    co_await stopped_by_signal();
    co_return;
  }
  const auto model = need(fps::plan::model_from_layout(plane_));
  const auto plan = plan_random(model);
  const auto run = co_await move(ex, model, plan);
  if (!run) {
    co_await stopped_by_signal();
    co_return;
  }
  if (verify(*run, model, plan) > 0)
    throw Exception(Error(host::HostErrc::collision, "the simulator saw collisions during the planned move"));
  print_timings(phases_, plan.stats.duration_s / kTimeScale);
  print_resources();
  co_await fpa_.close();
  fmt::print("   the same from a shell: `axon sim fps --layout default` (docs/fps-simulator.md), then `axon fps ...`\n");
  if (!run->completed) throw Exception(Error(host::HostErrc::sequence_failed, failure_text(*run)));
}

}  // namespace

asio::awaitable<void> demo_fps(asio::any_io_executor ex, std::function<void(std::function<void()>)> set_on_signal) {
  fmt::print("\naxon demo: a focal plane of fiber positioners (fps)\n\n");
  const auto plane = need(resolve_layout("default"));
  fps::sim::FocalPlaneSimOptions so;
  so.simulator.time_scale = kTimeScale;
  so.seed = 7;
  core::LoopThread sim_thread;
  auto sim = sim_thread.call([&] { return need(fps::sim::FocalPlaneSimulator::start(sim_thread.executor(), plane, so)); });
  struct StopSim {
    core::LoopThread& t;
    fps::sim::FocalPlaneSimulator& s;
    ~StopSim() {
      t.call([this] { s.stop(); });
      t.stop();
    }
  } stop_sim{sim_thread, *sim};
  const auto sextants = sim_thread.call([&] { return sim->sextants(); });
  const auto gateways = sim_thread.call([&] { return sim->gateways(); });
  const auto plc_endpoint = sim_thread.call([&] { return sim->plc()->endpoint(); });
  fmt::print("1. simulated focal plane '{}': {} robots in {} sextants on {} buses (1 Mbit/s, exact frame bits,\n"
             "   real-time pacing) behind {} CAN@net gateway emulators; PLC emulator at {}; time x{};\n"
             "   robots start at random alpha with beta folded (seed {})\n",
             plane.name(), sim_thread.call([&] { return sim->simulator().size(); }), sextants.size(), plane.buses().size(),
             gateways.size(), plc_endpoint.to_string(), kTimeScale, so.seed);

  host::FocalPlaneArrayOptions ao;
  for (const auto& g : gateways) ao.addresses[g.id] = g.endpoint;
  ao.plc = plc_endpoint;
  ao.array.positioner.poll_interval = 100ms;
  auto connected = co_await host::FocalPlaneArray::connect(ex, plane, ao);
  auto fpa = need(std::move(connected));
  stop_robots_on_signal(set_on_signal, fpa->array());
  FpsDemo demo(plane, sim_thread, *sim, *fpa, so.seed);
  co_await demo.run(ex, ao);
}

}  // namespace axon::app
