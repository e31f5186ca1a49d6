// fps soak: the default 500-robot focal plane (24 buses behind 6 CAN@net gateway emulators, the
// PLC emulator) on a thread of its own, driven over loopback TCP by fps::host::FocalPlaneArray,
// plan-and-move cycles to random targets for --minutes while a seeded plan injects, one per cycle
// in a shuffled order: a collision mid-move, a power cycle of a sextant (gateway and robots)
// between moves, a power loss of a sextant mid-move, a gateway connection reset during the upload,
// a robot that goes silent before the upload, a channel that goes bus-off mid-move, and nothing.
// All the while the robots' replies are dropped, delayed and duplicated at low rates.
//
// Checked per cycle: every injected fault was reported by the host (lock reason, link stops, the
// run's report), no run started unless every robot had loaded its trajectory, every collision
// stopped all 24 buses, no robot still moves once the run returned after a stop, the simulator saw
// no collision between arms (but for a power loss mid-move: robots that stop dead may be touched
// by a neighbour before the host's abort reaches it; counted, and the host moves them apart with
// host::back_off); before each cycle the host has reconnected every gateway by itself and the
// plane is back in service (unlock, every robot ready, no robot in contact). At the end: RSS and
// descriptors.
//
//   build/release/soak/axon_soak_fps --minutes 30 --seed 1
#include "soak.hpp"

#include "axon/core/loop_thread.hpp"
#include "axon/fps/host/back_off.hpp"
#include "axon/fps/host/focal_plane_array.hpp"
#include "axon/fps/host/plan_and_move.hpp"
#include "axon/fps/layout/layout_name.hpp"
#include "axon/fps/plan/layout_model.hpp"
#include "axon/fps/plan/problems.hpp"
#include "axon/fps/sim/focal_plane_sim.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/io_context.hpp>
#include <fmt/format.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <random>

namespace axon::soak {
namespace {

using namespace std::chrono_literals;
namespace asio = boost::asio;
namespace host = fps::host;
using Clock = std::chrono::steady_clock;

enum class Fault { none, collision, power_cycle, link_reset, silent_robot, bus_off, power_loss };
constexpr std::array kFaults{Fault::none,         Fault::collision, Fault::power_cycle, Fault::link_reset,
                             Fault::silent_robot, Fault::bus_off,   Fault::power_loss};
const char* name(Fault f) {
  switch (f) {
    case Fault::none: return "none";
    case Fault::collision: return "collision";
    case Fault::power_cycle: return "power_cycle";
    case Fault::link_reset: return "link_reset";
    case Fault::silent_robot: return "silent_robot";
    case Fault::bus_off: return "bus_off";
    case Fault::power_loss: return "power_loss_mid_move";
  }
  return "?";
}

constexpr double kTimeScale = 10;  // simulated seconds per real second

class FpsSoak {
 public:
  FpsSoak(Args args, fps::FocalPlane plane) : args_(args), plane_(std::move(plane)), rng_(args.seed) {
    sum_.name = "fps";
  }
  asio::awaitable<void> run(asio::any_io_executor ex);
  int report() const { return sum_.report(); }

 private:
  template <class F>
  auto on_sim(F f) {
    return sim_thread_.call(std::move(f));
  }
  void start_sim();
  asio::awaitable<void> connect(asio::any_io_executor ex);
  asio::awaitable<bool> back_in_service();
  asio::awaitable<bool> separate();
  asio::awaitable<void> cycle(asio::any_io_executor ex, std::uint64_t n, Fault f);
  asio::awaitable<void> inject(Fault f, std::shared_ptr<bool> done);
  asio::awaitable<void> power_cycle();
  asio::awaitable<void> judge(Fault f, const Result<host::PlanAndMoveReport>& r, std::uint64_t collisions_before);
  asio::awaitable<bool> all_still(core::Duration within);
  std::uint16_t pick_robot(bool moving);
  // Contacts between arms (and with obstacles) the simulator has seen so far.
  std::uint64_t arm_collisions() {
    return on_sim([&] {
      const auto& st = sim_->simulator().stats();
      return st.neighbour_collisions + st.obstacle_collisions;
    });
  }
  // Gateway connections the host has lost so far, all gateways.
  std::uint64_t link_losses() const {
    std::uint64_t n = 0;
    for (const auto& g : fpa_->gateways()) n += g.losses;
    return n;
  }
  void fail(std::string what) {
    spdlog::error("soak fps: {}", what);
    sum_.failures.push_back(std::move(what));
  }

