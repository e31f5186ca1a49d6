#include "axon/c4g/apps/app.hpp"

#include "axon/c4g/protocol/mode.hpp"
#include "axon/core/error.hpp"

#include <fmt/format.h>

#include <cstdarg>
#include <cstdio>

namespace axon::c4g::apps {

using protocol::code;
using protocol::Mode;

Result<ArmView> make_arm_view(const protocol::InitPacket& init, const protocol::AxisMap& map, std::size_t arm) {
  if (arm < 1 || arm > protocol::kMaxArms)
    return Error(CoreErrc::invalid_argument, fmt::format("arm {} does not exist (1..4)", arm));
  AXON_TRY(t, protocol::ArmTransform::from_init(init, arm));
  ArmView v;
  v.arm = arm;
  v.count = t.axes();
  v.first = map.arm_first(arm);
  v.period_s = init.period_ms > 0 ? init.period_ms * 1e-3 : 1e-3;
  for (std::size_t ax = 1; ax <= v.count; ++ax) {
    const auto idx = map.open_index(arm, ax);
    if (!idx)
      return Error(CoreErrc::invalid_argument,
                   fmt::format("arm {} axis {} is not open (the application drives logical axes 1..{} of the arm)", arm,
                               ax, v.count));
    if (*idx != v.first + ax - 1)
      return Error(CoreErrc::invalid_argument,
                   fmt::format("arm {}: open axes are not in logical order (axis {} at open index {})", arm, ax, *idx));
  }
  v.transform = std::move(t);
  return v;
}

App::App() : events_(1024) {
  for (auto& m : shown_mode_) m.store(0, std::memory_order_relaxed);
  for (auto& p : shown_position_) p.store(0, std::memory_order_relaxed);
}

std::string App::status() const {
  const std::size_t n = shown_count_.load(std::memory_order_relaxed);
  std::string out = fmt::format("{} cycles {}", name(), cycles());
  if (n == 0) return out + " (no packet yet)";
  out += " modes";
  for (std::size_t i = 0; i < n; ++i) out += fmt::format(" {}", shown_mode_[i].load(std::memory_order_relaxed));
  return out;
}

std::string App::summary() const {
  std::string s = fmt::format("{}: {} cycles", name(), cycles());
  if (has_error()) s += fmt::format(", error: {}", error());
  return s + "\n";
}

std::string App::error() const {
  if (!has_error()) return {};
  return std::string(error_.data());
}

void App::fail(const char* format, ...) noexcept {
  va_list ap;
  va_start(ap, format);
  fail_v(format, ap);
  va_end(ap);
}

void App::fail_v(const char* format, va_list args) noexcept {
  if (error_set_.load(std::memory_order_acquire)) return;  // the first error is the cause
  std::vsnprintf(error_.data(), error_.size(), format, args);
  error_set_.store(true, std::memory_order_release);
}

void App::push(const Event& e) noexcept {
  if (!events_.push(e)) events_dropped_.fetch_add(1, std::memory_order_relaxed);
}

void App::note(std::int32_t c, int axis, std::int32_t aux) noexcept {
  push(Event{EventKind::note, cycle_, wall_ns_, axis, c, aux});
}

void App::exit_from_open(host::ReplyBuilder& reply, std::size_t arm) noexcept {
  reply.exit_from_open(arm);
  if (arm >= 1 && arm <= protocol::kMaxArms && !exit_logged_[arm - 1]) {
    exit_logged_[arm - 1] = true;
    push(Event{EventKind::exit_sent, cycle_, wall_ns_, static_cast<int>(arm), 0, 0});
  }
}

std::vector<Event> App::drain_events() {
  std::vector<Event> out;
  events_.consume_all([&](const Event& e) { out.push_back(e); });
  return out;
}

void App::record_samples(std::size_t capacity) {
  samples_ = std::make_unique<boost::lockfree::spsc_queue<Sample>>(capacity > 0 ? capacity : 1);
}

std::size_t App::drain_samples(const std::function<void(const Sample&)>& f) {
  if (!samples_) return 0;
  return samples_->consume_all(f);
}

std::string App::fmt_code(std::int32_t c) { return fmt::format("note {}", c); }

std::string App::describe(const Event& e) const {
  switch (e.kind) {
    case EventKind::init: return fmt::format("initialization packet: {} open axes, period {} ms", e.value, e.aux);
    case EventKind::mode_change:
      return fmt::format("axis {}: mode {} -> {} ({})", e.axis + 1, e.value, e.aux, protocol::mode_name(e.aux));
    case EventKind::drives: return fmt::format("arm {}: drives {}", e.axis, e.value ? "on" : "off");
    case EventKind::exit_sent: return fmt::format("arm {}: exit from open sent", e.axis);
    case EventKind::note: return note_text(e.value);
    case EventKind::silence: return "no packets from the controller";
  }
  return "?";
}

void App::on_init(const protocol::InitPacket& init, const protocol::AxisMap& axes) {
  init_ = init;
  map_ = axes;
  have_init_ = true;
  have_packet_ = false;
  exit_logged_ = {};
  push(Event{EventKind::init, cycle_, wall_ns_, -1, init.open_axes, init.period_ms});
  setup(init, axes);
}

void App::on_cycle(const host::CycleContext& ctx, host::ReplyBuilder& reply) {
  const auto& req = ctx.request;
  cycle_ = ctx.cycle;
  wall_ns_ = ctx.arrival_wall_ns;
  const std::size_t n = req.count;
  bool all0 = true;
  for (std::size_t i = 0; i < n; ++i) {
    const std::int32_t m = req.axes[i].mode;
    if (have_packet_ && m != prev_modes_[i]) push(Event{EventKind::mode_change, cycle_, wall_ns_, static_cast<int>(i), prev_modes_[i], m});
    if (m == code(Mode::exit_open)) exit_open_seen_.store(true, std::memory_order_release);
    if (m != code(Mode::mode0) && m != code(Mode::exit_open)) all0 = false;
    shown_mode_[i].store(m, std::memory_order_relaxed);
    shown_position_[i].store(req.axes[i].d3, std::memory_order_relaxed);
  }
  for (std::size_t arm = 1; arm <= protocol::kMaxArms; ++arm) {
    const bool on = protocol::drives_on(req.infpar, arm);
    const bool has_axes = !have_init_ || map_.arm_count(arm) > 0;
    if (has_axes && (on != drives_[arm - 1] || (!have_packet_ && on)))
      push(Event{EventKind::drives, cycle_, wall_ns_, static_cast<int>(arm), on ? 1 : 0, 0});
    drives_[arm - 1] = on;
  }
  shown_count_.store(n, std::memory_order_relaxed);
  quiescent_.store(all0, std::memory_order_release);
  cycles_.fetch_add(1, std::memory_order_relaxed);

  step(ctx, reply);
  if (samples_) {
    Sample s;
    s.cycle = cycle_;
    s.wall_ns = wall_ns_;
    s.request = req;
    s.reply = reply.packet();
    if (!samples_->push(s)) samples_dropped_.fetch_add(1, std::memory_order_relaxed);
  }

  // A new series of exit requests gets logged again once the arm is back in mode 0.
  if (have_init_)
    for (std::size_t arm = 1; arm <= protocol::kMaxArms; ++arm) {
      const std::size_t first = map_.arm_first(arm);
      if (map_.arm_count(arm) > 0 && first < n && req.axes[first].mode == code(Mode::mode0) &&
          !protocol::exit_from_open(reply.packet().infpar, arm))
        exit_logged_[arm - 1] = false;
    }
  for (std::size_t i = 0; i < n; ++i) prev_modes_[i] = req.axes[i].mode;
  have_packet_ = true;
}

void App::on_silence() noexcept {
  quiescent_.store(true, std::memory_order_release);
  have_packet_ = false;
  push(Event{EventKind::silence, cycle_, wall_ns_, -1, 0, 0});
  silence();
}

}  // namespace axon::c4g::apps
