#include "axon/c4g/sim/simulated_controller.hpp"

#include "axon/c4g/sim/client_runner.hpp"
#include "axon/c4g/sim/scenario.hpp"
#include "axon/c4g/sim/udp_client.hpp"
#include "axon/net/endpoint.hpp"

#include <boost/lockfree/spsc_queue.hpp>
#include <fmt/format.h>

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <thread>

namespace axon::c4g::sim {

namespace {

Exception invalid(std::string text) { return Exception(Error(CoreErrc::invalid_argument, std::move(text))); }

RobotConfig robot_for(const SimulatedControllerOptions& o) {
  auto robot = find_robot(o.robot).value();  // throws axon::Exception naming the robots known
  if (o.switch_t1_s >= 0) robot.scs.times.t1_s = o.switch_t1_s;
  if (o.switch_t2_s >= 0) robot.scs.times.t2_s = o.switch_t2_s;
  if (o.switch_t3_s >= 0) robot.scs.times.t3_s = o.switch_t3_s;
  if (o.switch_tolerance >= 0) robot.scs.still_tolerance = o.switch_tolerance;
  if (o.pc_reduces_current) robot.scs.reduce_pc_current = false;
  return robot;
}

Scenario scenario_for(const SimulatedControllerOptions& o) {
  if (!o.scenario_yaml.empty() && !o.scenario_file.empty()) throw invalid("give the scenario as YAML text or as a file, not both");
  if (!o.scenario_yaml.empty()) return Scenario::parse(o.scenario_yaml).value();
  if (!o.scenario_file.empty()) return Scenario::load_file(o.scenario_file).value();
  return Scenario::default_scenario();
}

double us(std::int64_t ns) { return static_cast<double>(ns) / 1000.0; }

// Live hand-over queues: snapshots (a reader at 50 Hz takes them as they come; a few spare) and
// events (a program's burst of mode changes on ten axes fits many times over).
constexpr std::size_t kLiveStates = 16;
constexpr std::size_t kLiveEvents = 1024;

}  // namespace

int SimulatedControllerReport::exit_code() const noexcept {
  switch (outcome) {
    case Outcome::completed: return 0;
    case Outcome::communication_error: return 4;  // the controller's safety reaction: drives off
    default: return 1;
  }
}

struct SimulatedController::Impl {
  Impl(Controller c, UdpClient u, SimulatedControllerOptions o)
      : controller(std::move(c)), udp(std::move(u)), options(std::move(o)), local(udp.local_endpoint().to_string()) {}

  Controller controller;
  UdpClient udp;
  SimulatedControllerOptions options;
  std::string local;
  std::string description;  // written before the thread starts
  std::atomic<bool> stop_flag{false};
  std::atomic<bool> running{true};
  std::mutex mutex;
  std::condition_variable ended;
  bool done = false;  // under mutex
  SimulatedControllerReport report;
  std::thread thread;
  // Live hand-over (live_period_s > 0): written on the controller's thread, read by take_live().
  std::uint64_t live_every = 0;  // ticks between two snapshots
  std::unique_ptr<boost::lockfree::spsc_queue<LiveState>> live_states;
  std::unique_ptr<boost::lockfree::spsc_queue<LiveEvent>> live_events;
  std::atomic<std::uint64_t> live_dropped{0};
  LiveState scratch;  // the controller's thread's copy, queued whole

  void open_live() {
    if (options.live_period_s <= 0) return;
    live_every = std::max<std::uint64_t>(1, static_cast<std::uint64_t>(options.live_period_s / controller.period_s() + 0.5));
    live_states = std::make_unique<boost::lockfree::spsc_queue<LiveState>>(kLiveStates);
    live_events = std::make_unique<boost::lockfree::spsc_queue<LiveEvent>>(kLiveEvents);
  }

  // The controller's thread: a snapshot into the queue (dropped, and counted, when it is full).
  void queue_live(const RunReport& rr, bool ended) noexcept {
    capture(controller, scratch);
    ++scratch.sequence;
    scratch.ended = ended;
    scratch.overruns = rr.overruns;
    scratch.rtt_count = rr.rtt.count();
    scratch.rtt_mean_us = rr.rtt.mean() / 1000.0;
    scratch.rtt_max_us = us(rr.rtt.max());
    if (!live_states->push(scratch)) live_dropped.fetch_add(1, std::memory_order_relaxed);
  }

  void run() noexcept {
    RunOptions ro;
    ro.duration_s = options.duration_s;
    ro.stop = &stop_flag;
    ro.window = options.reply_window;
    ro.reply_deadline = options.reply_deadline;
    std::vector<Event> events;
    ro.on_event = [&](const Event& e) {
      events.push_back(e);
      if (live_events && !live_events->push(live_event(e))) live_dropped.fetch_add(1, std::memory_order_relaxed);
      if (options.on_event) options.on_event(e);
    };
    if (live_states)
      ro.on_tick = [this](const Controller& c, const RunReport& rr) {
        if (c.stats().ticks % live_every == 0) queue_live(rr, false);
      };
    RunReport rr;
    try {
      rr = run_client(controller, udp, ro);
    } catch (...) {  // an event callback that threw: the run ends there
      rr.stopped = true;
    }
    if (live_states) queue_live(rr, true);
    SimulatedControllerReport r = summarise(rr);
    r.events = std::move(events);
    {
      std::lock_guard lock(mutex);
      report = std::move(r);
      done = true;
    }
    running.store(false, std::memory_order_release);
    ended.notify_all();
  }

