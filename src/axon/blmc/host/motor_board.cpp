#include "axon/blmc/host/motor_board.hpp"

#include "axon/blmc/host/board.hpp"
#include "axon/blmc/host/control_run.hpp"
#include "axon/blmc/host/error.hpp"
#include "axon/blmc/host/front_end.hpp"
#include "axon/blmc/host/session_log.hpp"
#include "axon/can/open.hpp"
#include "axon/core/loop_thread.hpp"
#include "axon/core/wakeup.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <type_traits>

namespace axon::blmc {

namespace {

using host::HostErrc;

double seconds_of(core::Duration d) { return std::chrono::duration<double>(d).count(); }

double pd_current(const MotorCommand& c, double position_rev, double velocity_rev_s) noexcept {
  return c.current_a + c.kp * (c.position_rev - position_rev) + c.kd * (c.velocity_rev_s - velocity_rev_s);
}

// The user's ControlLaw as a host::Controller: measurements in, PD terms evaluated, currents out.
class LawController final : public host::Controller {
 public:
  explicit LawController(ControlLaw law) : law_(std::move(law)) {}
  void start(const host::ControlInput& in) noexcept override { t0_ = in.now; }
  void update(const host::ControlInput& in, std::span<host::MotorPair> currents) noexcept override {
    const auto& m = in.boards[0];
    ControlState s;
    s.cycle = in.cycle;
    s.time_s = seconds_of(in.now - t0_);
    s.dt_s = seconds_of(in.dt);
    s.position_rev = {m.position.value.motor1, m.position.value.motor2};
    s.velocity_rev_s = {host::krpm_to_rev_per_s(m.velocity.value.motor1), host::krpm_to_rev_per_s(m.velocity.value.motor2)};
    s.current_a = {m.current.value.motor1, m.current.value.motor2};
    s.adc = {m.adc.value.motor1, m.adc.value.motor2};
    s.status = m.status.value;
    const Command c = law_(s);
    currents[0] = {pd_current(c[0], s.position_rev[0], s.velocity_rev_s[0]),
                   pd_current(c[1], s.position_rev[1], s.velocity_rev_s[1])};
  }

 private:
  ControlLaw law_;
  core::TimePoint t0_{};
};

// One start_control .. stop_control: shared by the caller's thread and the event-loop thread.
struct ControlRun {
  std::mutex mutex;
  std::condition_variable changed;
  bool started = false;
  bool finished = false;
  std::optional<Result<host::ControlOutcome>> outcome;
  std::exception_ptr failure;
  std::optional<host::CycleRecord> last;
  LoopFigures figures;
  core::Duration nominal{0};
  std::atomic<bool> stop{false};
  std::unique_ptr<LawController> law;
  std::optional<FrontEnd> front_end;  // when the law is its back end
  std::optional<host::CycleCsv> csv;
};

// One drained record into the run's live figures (its first record has no period yet).
void add_to_figures(LoopFigures& f, const host::CycleRecord& rec, core::Duration nominal) {
  using seconds = std::chrono::duration<double>;
  f.cycles = rec.cycle + 1;
  f.overruns = rec.overruns;
  f.compute_max_s = std::max(f.compute_max_s, seconds(rec.compute).count());
  if (rec.period <= core::Duration::zero()) return;
  f.period_max_s = std::max(f.period_max_s, seconds(rec.period).count());
  f.jitter_max_s = std::max(f.jitter_max_s, std::abs(seconds(rec.period - nominal).count()));
}

ControlReport to_report(const host::ControlOutcome& o) {
  ControlReport r;
  r.stats = o.stats;
  if (o.fault) {
    r.end = ControlEnd::fault;
    r.fault = o.fault->fault;
    r.fault_text = o.fault->fault.describe();
  }
  return r;
}

}  // namespace

struct MotorBoard::Impl {
  MotorBoardOptions options;
  core::LoopThread loop;  // first in, last out: the bus and the board live on it
  std::unique_ptr<can::Bus> bus;
  std::unique_ptr<host::Board> board;
  bool enabled = false;
  std::shared_ptr<ControlRun> run;
  LoopFigures last_figures;  // the last stopped run's

  explicit Impl(MotorBoardOptions o) : options(std::move(o)) {}
  // The loop's thread ends before the bus and the board go (close() ran first, unless the
  // constructor failed).
  ~Impl() { loop.stop(); }