  Args args_;
  fps::FocalPlane plane_;
  std::mt19937_64 rng_;
  core::LoopThread sim_thread_;
  std::unique_ptr<fps::sim::FocalPlaneSimulator> sim_;
  std::unique_ptr<host::FocalPlaneArray> fpa_;
  std::optional<fps::plan::CollisionModel> model_;
  std::string phase_;  // the run's latest phase (TrajectoryOptions::on_phase)
  std::vector<std::uint16_t> off_;  // robots whose power the soak cut
  Summary sum_;
  Baseline baseline_;
  std::map<Fault, std::uint64_t> injected_, reported_;
  bool last_clean_ok_ = false;
  std::uint64_t clean_failures_ = 0;   // cycles without an injected fault that did not complete
  std::uint64_t reuploads_ = 0;        // robots uploaded again after a lost reply
  unsigned failed_clean_ = 0;           // cycles in a row without an injected fault that failed
  std::uint64_t collision_locks_ = 0;   // the array's count when the cycle began
  bool check_contacts_ = false;          // a power loss mid-move may have left robots in contact
  std::uint64_t power_loss_contacts_ = 0;  // arm contacts the simulator saw in those cycles
  std::uint64_t backed_off_ = 0;         // robots moved out of a contact by host::back_off
};

void FpsSoak::start_sim() {
  fps::sim::FocalPlaneSimOptions so;
  so.simulator.time_scale = kTimeScale;
  so.seed = args_.seed;
  can::FaultRule drop{can::FaultRule::Action::drop};
  // About two lost replies a cycle: a lost read is read again, a robot whose upload lost one is
  // uploaded again (TrajectoryOptions::upload_retries); a run refused all the same is counted.
  drop.probability = 0.00005;
  can::FaultRule delay{can::FaultRule::Action::delay};
  delay.probability = 0.0005;
  delay.delay = 3ms;
  can::FaultRule dup{can::FaultRule::Action::duplicate};
  dup.probability = 0.0005;
  so.simulator.reply_faults.rules = {drop, delay, dup};
  so.simulator.reply_faults.seed = args_.seed;
  sim_ = on_sim([&] { return fps::sim::FocalPlaneSimulator::start(sim_thread_.executor(), plane_, so).value(); });
}

asio::awaitable<void> FpsSoak::connect(asio::any_io_executor ex) {
  host::FocalPlaneArrayOptions o;
  for (const auto& g : on_sim([&] { return sim_->gateways(); })) o.addresses[g.id] = g.endpoint;
  o.plc = on_sim([&] { return sim_->plc()->endpoint(); });
  o.array.positioner.poll_interval = 100ms;
  auto r = co_await host::FocalPlaneArray::connect(ex, plane_, o);
  fpa_ = std::move(r).value();
  model_ = fps::plan::model_from_layout(plane_).value();
}

// Every gateway connected again (by the host itself), the soak's powered-off robots back, the
// array unlocked and every robot ready. False (with a failure) when that does not happen in time.
asio::awaitable<bool> FpsSoak::back_in_service() {
  if (!off_.empty()) {
    on_sim([&] { (void)sim_->simulator().power_on(off_, false); });  // boot the application
    off_.clear();
  }
  const auto deadline = Clock::now() + 60s;
  auto links_up = [&] {
    return std::ranges::none_of(fpa_->gateways(), [](const host::GatewayLink& l) { return l.down; });
  };
  while (!links_up() && Clock::now() < deadline) co_await core::sleep_for(50ms);
  if (!links_up()) {
    fail("a gateway was not back within 60 s: the host did not reconnect by itself");
    co_return false;
  }
  for (int attempt = 0; attempt < 20; ++attempt) {
    if (fpa_->array().locked()) (void)co_await fpa_->array().unlock();
    const auto table = co_await fpa_->array().status_table(false);
    const auto ready = std::ranges::count_if(table.rows, [](const host::StatusRow& r) { return r.state() == "ready"; });
    if (!fpa_->array().locked() && static_cast<std::size_t>(ready) == table.rows.size()) co_return co_await separate();
    co_await core::sleep_for(250ms);
  }
  fail("the plane was not back in service (unlocked, every robot ready) within 20 attempts");
  co_return false;
}

// After a power loss mid-move: robots that stopped dead and the neighbours that stopped a few ms
// later may stand inside each other's collision buffers. The host moves them out (host::back_off)
// as an operator would have to; a contact it cannot clear takes the plane out of service.
asio::awaitable<bool> FpsSoak::separate() {
  if (!std::exchange(check_contacts_, false)) co_return true;
  host::BackOffRequest request;  // (not the default argument: gcc 12 fails on it inside a coroutine)
  auto r = co_await host::back_off(fpa_->array(), *model_, std::move(request));
  if (!r) {
    fail(fmt::format("back_off after a power loss mid-move: {}", r.error().message()));
    co_return false;
  }
  for (const auto& step : r.value().steps) backed_off_ += step.moved ? 1 : 0;
  if (!r.value().steps.empty()) spdlog::warn("soak fps: after the power loss:\n{}", r.value().summary());
  if (!r.value().ok()) {
    fail(fmt::format("robots left in contact after a power loss mid-move:\n{}", r.value().summary()));
    co_return false;
  }
  co_return true;
}

std::uint16_t FpsSoak::pick_robot(bool moving) {
  return on_sim([&]() -> std::uint16_t {
    std::vector<std::uint16_t> ids;
    for (auto* m : sim_->simulator().robots())
      if (!moving || m->moving()) ids.push_back(m->id());
    if (ids.empty()) return 0;
    return ids[std::uniform_int_distribution<std::size_t>(0, ids.size() - 1)(rng_)];
  });
}

// Waits for the phase the fault belongs to, then injects it on the simulator's thread.
asio::awaitable<void> FpsSoak::inject(Fault f, std::shared_ptr<bool> done) {
  const bool mid_move = f == Fault::collision || f == Fault::bus_off || f == Fault::power_loss;
  const std::string want = mid_move ? "started" : "checked";
  while (phase_ != want && !*done) co_await core::sleep_for(5ms);
  if (*done) co_return;
  co_await core::sleep_for(mid_move ? 400ms : 30ms);
  ++injected_[f];
  ++sum_.faults;
  const int sextant = std::uniform_int_distribution<int>(1, 6)(rng_);
  if (f == Fault::collision) {
    const auto id = pick_robot(true);
    if (id != 0) on_sim([&] { (void)sim_->simulator().force_collision(id, fps::sim::Arm::beta); });
  } else if (f == Fault::link_reset) {
    on_sim([&] { (void)sim_->set_gateway_power(sextant, false); });
    co_await core::sleep_for(300ms);
    on_sim([&] { (void)sim_->set_gateway_power(sextant, true); });
  } else if (f == Fault::silent_robot) {
    off_ = {pick_robot(false)};
    on_sim([&] { (void)sim_->simulator().power_off(off_, true); });
  } else if (f == Fault::power_loss) {  // a sextant's gateway and robots, while they move
    off_ = on_sim([&] { return sim_->sextants().at(sextant); });
    on_sim([&] {
      (void)sim_->set_gateway_power(sextant, false);
      (void)sim_->simulator().power_off(off_, true);
    });
    check_contacts_ = true;
    co_await core::sleep_for(1500ms);
    on_sim([&] { (void)sim_->set_gateway_power(sextant, true); });  // the robots come back in back_in_service()
  } else if (f == Fault::bus_off) {
    const int channel = std::uniform_int_distribution<int>(1, 4)(rng_);
    on_sim([&] {
      for (const auto& g : sim_->gateways())
        if (g.sextant == sextant) sim_->gateway_emulator(g.id)->inject_bus_off(channel);
    });
  }
}

// No simulated robot moves (those without power aside) within `within`.
asio::awaitable<bool> FpsSoak::all_still(core::Duration within) {
  const auto until = Clock::now() + within;
  for (;;) {
    const bool still = on_sim([&] {
      return std::ranges::none_of(sim_->simulator().robots(), [](auto* m) { return m->moving(); });
    });
    if (still) co_return true;
    if (Clock::now() > until) co_return false;
    co_await core::sleep_for(50ms);
  }
}

// A sextant loses power (gateway and robots) between moves for 1.5 s; the host must notice, stop
// everything, and find the gateway back by itself. (Mid-move, see docs/reliability.md: robots that
// lose power stop dead while their neighbours stop a few ms later, which can leave two of them
// inside each other's collision buffers, and the planner refuses to start from there.)
asio::awaitable<void> FpsSoak::power_cycle() {
  const int sextant = std::uniform_int_distribution<int>(1, 6)(rng_);
  const auto losses = link_losses();
  off_ = on_sim([&] { return sim_->sextants().at(sextant); });
  on_sim([&] {
    (void)sim_->set_gateway_power(sextant, false);
    (void)sim_->simulator().power_off(off_, true);
  });
  ++injected_[Fault::power_cycle];
  ++sum_.faults;
  co_await core::sleep_for(1500ms);
  on_sim([&] { (void)sim_->set_gateway_power(sextant, true); });  // the robots come back in back_in_service()
  if (link_losses() > losses && fpa_->array().locked()) ++reported_[Fault::power_cycle];
}

// One plan-and-move to random targets with fault `f` injected at its phase, then judged.
asio::awaitable<void> FpsSoak::cycle(asio::any_io_executor ex, std::uint64_t n, Fault f) {
  if (f == Fault::power_cycle) {
    co_await power_cycle();
    if (!co_await back_in_service()) co_return;
  }
  const auto& model = *model_;
  const auto targets = fps::plan::random_poses(model, args_.seed * 100003 + n);
  host::PlanAndMoveOptions o;
  o.planner.seed = args_.seed + n;
  o.run = [this](host::Trajectories t, host::TrajectoryOptions to) { return fpa_->run_trajectories(std::move(t), std::move(to), true); };
  phase_.clear();
  o.trajectory.on_phase = [this](std::string_view p) { phase_ = std::string(p); };
  const auto collisions = arm_collisions();
  auto done = std::make_shared<bool>(false);
  collision_locks_ = fpa_->array().counters().collision_locks;
  if (f != Fault::none && f != Fault::power_cycle) asio::co_spawn(ex, inject(f, done), asio::detached);
  auto r = co_await host::plan_and_move(fpa_->array(), plane_, model, targets, o);
  *done = true;
  co_await judge(f, r, collisions);
  ++sum_.cycles;
}

// Whether the host reported the fault, kept everything safe and lost nothing.
asio::awaitable<void> FpsSoak::judge(Fault f, const Result<host::PlanAndMoveReport>& r, std::uint64_t collisions_before) {
  const host::TrajectoryReport* run = r && r.value().run ? &*r.value().run : nullptr;
  if (run != nullptr && run->started) {
    for (const auto& rr : run->robots) {
      const auto s = rr.state;
      if (s == host::RobotState::upload_failed || s == host::RobotState::not_ready || s == host::RobotState::withdrawn ||
          s == host::RobotState::still_loaded) {
        ++sum_.unsafe;
        fail(fmt::format("{}: the run started although robot {} was {}", name(f), rr.id, to_string(s)));
      }
    }
  }
  if (run != nullptr)
    for (const auto& rr : run->robots) reuploads_ += rr.upload_attempts > 1 ? 1 : 0;
  const bool stopped = fpa_->array().locked() || (run != nullptr && !run->completed) || !r;
  if (f == Fault::none || f == Fault::power_cycle) {
    last_clean_ok_ = r && (run == nullptr || run->completed);
    failed_clean_ = last_clean_ok_ ? 0 : failed_clean_ + 1;
    clean_failures_ += last_clean_ok_ ? 0 : 1;
    if (!last_clean_ok_)
      spdlog::warn("soak fps: a cycle without an injected fault did not complete (reply faults?): {}",
                   r ? run->outcome : r.error().message());
  } else if (injected_[f] > reported_[f] && stopped) {
    ++reported_[f];
  }
  if (fpa_->array().counters().collision_locks > collision_locks_ && fpa_->array().last_stop() &&
      fpa_->array().last_stop()->buses_sent() != fpa_->bus_count()) {
    ++sum_.unsafe;
    fail(fmt::format("collision: the abort went out on {} of {} buses", fpa_->array().last_stop()->buses_sent(), fpa_->bus_count()));
  }
  if (!co_await all_still(3s)) {
    ++sum_.unsafe;
    fail(fmt::format("{}: robots still moving 3 s after the run returned", name(f)));
  }
  const auto collisions = arm_collisions();
  if (collisions != collisions_before && f == Fault::power_loss) {
    // Robots without power stop dead, their neighbours on other gateways a few ms later, at the
    // host's abort: contacts the host cannot prevent, counted, then cleared by separate().
    power_loss_contacts_ += collisions - collisions_before;
  } else if (collisions != collisions_before) {
    ++sum_.unsafe;
    fail(fmt::format("{}: the simulator saw {} collision(s) between arms", name(f), collisions - collisions_before));
  }
}

asio::awaitable<void> FpsSoak::run(asio::any_io_executor ex) {
  const auto t0 = Clock::now();
  start_sim();
  co_await connect(ex);
  const auto end = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(args_.minutes * 60));
  std::vector<Fault> order(kFaults.begin(), kFaults.end());
  for (std::uint64_t n = 0; Clock::now() < end || n == 0; ++n) {
    if (n % order.size() == 0) std::shuffle(order.begin() + 1, order.end(), rng_);  // "none" first: the warm-up
    if (!co_await back_in_service()) break;
    if (n == 1) baseline_ = Baseline{};
    const Fault f = order[n % order.size()];
    spdlog::info("soak fps: cycle {} ({})", n, name(f));
    co_await cycle(ex, n, f);
    if (failed_clean_ >= 3) {
      fail("3 cycles in a row without an injected fault did not complete: the plane is out of service");
      break;
    }
  }
  // The last word: the plane in service once more, and one clean cycle.
  // The plane back in service: without the lost replies (their cost is the runs they refused, counted
  // above), one clean cycle must complete; a second try is allowed.
  on_sim([&] { sim_->simulator().set_reply_faults({}); });
  last_clean_ok_ = false;
  for (int attempt = 0; attempt < 2 && !last_clean_ok_; ++attempt)
    if (co_await back_in_service()) co_await cycle(ex, 1'000'000 + attempt, Fault::none);
  if (!last_clean_ok_) fail("the plane is not back in service: the last cycle, without a fault, did not complete");
  std::uint64_t lost = 0;
  std::string per;
  for (const auto& [f, count] : injected_) {
    lost += count - reported_[f];
    per += fmt::format("{}{}={}/{}", per.empty() ? "" : ",", name(f), reported_[f], count);
  }
  sum_.lost = lost;
  const auto st = on_sim([&] { return sim_->simulator().stats(); });
  std::uint64_t restorations = 0;
  for (const auto& g : fpa_->gateways()) restorations += g.restorations;
  sum_.more = {{"reported", per},
               {"link_losses", std::to_string(link_losses())},
               {"reconnections", std::to_string(restorations)},
               {"bus_off_restarts", std::to_string(fpa_->bus_off_restarts())},
               {"runs_refused_without_fault", std::to_string(clean_failures_)},
               {"reuploads", std::to_string(reuploads_)},
               {"power_loss_contacts", std::to_string(power_loss_contacts_)},
               {"backed_off", std::to_string(backed_off_)},
               {"reply_faults", fmt::format("{}/{}/{}", st.faults_dropped, st.faults_delayed, st.faults_duplicated)}};
  sum_.finish(baseline_, Clock::now() - t0);  // before anything closes
  co_await fpa_->close();
  on_sim([&] { sim_->stop(); });
}

}  // namespace
}  // namespace axon::soak

int main(int argc, char** argv) {
  using namespace axon;
  namespace asio = boost::asio;
  const auto args = soak::parse_args(argc, argv, "fps");
  spdlog::set_default_logger(spdlog::stderr_color_mt("soak"));  // stdout: the summary line only
  spdlog::set_level(spdlog::level::warn);
  auto plane = fps::resolve_layout("default");
  if (!plane) {
    std::fprintf(stderr, "axon_soak_fps: %s\n", plane.error().message().c_str());
    return 2;
  }
  soak::FpsSoak soak(args, std::move(plane).value());
  asio::io_context io;
  std::exception_ptr failed;
  asio::co_spawn(io, soak.run(io.get_executor()), [&](std::exception_ptr e) { failed = e; });
  io.run();
  if (failed) {
    try {
      std::rethrow_exception(failed);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "axon_soak_fps: %s\n", e.what());
      return 2;
    }
  }
  return soak.report();
}
