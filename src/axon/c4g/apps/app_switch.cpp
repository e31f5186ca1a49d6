#include "axon/c4g/apps/app_switch.hpp"

#include "axon/c4g/apps/echo.hpp"
#include "axon/c4g/apps/open_mode.hpp"
#include "axon/c4g/protocol/packet.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <thread>

namespace axon::c4g::apps {

namespace {

double seconds_between(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

std::chrono::steady_clock::duration after(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(s));
}

// Apps that hold no open mode of their own: the monitor and the echo (whose reply in 0' is the
// server's safe reply too) never leave a mode, and an open-mode app waiting for its mode (or done
// with it) has none; the arm's mode, if open, is then the program's, which the monitor answers as
// before. Taking them out needs no wait.
bool holds_no_mode(const App& app) {
  if (dynamic_cast<const MonitorApp*>(&app) != nullptr || dynamic_cast<const EchoApp*>(&app) != nullptr) return true;
  const auto* o = dynamic_cast<const OpenModeApp*>(&app);
  return o != nullptr && (o->phase() == Phase::waiting || o->phase() == Phase::done);
}

}  // namespace

// Marks one cycle-thread call: the epoch is odd from before the app pointer is read until the call
// returned (or threw).
struct AppSwitch::Epoch {
  std::atomic<std::uint64_t>& epoch;
  explicit Epoch(std::atomic<std::uint64_t>& e) noexcept : epoch(e) { epoch.fetch_add(1, std::memory_order_seq_cst); }
  ~Epoch() { epoch.fetch_add(1, std::memory_order_release); }
  Epoch(const Epoch&) = delete;
  Epoch& operator=(const Epoch&) = delete;
};

AppSwitch::AppSwitch(AppSwitchOptions options) : options_(options) {
  for (auto& d : shown_drives_) d.store(false, std::memory_order_relaxed);
}

AppSwitch::~AppSwitch() {
  // The server (which calls the cycle side) is gone by now: nothing uses current_ any more.
  current_.store(nullptr, std::memory_order_seq_cst);
}

// ---- cycle thread ----

App& AppSwitch::serving() noexcept {
  App* a = current_.load(std::memory_order_seq_cst);
  return a != nullptr ? *a : monitor_;
}

void AppSwitch::setup(const protocol::InitPacket& init, const protocol::AxisMap& axes) {
  const Epoch mark(epoch_);
  {
    std::lock_guard lock(init_mutex_);  // once per initialization packet, as the Server's own copy
    init_ = init;
    map_ = axes;
    ++init_generation_;
  }
  monitor_.on_init(init, axes);
  if (App* a = current_.load(std::memory_order_seq_cst)) a->on_init(init, axes);
}

void AppSwitch::step(const host::CycleContext& ctx, host::ReplyBuilder& reply) {
  const Epoch mark(epoch_);
  for (std::size_t arm = 1; arm <= protocol::kMaxArms; ++arm)
    shown_drives_[arm - 1].store(protocol::drives_on(ctx.request.infpar, arm), std::memory_order_relaxed);
  serving().on_cycle(ctx, reply);
}

void AppSwitch::silence() noexcept {
  const Epoch mark(epoch_);
  for (auto& d : shown_drives_) d.store(false, std::memory_order_relaxed);
  monitor_.on_silence();
  if (App* a = current_.load(std::memory_order_seq_cst)) a->on_silence();
}

// ---- control side ----

// After current_ changed: the cycle thread either read the new pointer or is inside the call that
// read the old one (the epoch is odd); wait for that call to end. Calls take microseconds.
void AppSwitch::wait_unused() const noexcept {
  const std::uint64_t e = epoch_.load(std::memory_order_seq_cst);
  if ((e & 1u) == 0) return;
  while (epoch_.load(std::memory_order_acquire) == e) std::this_thread::sleep_for(std::chrono::microseconds(50));
}

Result<void> AppSwitch::install(std::unique_ptr<App> app) {
  if (!app) return Error(CoreErrc::invalid_argument, "no application to install");
  std::lock_guard lock(control_);
  if (app_)
    return Error(CoreErrc::invalid_argument,
                 fmt::format("{} is in force{}: stop it first", app_->name(), stage_ == Stage::serving ? "" : " (stopping)"));
  // Set up with the last initialization packet here; should another arrive meanwhile, again.
  std::uint64_t generation = 0;
  while (true) {
    std::optional<protocol::InitPacket> init;
    protocol::AxisMap map;
    {
      std::lock_guard il(init_mutex_);
      init = init_;
      map = map_;
      generation = init_generation_;
    }
    if (init) app->on_init(*init, map);
    std::lock_guard il(init_mutex_);
    if (generation != init_generation_) continue;
    current_.store(app.get(), std::memory_order_seq_cst);  // in force from the next call
    break;
  }
  app_ = std::move(app);
  since_ = Clock::now();
  stage_ = Stage::serving;
  drive_off_asked_ = false;
  installs_.fetch_add(1, std::memory_order_relaxed);
  return axon::ok();
}

void AppSwitch::begin_stop() {
  std::lock_guard lock(control_);
  if (!app_ || stage_ != Stage::serving) return;
  app_->request_stop();
  stage_ = Stage::leaving;
  deadline_ = Clock::now() + after(options_.stop_timeout_s);
}

bool AppSwitch::settled(const host::Server& server) const {
  const auto st = server.state();
  return quiescent() || st == host::ServerState::silent || st == host::ServerState::waiting || server.safety().obeyed() ||
         holds_no_mode(*app_);
}

AppEnded AppSwitch::take_out(std::string reason, bool left_cleanly) {
  current_.store(nullptr, std::memory_order_seq_cst);  // the monitor from the next call
  wait_unused();
  drain_app_locked(leftover_);
  AppEnded e;
  e.app = std::string(app_->name());
  e.reason = std::move(reason);
  e.finished = app_->finished();
  e.error = app_->error();
  e.left_cleanly = left_cleanly;
  e.drive_off = drive_off_asked_;
  e.summary = app_->summary();
  e.in_force_s = seconds_between(since_, Clock::now());
  e.serial = installs_.load(std::memory_order_relaxed);
  last_ended_ = e;
  app_.reset();
  stage_ = Stage::serving;
  drive_off_asked_ = false;
  return e;
}

std::optional<AppEnded> AppSwitch::poll(host::Server& server) {
  std::lock_guard lock(control_);
  if (!app_) return std::nullopt;
  const auto now = Clock::now();
  auto why = [&] { return app_->has_error() ? "refused" : app_->stop_requested() ? "stopped" : "finished"; };
  auto drive_off = [&] {
    spdlog::warn("c4g switch: {} did not leave its open mode: asking for drive off", app_->name());
    server.safety().trip(host::FaultReason::user_request);
    drive_off_asked_ = true;
    stage_ = Stage::driving_off;
    deadline_ = now + after(options_.drive_off_wait_s);
  };
  switch (stage_) {
    case Stage::serving:
      if (app_->finished()) return take_out("finished", true);
      if (!app_->has_error()) return std::nullopt;
      if (app_->drive_off_on_error()) {  // the PC closes the loops: no passive reply holds the robot
        drive_off();
        return std::nullopt;
      }
      app_->request_stop();
      stage_ = Stage::leaving;
      deadline_ = now + after(options_.stop_timeout_s);
      return std::nullopt;
    case Stage::leaving:
      if (settled(server)) return take_out(why(), true);
      if (now >= deadline_) drive_off();
      return std::nullopt;
    case Stage::driving_off:
      if (settled(server) || now >= deadline_) return take_out(why(), settled(server));
      return std::nullopt;
  }
  return std::nullopt;
}

std::optional<AppEnded> AppSwitch::stop(host::Server& server, const std::function<void()>& between) {
  std::uint64_t serial = 0;
  {
    std::lock_guard lock(control_);
    if (!app_) return std::nullopt;
    serial = installs_.load(std::memory_order_relaxed);
  }
  begin_stop();
  while (true) {
    if (auto ended = poll(server)) return ended;
    {
      std::lock_guard lock(control_);
      if (!app_ || installs_.load(std::memory_order_relaxed) != serial)  // another thread's poll took it out
        return last_ended_ && last_ended_->serial == serial ? last_ended_ : std::nullopt;
    }
    if (between) between();
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

bool AppSwitch::has_app() const {
  std::lock_guard lock(control_);
  return app_ != nullptr;
}

AppInForce AppSwitch::in_force() const {
  std::lock_guard lock(control_);
  AppInForce v;
  const App& a = app_ ? *app_ : static_cast<const App&>(monitor_);
  v.app = std::string(a.name());
  v.installed = app_ != nullptr;
  if (const auto* o = dynamic_cast<const OpenModeApp*>(&a)) v.phase = std::string(to_string(o->phase()));
  v.status = a.status();
  v.stopping = app_ && stage_ != Stage::serving;
  v.error = a.error();
  v.cycles = a.cycles();
  v.in_force_s = app_ ? seconds_between(since_, Clock::now()) : 0.0;
  return v;
}

std::string AppSwitch::status() const {
  std::lock_guard lock(control_);
  return app_ ? app_->status() : monitor_.status();
}

std::string AppSwitch::summary() const {
  std::lock_guard lock(control_);
  return app_ ? app_->summary() : monitor_.summary();
}

void AppSwitch::drain_app_locked(std::vector<Described>& out) {
  if (!app_) return;
  for (const auto& e : app_->drain_events())
    if (e.kind == EventKind::note || e.kind == EventKind::exit_sent)  // the rest the switch reports itself
      out.push_back({e, std::string(app_->name()), app_->describe(e)});
}

std::vector<AppSwitch::Described> AppSwitch::drain() {
  std::lock_guard lock(control_);
  std::vector<Described> out = std::move(leftover_);
  leftover_.clear();
  for (const auto& e : App::drain_events()) out.push_back({e, std::string(name()), describe(e)});
  monitor_.drain_events();  // its modes and drives are the switch's own
  drain_app_locked(out);
  return out;
}

std::optional<std::pair<protocol::InitPacket, protocol::AxisMap>> AppSwitch::init_packet() const {
  std::lock_guard lock(init_mutex_);
  if (!init_) return std::nullopt;
  return std::make_pair(*init_, map_);
}

std::vector<std::int32_t> AppSwitch::modes() const {
  const std::size_t n = shown_count_.load(std::memory_order_relaxed);
  std::vector<std::int32_t> out(n);
  for (std::size_t i = 0; i < n; ++i) out[i] = shown_mode_[i].load(std::memory_order_relaxed);
  return out;
}

bool AppSwitch::drives_on(std::size_t arm) const noexcept {
  return arm >= 1 && arm <= protocol::kMaxArms && shown_drives_[arm - 1].load(std::memory_order_relaxed);
}

}  // namespace axon::c4g::apps