  // Runs a board coroutine (it returns a Result) on the loop and waits for it (core::LoopThread::run).
  // A call that overstays its time limit is interrupted (the board's waits end at once, so the
  // coroutine ends soon), the interrupt is then taken back so that later calls work, and the call
  // throws HostErrc::timeout naming `what`.
  template <class Make>
  auto wait(Make make, core::Duration timeout, const char* what) {
    using R = typename std::invoke_result_t<Make&>::value_type;
    try {
      // LoopThread::run hands back a default-constructible value: the Result travels in an optional.
      auto r = loop.run(
          [make = std::move(make)]() -> boost::asio::awaitable<std::optional<R>> {
            auto result = co_await make();
            co_return std::optional<R>(std::move(result));
          },
          timeout, [b = board.get()] {
            if (b) b->interrupt();
          });
      return std::move(*r);
    } catch (const Exception& e) {
      if (e.code() != CoreErrc::timeout) throw;
      // Queued after the interrupt (the loop runs its work in order).
      if (board) boost::asio::post(loop.executor(), [b = board.get()] { b->clear_interrupt(); });
      throw Exception(Error(HostErrc::timeout, fmt::format("{}: {}: no result within {:.1f} s", options.name, what, seconds_of(timeout))));
    }
  }
  // Sends one of the board's settings (Board::set_onboard_* ...) and waits for it.
  template <class Send>
  void setting(const char* what, Send send) {
    if (run) throw Exception(Error(HostErrc::cyclic_active, fmt::format("{}: {}: stop_control first", options.name, what)));
    wait([b = board.get(), send] { return send(*b); }, std::chrono::seconds(2), what).value();
  }
  void interrupt() {
    boost::asio::post(loop.executor(), [b = board.get()] { b->interrupt(); });
  }
  void open(const std::string& spec_text);
  host::ControlOptions control_options(const ControlSettings& s) const;
  void start(ControlLaw law, const ControlSettings& settings, const FrontEnd* front_end = nullptr);
  ControlReport stop();
  ControlReport finish(std::chrono::milliseconds duration);  // waits for the run's end, then stop()
  void disable();
  void close() noexcept;
};

void MotorBoard::Impl::open(const std::string& spec_text) {
  const auto spec = can::parse_bus_spec(spec_text).value();
  can::OpenOptions oo;
  oo.connect_timeout = options.connect_timeout;
  // open_bus gives up after the connect timeout itself.
  bus = wait([ex = loop.executor(), spec, oo] { return can::open_bus(ex, spec, oo); },
             options.connect_timeout + std::chrono::seconds(1), "open")
            .value();
  host::BoardOptions bo;
  bo.name = options.name;
  bo.motors = options.motors;
  bo.ready_timeout = options.ready_timeout;
  bo.status_timeout = options.status_timeout;
  bo.recv_timeout_ms = options.recv_timeout_ms;
  board = loop.call([&] { return std::make_unique<host::Board>(*bus, bo); });
}

host::ControlOptions MotorBoard::Impl::control_options(const ControlSettings& s) const {
  host::ControlOptions o;
  o.limits = s.limits;
  for (std::size_t i = 0; i < 2; ++i) o.limits.motors[i] = o.limits.motors[i] && options.motors[i];
  o.loop.period = std::chrono::duration_cast<core::Duration>(s.period);
  o.loop.realtime = s.realtime;
  o.loop.cpus = s.cpus;
  o.loop.pacing = s.pace_measurements ? host::Pacing::measurements : host::Pacing::clock;
  o.refresh = std::chrono::duration_cast<core::Duration>(s.refresh);
  if (auto v = host::validate(o, options.recv_timeout_ms); !v) throw Exception(v.error());
  return o;
}

void MotorBoard::Impl::start(ControlLaw law, const ControlSettings& settings, const FrontEnd* front_end) {
  if (!enabled) throw Exception(Error(HostErrc::not_enabled, fmt::format("{}: start_control", options.name)));
  if (run) throw Exception(Error(HostErrc::cyclic_active, fmt::format("{}: start_control", options.name)));
  if (!law) throw Exception(Error(HostErrc::invalid_argument, fmt::format("{}: start_control: no control law", options.name)));
  const auto opts = control_options(settings);
  auto r = std::make_shared<ControlRun>();
  r->law = std::make_unique<LawController>(std::move(law));
  if (front_end) r->front_end = *front_end;
  if (!settings.csv.empty()) r->csv.emplace(host::CycleCsv::create(settings.csv).value());
  host::ControlHooks hooks;
  r->nominal = opts.loop.period;
  r->figures.running = true;
  hooks.record = [r](const host::CycleRecord& rec) {
    if (r->csv) r->csv->write(rec);
    const std::lock_guard lock(r->mutex);
    r->last = rec;
    add_to_figures(r->figures, rec, r->nominal);
  };
  hooks.refresh = [r](double, const host::CycleRecord*) {
    const std::lock_guard lock(r->mutex);
    if (!r->started) {
      r->started = true;
      r->changed.notify_all();
    }
    return true;
  };
  hooks.stop = [r] { return r->stop.load(); };
  if (r->front_end) hooks.done = [r] { return r->front_end->gave_up(); };
  boost::asio::co_spawn(
      loop.executor(),
      [b = board.get(), r, opts, hooks, name = options.name]() -> boost::asio::awaitable<void> {
        std::optional<Result<host::ControlOutcome>> out;
        std::exception_ptr failure;
        try {
          auto o = co_await host::run_control(*b, *r->law, opts, hooks);
          out.emplace(std::move(o));
          // A front end that never acted: nobody is steering, so the motors go off now.
          if (r->front_end && r->front_end->gave_up()) {
            if (auto d = co_await b->disable(); !d) spdlog::error("{}: disable after no first action: {}", name, d.error().message());
          }
        } catch (...) {
          failure = std::current_exception();
        }
        const std::lock_guard lock(r->mutex);
        r->outcome = std::move(out);
        r->failure = failure;
        r->finished = true;
        r->changed.notify_all();
      },
      boost::asio::detached);
  run = r;
  std::unique_lock lock(r->mutex);
  r->changed.wait_for(lock, std::chrono::seconds(5), [&] { return r->started || r->finished; });
  const bool failed = r->finished && (r->failure || !r->outcome || !*r->outcome);
  if (r->started || (r->finished && !failed)) return;  // a loop that ended at once (a fault) reports at stop
  lock.unlock();
  (void)stop();  // rethrows what ended the start
  throw Exception(Error(HostErrc::timeout, fmt::format("{}: the control loop did not start", options.name)));
}

ControlReport MotorBoard::Impl::stop() {
  auto r = std::move(run);
  if (!r) throw Exception(Error(HostErrc::not_cyclic, fmt::format("{}: stop_control: no control running", options.name)));
  r->stop = true;
  std::unique_lock lock(r->mutex);
  if (!r->changed.wait_for(lock, std::chrono::seconds(5), [&] { return r->finished; })) {
    lock.unlock();
    interrupt();
    lock.lock();
    if (!r->changed.wait_for(lock, std::chrono::seconds(2), [&] { return r->finished; }))
      throw Exception(Error(HostErrc::timeout, fmt::format("{}: the control loop did not stop", options.name)));
  }
  last_figures = r->figures;
  last_figures.running = false;
  if (r->failure) std::rethrow_exception(r->failure);
  auto report = to_report(r->outcome->value());
  if (r->front_end) {
    report.actions = r->front_end->stats();
    if (!report.fault && r->front_end->gave_up()) {
      report.end = ControlEnd::no_first_action;
      enabled = false;
    }
  }
  if (r->csv) {
    report.csv_lines = r->csv->lines();
    r->csv->flush().value();
  }
  return report;
}

void MotorBoard::Impl::disable() {
  if (run) {
    try {
      (void)stop();
    } catch (const std::exception& e) {
      spdlog::error("{}: stopping control before the disable: {}", options.name, e.what());
    }
  }
  auto r = wait([b = board.get()] { return b->disable(); }, std::chrono::seconds(5), "disable");
  enabled = false;
  r.value();
}

void MotorBoard::Impl::close() noexcept {
  try {
    if (board && (enabled || run)) disable();
  } catch (const std::exception& e) {
    spdlog::error("{}: could not disable the board (the motors may still be on): {}", options.name, e.what());
  }
  try {
    // What the disable queued goes out before the connection closes.
    if (bus) {
      auto flushed = wait([b = bus.get()] { return b->flush(std::chrono::seconds(1)); }, std::chrono::seconds(2), "flush");
      (void)flushed;
    }
    loop.call([this] {
      board.reset();
      if (bus) bus->close();
    });
  } catch (...) {
  }
  loop.stop();
}

MotorBoard::MotorBoard(const std::string& bus_spec, MotorBoardOptions options)
    : impl_(std::make_unique<Impl>(std::move(options))) {
  impl_->open(bus_spec);
}

MotorBoard::~MotorBoard() {
  if (impl_) impl_->close();
}

MotorBoard::MotorBoard(MotorBoard&&) noexcept = default;
MotorBoard& MotorBoard::operator=(MotorBoard&& other) noexcept {
  if (this != &other) {
    if (impl_) impl_->close();
    impl_ = std::move(other.impl_);
  }
  return *this;
}

void MotorBoard::enable() {
  auto& i = *impl_;
  const auto limit = i.options.ready_timeout + std::chrono::seconds(2);
  auto r = i.wait([b = i.board.get()] { return b->enable(); }, limit, "enable");
  if (!r) {
    try {
      i.disable();
    } catch (const std::exception& e) {
      spdlog::error("{}: disable after the failed enable: {}", i.options.name, e.what());
    }
    throw Exception(r.error());
  }
  i.enabled = true;
}

void MotorBoard::disable() { impl_->disable(); }

void MotorBoard::recover() {
  auto& i = *impl_;
  if (i.run) throw Exception(Error(HostErrc::cyclic_active, fmt::format("{}: recover: stop_control first", i.options.name)));
  i.enabled = true;  // the recovery enables: whatever happens next, the way out disables
  const auto limit = i.options.ready_timeout + std::chrono::seconds(2);
  i.wait([b = i.board.get()] { return b->recover(); }, limit, "recover").value();
}
bool MotorBoard::enabled() const noexcept { return impl_->enabled; }

protocol::Status MotorBoard::wait_status() {
  auto& i = *impl_;
  return i.wait([b = i.board.get(), t = i.options.status_timeout] { return b->wait_status(t); },
                                          i.options.status_timeout + std::chrono::seconds(1), "wait_status")
      .value();
}

host::Measurements MotorBoard::measurements() {
  auto& i = *impl_;
  if (i.run) {
    const std::lock_guard lock(i.run->mutex);
    if (i.run->last) return host::measurements_of(*i.run->last);
  }
  return i.loop.call([b = i.board.get()] { return b->latest(); });
}

void MotorBoard::start_control(ControlLaw law, ControlSettings settings) { impl_->start(std::move(law), settings); }

bool MotorBoard::control_running() {
  auto& r = impl_->run;
  if (!r) return false;
  const std::lock_guard lock(r->mutex);
  return !r->finished;
}

ControlReport MotorBoard::stop_control() { return impl_->stop(); }

LoopFigures MotorBoard::loop_figures() {
  auto& r = impl_->run;
  if (!r) return impl_->last_figures;
  const std::lock_guard lock(r->mutex);
  auto f = r->figures;
  f.running = !r->finished;
  return f;
}

const char* to_string(ControlEnd e) noexcept {
  switch (e) {
    case ControlEnd::requested: return "requested";
    case ControlEnd::fault: return "fault";
    case ControlEnd::no_first_action: return "no_first_action";
  }
  return "?";
}

void MotorBoard::start_control(const FrontEnd& front_end, ControlSettings settings) {
  impl_->start(front_end.law(), settings, &front_end);
}

ControlReport MotorBoard::run_control(const FrontEnd& front_end, std::chrono::milliseconds duration, ControlSettings settings) {
  impl_->start(front_end.law(), settings, &front_end);
  return impl_->finish(duration);
}

ControlReport MotorBoard::run_control(ControlLaw law, std::chrono::milliseconds duration, ControlSettings settings) {
  impl_->start(std::move(law), settings);
  return impl_->finish(duration);
}

ControlReport MotorBoard::Impl::finish(std::chrono::milliseconds duration) {
  {
    auto r = run;
    std::unique_lock lock(r->mutex);
    r->changed.wait_for(lock, duration, [&] { return r->finished; });
  }
  return stop();
}

HomingReport MotorBoard::home(host::HomingOptions options, ControlSettings settings, std::chrono::milliseconds timeout) {
  auto& i = *impl_;
  if (!i.enabled) throw Exception(Error(HostErrc::not_enabled, fmt::format("{}: home", i.options.name)));
  if (i.run) throw Exception(Error(HostErrc::cyclic_active, fmt::format("{}: home", i.options.name)));
  auto opts = i.control_options(settings);
  opts.duration = std::chrono::duration_cast<core::Duration>(timeout);
  for (std::size_t k = 0; k < 2; ++k) options.motors[k] = options.motors[k] && i.options.motors[k];
  auto r = i.wait(
      [b = i.board.get(), options, opts] { return host::run_homing(*b, options, opts); },
      opts.duration + std::chrono::seconds(3), "home");
  const auto run = std::move(r).value();
  HomingReport report;
  report.control = to_report(run.control);
  report.motors = run.motors;
  report.all_found = run.all_found;
  return report;
}

void MotorBoard::set_onboard_gains(const host::OnboardGains& gains) {
  impl_->setting("set_onboard_gains", [gains](host::Board& b) { return b.set_onboard_gains(gains); });
}

void MotorBoard::set_onboard_references(const host::OnboardReferences& references) {
  impl_->setting("set_onboard_references", [references](host::Board& b) { return b.set_onboard_references(references); });
}

void MotorBoard::set_onboard_current_limits(const host::OnboardCurrentLimits& limits) {
  impl_->setting("set_onboard_current_limits", [limits](host::Board& b) { return b.set_onboard_current_limits(limits); });
}

void MotorBoard::set_rollover_error(bool on) {
  impl_->setting("set_rollover_error", [on](host::Board& b) { return b.set_rollover_error(on); });
}

void MotorBoard::set_virtual_springs(std::array<bool, 2> on) {
  impl_->setting("set_virtual_springs", [on](host::Board& b) { return b.set_virtual_springs(on); });
}

void MotorBoard::interrupt() { impl_->interrupt(); }

void MotorBoard::clear_interrupt() {
  impl_->loop.call([b = impl_->board.get()] { b->clear_interrupt(); });
}

}  // namespace axon::blmc