  SimulatedControllerReport summarise(const RunReport& rr) const {
    SimulatedControllerReport r;
    const bool completed = controller.scenario_done() || (controller.scenario_running_forever() && rr.stopped);
    using O = SimulatedControllerReport::Outcome;
    if (controller.communication_error()) r.outcome = O::communication_error, r.outcome_text = "communication error";
    else if (controller.scenario_failed()) r.outcome = O::scenario_error, r.outcome_text = "scenario error: " + controller.scenario_error();
    else if (!completed) r.outcome = O::incomplete, r.outcome_text = "scenario incomplete";
    else r.outcome = O::completed, r.outcome_text = "completed";
    r.robot = controller.robot().name;
    r.period_ms = controller.init().period_ms;
    r.stats = controller.stats();
    r.overruns = rr.overruns;
    r.reply_window_us = static_cast<double>(rr.window_ns) / 1000.0;
    r.elapsed_s = rr.elapsed_s;
    r.stopped = rr.stopped;
    const auto& h = rr.rtt;
    r.rtt_count = h.count();
    if (h.count() > 0) {
      r.rtt_min_us = us(h.min());
      r.rtt_mean_us = h.mean() / 1000.0;
      r.rtt_p50_us = us(h.percentile(50));
      r.rtt_p99_us = us(h.percentile(99));
      r.rtt_p999_us = us(h.percentile(99.9));
      r.rtt_max_us = us(h.max());
    }
    r.joint_degrees.resize(protocol::kMaxArms + 1);
    for (std::size_t arm = 1; arm <= protocol::kMaxArms; ++arm) r.joint_degrees[arm] = controller.joint_degrees(arm);
    return r;
  }
};

SimulatedController::SimulatedController(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
SimulatedController::SimulatedController(SimulatedController&&) noexcept = default;
SimulatedController& SimulatedController::operator=(SimulatedController&& o) noexcept {
  if (this != &o) {
    if (impl_) stop();
    impl_ = std::move(o.impl_);
  }
  return *this;
}

SimulatedController::~SimulatedController() {
  if (!impl_) return;
  impl_->stop_flag.store(true);
  if (impl_->thread.joinable()) impl_->thread.join();
}

SimulatedController SimulatedController::start(SimulatedControllerOptions options) {
  auto scenario = scenario_for(options);
  const std::string program = scenario.name;
  auto controller = Controller::create(robot_for(options), std::move(scenario), options.controller).value();
  const auto server = net::parse_endpoint(options.server, 1000).value();
  std::optional<net::Endpoint> local;
  if (!options.bind.empty()) local = net::parse_endpoint(options.bind, 0).value();
  auto opened = UdpClient::open(server, local);
  if (!opened)
    throw Exception(Error(opened.error().code, fmt::format("{}: C4GOpen: error opening the socket UDP port {} ({})",
                                                           event::kSocketError, server.port, opened.error().detail)));
  auto impl = std::make_unique<Impl>(std::move(controller), std::move(opened).value(), std::move(options));
  const auto& c = impl->controller;
  const auto window = reply_window(impl->options.reply_window, impl->options.reply_deadline, c.period_s());
  impl->description = fmt::format("robot {}, {} open axes, {} ms, scenario '{}', server {}, from {}, reply window {} us{}",
                                  c.robot().name, c.axis_count(), c.init().period_ms, program, server.to_string(),
                                  impl->local, std::chrono::duration_cast<std::chrono::microseconds>(window).count(),
                                  impl->options.reply_deadline.count() > 0          ? ""
                                  : impl->options.reply_window == ReplyWindow::manual ? " (the manual's T_CYCLE1)"
                                                                                      : " (lenient: one period)");
  impl->open_live();
  impl->thread = std::thread([p = impl.get()] { p->run(); });
  return SimulatedController(std::move(impl));
}

SimulatedControllerReport SimulatedController::wait() {
  std::unique_lock lock(impl_->mutex);
  impl_->ended.wait(lock, [&] { return impl_->done; });
  lock.unlock();
  if (impl_->thread.joinable()) impl_->thread.join();
  return impl_->report;
}

std::optional<SimulatedControllerReport> SimulatedController::wait_for(std::chrono::nanoseconds timeout) {
  {
    std::unique_lock lock(impl_->mutex);
    if (!impl_->ended.wait_for(lock, timeout, [&] { return impl_->done; })) return std::nullopt;
  }
  return wait();
}

SimulatedControllerReport SimulatedController::stop() {
  impl_->stop_flag.store(true);
  return wait();
}

bool SimulatedController::running() const noexcept { return impl_ && impl_->running.load(std::memory_order_acquire); }

std::string SimulatedController::local_address() const { return impl_->local; }

std::string SimulatedController::describe() const { return impl_->description; }

std::vector<std::string> SimulatedController::program_steps() const {
  std::vector<std::string> out;
  for (const auto& step : impl_->controller.scenario().steps) out.push_back(fmt::format("{} ({})", to_string(step.kind), step.where));
  return out;
}

const RobotConfig& SimulatedController::robot() const noexcept { return impl_->controller.robot(); }

bool SimulatedController::take_live(LiveState& state, const std::function<void(const LiveEvent&)>& on_event) {
  if (!impl_->live_states) return false;
  // Events first: a snapshot taken after them must not be shown before them.
  impl_->live_events->consume_all([&](const LiveEvent& e) {
    if (on_event) on_event(e);
  });
  bool got = false;
  impl_->live_states->consume_all([&](const LiveState& s) {
    state = s;
    got = true;
  });
  return got;
}

std::uint64_t SimulatedController::live_dropped() const noexcept { return impl_->live_dropped.load(std::memory_order_relaxed); }

}  // namespace axon::c4g::sim
