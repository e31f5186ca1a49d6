#include "axon/fps/sim/simulator.hpp"

#include "axon/can/error.hpp"
#include "axon/core/deadline_queue.hpp"
#include "axon/core/wakeup.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/redirect_error.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/use_awaitable.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <functional>
#include <unordered_map>

namespace axon::fps::sim {

namespace proto = protocol;

namespace {

// Frames the firmware writes to flash take longer to process.
bool writes_flash(std::uint8_t command) noexcept {
  return command == proto::number(proto::CommandId::save_calibration) ||
         command == proto::number(proto::CommandId::start_firmware_upgrade) ||
         command == proto::number(proto::CommandId::firmware_data);
}

SimDuration scaled(SimDuration d, double factor) noexcept {
  const double ns = static_cast<double>(d.count()) * factor;
  if (ns >= 9.0e18) return SimDuration::max();
  return SimDuration(static_cast<std::int64_t>(ns));
}

}  // namespace

Result<void> SimulatorOptions::validate() const {
  const auto bad = [](std::string what) { return make_error(CoreErrc::invalid_argument, "simulator: " + what); };
  if (!std::isfinite(time_scale) || time_scale <= 0 || time_scale > 1e6) {
    return bad(fmt::format("time scale {} is not within (0, 1e6]", time_scale));
  }
  if (tick <= core::Duration::zero()) return bad("tick must be positive");
  if (collision_step <= SimDuration::zero()) return bad("collision step must be positive");
  if (processing_delay < core::Duration::zero() || flash_delay < core::Duration::zero()) {
    return bad("processing delays must not be negative");
  }
  return ok();
}

struct Robot {
  Robot(PositionerModel m, std::unique_ptr<can::Bus> b)
      : model(std::move(m)), bus(std::move(b)), idle(bus->get_executor()) {}
  PositionerModel model;
  std::unique_ptr<can::Bus> bus;
  // The frame being processed (taken from the receive buffer, answered when its processing time
  // is over), and the robot's serve loop, parked while the robot works through its buffer.
  std::optional<proto::Message> current;
  core::Wakeup idle;
  std::deque<can::Frame> outq;
  bool sending = false;
};

struct Simulator::State final : std::enable_shared_from_this<State>, core::DeadlineClient {
  asio::any_io_executor executor;
  SimulatorOptions options;
  const core::Clock* clock = nullptr;
  core::TimePoint start_real{};
  std::vector<std::unique_ptr<Robot>> robots;
  std::unordered_map<std::uint16_t, Robot*> by_id;
  can::FaultInjector faults;
  CollisionMonitor monitor;
  bool monitor_dirty = true;
  std::optional<plan::ModelSpec> geometry;  // set_geometry
  std::vector<Obstacle> obstacles;          // add_obstacle
  SimTime last_step{};
  bool running = false;
  bool stopped = false;
  asio::steady_timer tick_timer;
  SimulatorStats stats;

  // Processing times of every robot in one heap: (end of processing, order taken) -> robot. A
  // timer per command per robot cost a kernel timer update for each of tens of thousands of
  // frames a second; one heap, woken by the executor's DeadlineQueue (shared with the paced
  // buses), handles every robot that is due in one go.
  struct Due {
    core::TimePoint at;
    std::uint64_t seq;
    Robot* robot;
  };
  std::vector<Due> due;  // min-heap on (at, seq)
  std::uint64_t next_due = 0;
  core::DeadlineQueue* deadlines;
  core::TimePoint due_armed = core::TimePoint::max();

  State(asio::any_io_executor ex, SimulatorOptions o)
      : executor(ex), options(std::move(o)), faults(options.reply_faults), tick_timer(ex), deadlines(&core::DeadlineQueue::of(ex)) {
    clock = options.clock != nullptr ? options.clock : &core::SteadyClock::instance();
    start_real = clock->now();
  }

  [[nodiscard]] SimTime now() const noexcept {
    const auto real = clock->now() - start_real;
    return scaled(std::chrono::duration_cast<SimDuration>(real), options.time_scale);
  }

  Result<PositionerModel*> add(PositionerConfig config, const std::function<Result<std::unique_ptr<can::Bus>>(
                                                            std::string_view, const can::BusOptions&)>& open);
  void emit(Robot& r, const Outbox& out, bool from_sync = false);
  void enqueue(Robot& r, const can::Frame& f);
  void spawn(Robot& r);
  bool start_processing(Robot& r, const can::Frame& f);
  bool take_next(Robot& r);
  void schedule(Robot& r, core::TimePoint at);
  void arm_due(core::TimePoint at);
  void run_due();
  void on_deadline() override { run_due(); }
  SimTime event_time();
  void step();
  // The monitor, rebuilt first when robots, obstacles or the geometry changed.
  const CollisionMonitor& current_monitor();
  void check_collisions(SimTime t);

  static asio::awaitable<void> serve(std::shared_ptr<State> self, Robot* r);
  static asio::awaitable<void> drain(std::shared_ptr<State> self, Robot* r);
  static asio::awaitable<void> delayed(std::shared_ptr<State> self, Robot* r, can::Frame f, core::Duration d);
  static asio::awaitable<void> tick(std::shared_ptr<State> self);
};

Result<PositionerModel*> Simulator::State::add(
    PositionerConfig config,
    const std::function<Result<std::unique_ptr<can::Bus>>(std::string_view, const can::BusOptions&)>& open) {
  AXON_TRY(config.validate());
  if (stopped) return make_error(CoreErrc::closed, "simulator: stopped, cannot add robots");
  if (by_id.contains(config.id)) {
    return make_error(CoreErrc::invalid_argument, fmt::format("simulator: positioner id {} is already taken", config.id));
  }
  if (!options.scale_protocol_timeouts) {
    // Keep what the host times in real time: these are stretched by the scale.
    config.boot_time = scaled(config.boot_time, options.time_scale);
    config.bootloader_timeout = scaled(config.bootloader_timeout, options.time_scale);
    config.watchdog_timeout = scaled(config.watchdog_timeout, options.time_scale);
    config.sync_recheck = scaled(config.sync_recheck, options.time_scale);
  }
  can::BusOptions bo;
  bo.rx_capacity = config.receive_buffer;
  AXON_TRY(bus, open(fmt::format("fps{}", config.id), bo));
  // Hardware acceptance filter: own id and broadcasts, extended frames only.
  constexpr std::uint32_t kIdMask = std::uint32_t{proto::kMaxPositionerId} << proto::kPositionerShift;
  bus->set_filters({can::Filter{std::uint32_t{config.id} << proto::kPositionerShift, kIdMask, can::Filter::Format::extended},
                    can::Filter{0, kIdMask, can::Filter::Format::extended}});
  const std::uint16_t id = config.id;
  auto robot = std::make_unique<Robot>(PositionerModel(std::move(config), event_time()), std::move(bus));
  Robot* r = robot.get();
  robots.push_back(std::move(robot));
  by_id.emplace(id, r);
  monitor_dirty = true;
  if (running) spawn(*r);
  return &r->model;
}

void Simulator::State::spawn(Robot& r) {
  asio::co_spawn(executor, serve(shared_from_this(), &r), asio::detached);
}

asio::awaitable<void> Simulator::State::serve(std::shared_ptr<State> self, Robot* r) {
  // Waits for a frame while the robot is idle; once busy, the robot takes its next frames from the
  // buffer itself as each processing time ends (run_due), and wakes this loop when it runs dry.
  while (!self->stopped) {
    auto frame = co_await r->bus->receive();
    if (self->stopped) break;
    if (!frame) {
      if (frame.error() == can::CanErrc::closed) break;
      continue;
    }
    r->idle.reset();
    if (!self->start_processing(*r, frame.value()) && !self->take_next(*r)) continue;
    co_await r->idle.wait();
  }
}

bool Simulator::State::start_processing(Robot& r, const can::Frame& f) {
  auto msg = proto::from_frame(f);
  if (!msg) {
    ++stats.non_fps_frames;
    return false;
  }
  ++stats.frames_processed;
  const auto delay = writes_flash(msg.value().id.command) ? options.flash_delay : options.processing_delay;
  r.current = std::move(msg).value();
  schedule(r, core::SteadyClock::instance().now() + delay);
  return true;
}

bool Simulator::State::take_next(Robot& r) {
  while (auto f = r.bus->try_receive()) {
    if (start_processing(r, *f)) return true;
  }
  return false;
}

void Simulator::State::schedule(Robot& r, core::TimePoint at) {
  const auto later = [](const Due& a, const Due& b) { return a.at != b.at ? a.at > b.at : a.seq > b.seq; };
  due.push_back(Due{at, next_due++, &r});
  std::push_heap(due.begin(), due.end(), later);
  if (at < due_armed) arm_due(at);
}

void Simulator::State::arm_due(core::TimePoint at) {
  due_armed = at;
  deadlines->arm(*this, at);  // replaces the later deadline armed before
}

void Simulator::State::run_due() {
  const auto later = [](const Due& a, const Due& b) { return a.at != b.at ? a.at > b.at : a.seq > b.seq; };
  due_armed = core::TimePoint::max();
  const auto t = core::SteadyClock::instance().now();
  std::optional<SimTime> at;  // one instant for every frame answered in this round
  while (!stopped && !due.empty() && due.front().at <= t) {
    std::pop_heap(due.begin(), due.end(), later);
    Robot& r = *due.back().robot;
    due.pop_back();
    if (r.current) {
      const proto::Message m = *r.current;
      r.current.reset();
      if (!at) at = event_time();
      emit(r, r.model.handle(m, *at));
    }
    if (!take_next(r)) r.idle.notify();
  }
  if (!stopped && !due.empty()) arm_due(due.front().at);
}

void Simulator::State::emit(Robot& r, const Outbox& out, bool from_sync) {
  for (const auto& m : out) {
    auto frame = proto::to_frame(m);
    if (!frame) {  // cannot happen for frames a model builds; counted rather than trusted
      ++stats.send_errors;
      continue;
    }
    if (from_sync || m.id.command == proto::number(proto::CommandId::collision_detected)) ++stats.unsolicited;
    if (faults.empty()) {
      enqueue(r, frame.value());
      continue;
    }
    const auto d = faults.apply(frame.value());
    if (d.drop) {
      ++stats.faults_dropped;
      continue;
    }
    if (d.corrupted) ++stats.faults_corrupted;
    if (d.duplicate) ++stats.faults_duplicated;
    if (d.delay > core::Duration::zero()) ++stats.faults_delayed;
    for (int i = 0; i < (d.duplicate ? 2 : 1); ++i) {
      if (d.delay > core::Duration::zero()) {
        asio::co_spawn(executor, delayed(shared_from_this(), &r, d.frame, d.delay), asio::detached);
      } else {
        enqueue(r, d.frame);
      }
    }
  }
}

void Simulator::State::enqueue(Robot& r, const can::Frame& f) {
  r.outq.push_back(f);
  if (r.sending) return;
  r.sending = true;
  asio::co_spawn(executor, drain(shared_from_this(), &r), asio::detached);
}

asio::awaitable<void> Simulator::State::drain(std::shared_ptr<State> self, Robot* r) {
  // One sender per robot keeps its frames in order whatever the transport.
  while (!r->outq.empty() && !self->stopped) {
    const can::Frame f = r->outq.front();
    r->outq.pop_front();
    auto sent = co_await r->bus->send(f);
    if (sent) {
      ++self->stats.frames_sent;
    } else {
      ++self->stats.send_errors;
    }
  }
  r->outq.clear();
  r->sending = false;
}

asio::awaitable<void> Simulator::State::delayed(std::shared_ptr<State> self, Robot* r, can::Frame f,
                                                core::Duration d) {
  asio::steady_timer timer(self->executor);
  timer.expires_after(d);
  boost::system::error_code ec;
  co_await timer.async_wait(asio::redirect_error(asio::use_awaitable, ec));
  if (!self->stopped) self->enqueue(*r, f);
}

asio::awaitable<void> Simulator::State::tick(std::shared_ptr<State> self) {
  while (!self->stopped) {
    self->tick_timer.expires_after(self->options.tick);
    boost::system::error_code ec;
    co_await self->tick_timer.async_wait(asio::redirect_error(asio::use_awaitable, ec));
    if (self->stopped) break;
    self->step();
  }
}

SimTime Simulator::State::event_time() {
  // The collision check compares the poses of every robot at one instant, so no robot may run
  // ahead of the others. While anything moves, only step() moves time on (every robot, checks
  // included): a frame is answered at the instant of the last step. Answering it at the present
  // instead moved that robot alone ahead; under load, with the tick late, seconds ahead of its
  // neighbours, and the check saw collisions that robots on one clock and one sync edge (the
  // hardware) never have. With nothing moving, poses do not depend on time: the world jumps to
  // the present, so a move starts when its frame arrives.
  const bool any_moving = std::any_of(robots.begin(), robots.end(), [](const auto& r) { return r->model.moving(); });
  if (!any_moving) last_step = std::max(last_step, now());
  return last_step;
}

namespace {

// A robot's geometry from its config, against the plane's arm design.
plan::RobotSpec spec_of(const PositionerConfig& c, const ArmLengths& design) {
  plan::RobotSpec s;
  s.id = c.id;
  s.centre = {c.x_mm, c.y_mm};
  s.calibration.orientation_deg = c.orientation_deg;
  s.calibration.alpha_length_delta_mm = c.arms.alpha_length_mm - design.alpha_length_mm;
  s.calibration.beta_length_delta_mm = c.arms.beta_collision_mm - design.beta_collision_mm;
  s.buffer_mm = c.collision_buffer_mm;
  return s;
}

}  // namespace

const CollisionMonitor& Simulator::State::current_monitor() {
  if (!monitor_dirty) return monitor;
  plan::ModelSpec spec;
  std::unordered_map<std::int32_t, const plan::RobotSpec*> listed;
  if (geometry) {
    spec.design = geometry->design;
    spec.fiducials = geometry->fiducials;
    spec.obstacles = geometry->obstacles;
    for (const auto& r : geometry->robots) listed.emplace(r.id, &r);
  }
  spec.obstacles.insert(spec.obstacles.end(), obstacles.begin(), obstacles.end());
  spec.robots.reserve(robots.size());
  for (const auto& r : robots) {
    const auto it = listed.find(r->model.id());
    spec.robots.push_back(it != listed.end() ? *it->second : spec_of(r->model.config(), spec.design));
  }
  // Ids are unique (add() refuses a second one), the one thing build() checks.
  monitor = CollisionMonitor(plan::CollisionModel::build(spec).value(), options.neighbour_collisions);
  monitor_dirty = false;
  return monitor;
}

void Simulator::State::step() {
  const SimTime target = std::max(now(), last_step);
  const bool has_obstacles = !current_monitor().model().obstacles().empty();  // rebuilt here when needed
  const bool check = options.neighbour_collisions || has_obstacles;
  SimTime t = last_step;
  do {
    const bool any_moving =
        std::any_of(robots.begin(), robots.end(), [](const auto& r) { return r->model.moving(); });
    // Fine steps only while something moves and collisions are checked; at rest, a step ends where
    // the sync line starts trajectories, so that the check follows them from their first instant.
    SimTime next = target;
    if (check && any_moving) {
      next = std::min(target, t + options.collision_step);
    } else if (check) {
      for (const auto& r : robots)
        if (const auto at = r->model.sync_check_at(); at && *at > t && *at < next) next = *at;
    }
    for (auto& r : robots) emit(*r, r->model.advance(next), true);  // all unsolicited
    if (check) check_collisions(next);
    t = next;
  } while (t < target);
  last_step = target;
}

void Simulator::State::check_collisions(SimTime t) {
  std::vector<CollisionMonitor::Pose> poses;
  poses.reserve(robots.size());
  for (const auto& r : robots) poses.push_back({r->model.physical_deg(Arm::alpha), r->model.physical_deg(Arm::beta)});
  const auto contacts = monitor.update(poses);
  std::vector<bool> done(robots.size());
  for (const auto& c : contacts) {
    if (done[c.robot]) continue;
    Robot& r = *robots[c.robot];
    // The arm that was driving into the contact feels it, if it watches for collisions.
    std::optional<Arm> arm;
    if (c.beta_moved && r.model.collision_detection(Arm::beta)) {
      arm = Arm::beta;
    } else if (c.alpha_moved && r.model.collision_detection(Arm::alpha)) {
      arm = Arm::alpha;
    }
    if (!arm) continue;
    done[c.robot] = true;
    ++(c.other ? stats.neighbour_collisions : stats.obstacle_collisions);
    emit(r, r.model.inject_collision(*arm, t));
  }
}

// ---- Simulator ------------------------------------------------------------------------------

Simulator::Simulator(asio::any_io_executor executor, SimulatorOptions options) {
  if (auto v = options.validate(); !v) throw Exception(v.error());
  state_ = std::make_shared<State>(std::move(executor), std::move(options));
}

Simulator::~Simulator() { stop(); }

Result<PositionerModel*> Simulator::add(PositionerConfig config, can::BusProvider& provider, std::string_view channel) {
  return state_->add(std::move(config), [&](std::string_view, const can::BusOptions& o) {
    return provider.open(channel, o);
  });
}

Result<PositionerModel*> Simulator::add(PositionerConfig config, can::VirtualBus& medium) {
  return state_->add(std::move(config), [&](std::string_view name, const can::BusOptions& o) -> Result<std::unique_ptr<can::Bus>> {
    return medium.attach(std::string(name), o);
  });
}

void Simulator::start() {
  State& s = *state_;
  if (s.running || s.stopped) return;
  s.running = true;
  s.last_step = std::max(s.last_step, s.now());
  for (auto& r : s.robots) s.spawn(*r);
  asio::co_spawn(s.executor, State::tick(state_), asio::detached);
}

void Simulator::stop() {
  if (!state_) return;
  State& s = *state_;
  if (s.stopped) return;
  s.stopped = true;
  s.running = false;
  s.tick_timer.cancel();
  s.deadlines->disarm(s);
  for (auto& r : s.robots) {
    r->idle.abandon();
    r->bus->close();
  }
}

bool Simulator::running() const noexcept { return state_->running; }
SimTime Simulator::now() const noexcept { return state_->now(); }
const SimulatorOptions& Simulator::options() const noexcept { return state_->options; }
void Simulator::step() { state_->step(); }
std::size_t Simulator::size() const noexcept { return state_->robots.size(); }

PositionerModel* Simulator::find(std::uint16_t id) noexcept {
  const auto it = state_->by_id.find(id);
  return it == state_->by_id.end() ? nullptr : &it->second->model;
}

std::vector<PositionerModel*> Simulator::robots() {
  std::vector<PositionerModel*> out;
  out.reserve(state_->robots.size());
  for (auto& r : state_->robots) out.push_back(&r->model);
  return out;
}

const can::Bus* Simulator::endpoint(std::uint16_t id) const noexcept {
  const auto it = state_->by_id.find(id);
  return it == state_->by_id.end() ? nullptr : it->second->bus.get();
}

std::uint64_t Simulator::receive_overflows() const noexcept {
  std::uint64_t n = 0;
  for (const auto& r : state_->robots) n += r->bus->stats().rx_dropped;
  return n;
}

namespace {
// The robots behind `ids`, or an error naming the first unknown one.
template <class Map>
auto lookup(Map& by_id, std::span<const std::uint16_t> ids) -> Result<std::vector<typename Map::mapped_type>> {
  std::vector<typename Map::mapped_type> out;
  out.reserve(ids.size());
  for (auto id : ids) {
    const auto it = by_id.find(id);
    if (it == by_id.end()) return make_error(CoreErrc::invalid_argument, fmt::format("simulator: no positioner {}", id));
    out.push_back(it->second);
  }
  return out;
}
}  // namespace

void Simulator::power_off(bool save_position) {
  const SimTime t = state_->event_time();
  for (auto& r : state_->robots) {
    r->model.power_off(t, save_position);
    while (r->bus->try_receive()) {
    }  // what was waiting in the receive buffer is gone with the power
  }
}

Result<void> Simulator::power_off(std::span<const std::uint16_t> ids, bool save_position) {
  AXON_TRY(robots, lookup(state_->by_id, ids));
  const SimTime t = state_->event_time();
  for (auto* r : robots) {
    r->model.power_off(t, save_position);
    while (r->bus->try_receive()) {
    }
  }
  return ok();
}

Result<void> Simulator::power_on(std::span<const std::uint16_t> ids, bool sync_line_low) {
  AXON_TRY(robots, lookup(state_->by_id, ids));
  const SimTime t = state_->event_time();
  for (auto* r : robots) r->model.power_on(t, sync_line_low);
  return ok();
}

Result<void> Simulator::set_sync_line(std::span<const std::uint16_t> ids, bool high) {
  AXON_TRY(robots, lookup(state_->by_id, ids));
  // Every robot (and the collision check) to the present first: a recheck due before this change
  // saw the line as it was. Then one edge, one instant for every robot it reaches.
  state_->step();
  const SimTime t = state_->event_time();
  for (auto* r : robots) state_->emit(*r, r->model.set_sync_line(high, t), true);
  return ok();
}

void Simulator::power_on(bool sync_line_low) {
  const SimTime t = state_->event_time();
  for (auto& r : state_->robots) r->model.power_on(t, sync_line_low);
}

void Simulator::power_cycle(bool sync_line_low) {
  power_off();
  power_on(sync_line_low);
}

void Simulator::set_sync_line(bool high) {
  state_->step();
  const SimTime t = state_->event_time();
  for (auto& r : state_->robots) state_->emit(*r, r->model.set_sync_line(high, t), true);
}

Result<void> Simulator::force_collision(std::uint16_t id, Arm arm) {
  const auto it = state_->by_id.find(id);
  if (it == state_->by_id.end()) {
    return make_error(CoreErrc::invalid_argument, fmt::format("simulator: no positioner {}", id));
  }
  state_->emit(*it->second, it->second->model.inject_collision(arm, state_->event_time()));
  return ok();
}

Result<void> Simulator::set_friction_fault(std::uint16_t id, Arm arm, std::optional<std::int32_t> level) {
  PositionerModel* m = find(id);
  if (m == nullptr) return make_error(CoreErrc::invalid_argument, fmt::format("simulator: no positioner {}", id));
  m->set_friction_fault(arm, level);
  return ok();
}

Result<void> Simulator::set_hall_fault(std::uint16_t id, Arm arm, HallFault fault) {
  const auto it = state_->by_id.find(id);
  if (it == state_->by_id.end()) {
    return make_error(CoreErrc::invalid_argument, fmt::format("simulator: no positioner {}", id));
  }
  state_->emit(*it->second, it->second->model.set_hall_fault(arm, fault, state_->event_time()));
  return ok();
}

void Simulator::add_obstacle(Obstacle obstacle) {
  state_->obstacles.push_back(std::move(obstacle));
  state_->monitor_dirty = true;
}

void Simulator::clear_obstacles() {
  state_->obstacles.clear();
  state_->monitor_dirty = true;
}

void Simulator::set_geometry(plan::ModelSpec geometry) {
  state_->geometry = std::move(geometry);
  state_->monitor_dirty = true;
}

const plan::CollisionModel& Simulator::collision_model() { return state_->current_monitor().model(); }

void Simulator::set_reply_faults(can::FaultPlan plan) { state_->faults = can::FaultInjector(std::move(plan)); }

const SimulatorStats& Simulator::stats() const noexcept { return state_->stats; }

}  // namespace axon::fps::sim
