#include "axon/c4g/apps/handover.hpp"

#include "axon/c4g/protocol/mode.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace axon::c4g::apps {

using protocol::code;
using protocol::Mode;

namespace {
bool main_open_mode(std::int32_t m) noexcept {
  return m == 1 || m == 2 || m == 4 || m == 5 || m == 7 || m == 8 || m == 9;
}
}  // namespace

HandoverApp::HandoverApp(HandoverOptions options) : options_(std::move(options)) {
  if (!(options_.hold_s >= 0)) throw Exception(Error(CoreErrc::invalid_argument, "handover: the hold time must not be negative"));
  if (options_.stream) {
    for (int mode : {4, 5}) {
      StreamOptions s = *options_.stream;
      s.mode = mode;
      s.arm = options_.arm;
      s.rearm = true;
      auto app = std::make_unique<StreamApp>(std::move(s));
      (mode == 4 ? stream4_ : stream5_) = app.get();
      parts_.push_back(std::move(app));
    }
  }
  CorrectOptions c = options_.correct.value_or(CorrectOptions{});
  if (!c.values && !c.feed && c.amplitude_rad.empty()) {
    c.amplitude_rad = {0.0};  // a zero correction
    c.open_time_s = options_.hold_s;
    c.ramp_s = 0;
  }
  c.arm = options_.arm;
  c.rearm = true;
  auto app = std::make_unique<CorrectApp>(std::move(c));
  correct_ = app.get();
  parts_.push_back(std::move(app));
}

void HandoverApp::setup(const protocol::InitPacket& init, const protocol::AxisMap& axes) {
  period_s_ = init.period_ms > 0 ? init.period_ms * 1e-3 : 1e-3;
  for (auto& p : parts_) p->on_init(init, axes);
}

void HandoverApp::step(const host::CycleContext& ctx, host::ReplyBuilder& reply) {
  const auto* map = axis_map();
  const std::size_t arm = options_.arm;
  if (map == nullptr || map->arm_count(arm) == 0) return;
  const std::size_t first = map->arm_first(arm);
  if (first >= ctx.request.count) return;
  const std::int32_t m0 = ctx.request.axes[first].mode;
  const std::int32_t before = previous_mode(first);

  if (stop_requested())
    for (auto& p : parts_)
      if (!p->stop_requested()) p->request_stop();
  for (auto& p : parts_) p->on_cycle(ctx, reply);
  for (auto& p : parts_)
    if (p->has_error() && !has_error()) fail("%s", p->error_text());

  if (m0 != before && main_open_mode(m0)) {
    phases_.fetch_add(1, std::memory_order_relaxed);
    current_.store(m0, std::memory_order_relaxed);
    held_ = 0;
    hold_noted_ = false;
    note(kNoteEntered + m0, static_cast<int>(arm));
    const bool served = m0 == 7 || ((m0 == 4 || m0 == 5));
    if (!served) note(kNoteUnserved + m0, static_cast<int>(arm));
  }
  if (m0 == code(Mode::mode0)) current_.store(0, std::memory_order_relaxed);

  if ((m0 == 4 || m0 == 5) && !options_.stream) {
    // Hold: the server's safe reply already keeps mode 4's last target and adds nothing in mode 5.
    if (static_cast<double>(++held_) * period_s_ >= options_.hold_s || stop_requested()) {
      if (!hold_noted_) note(kNoteHoldOver, static_cast<int>(arm));
      hold_noted_ = true;
      exit_from_open(reply, arm);
    }
  } else if (m0 == 1 || m0 == 2 || m0 == 8 || m0 == 9) {
    exit_from_open(reply, arm);
  }
}

void HandoverApp::silence() noexcept {
  for (auto& p : parts_) p->on_silence();
  for (auto& p : parts_)
    if (p->has_error() && !has_error()) fail("%s", p->error_text());
}

std::vector<Event> HandoverApp::drain_events() {
  auto out = App::drain_events();
  for (std::size_t i = 0; i < parts_.size(); ++i)
    for (auto e : parts_[i]->drain_events()) {
      if (e.kind == EventKind::note) {
        e.value += static_cast<std::int32_t>(i + 1) * kPartBase;
        out.push_back(e);
      } else if (e.kind == EventKind::exit_sent) {
        out.push_back(e);
      }
    }
  std::stable_sort(out.begin(), out.end(), [](const Event& a, const Event& b) { return a.cycle < b.cycle; });
  return out;
}

std::string HandoverApp::note_text(std::int32_t c) const {
  if (c >= kPartBase) {
    const auto i = static_cast<std::size_t>(c / kPartBase - 1);
    if (i < parts_.size()) {
      Event e;
      e.kind = EventKind::note;
      e.value = c % kPartBase;
      return parts_[i]->describe(e);
    }
  }
  const auto served_by = [&](std::int32_t m) -> std::string {
    if (m == 4 || m == 5) return options_.stream ? "trajectory" : fmt::format("hold {:.3f} s", options_.hold_s);
    if (m == 7) return options_.correct ? "correction" : fmt::format("zero correction {:.3f} s", options_.hold_s);
    return "nothing";
  };
  if (c >= kNoteUnserved && c < kNoteUnserved + 100)
    return fmt::format("handover: no part serves mode {}: exit from open", c - kNoteUnserved);
  if (c >= kNoteEntered && c < kNoteEntered + 100)
    return fmt::format("handover: arm {} entered open mode {} ({})", options_.arm, c - kNoteEntered, served_by(c - kNoteEntered));
  if (c == kNoteHoldOver) return "handover: hold time over: exit from open";
  return App::note_text(c);
}

std::string HandoverApp::status() const {
  return App::status() + fmt::format(" phases {} serving {}", phases(), current_.load(std::memory_order_relaxed));
}

std::string HandoverApp::summary() const {
  std::string s = App::summary() + fmt::format("handover: {} open phases", phases());
  if (stream4_) s += fmt::format(", {} trajectories in mode 4, {} in mode 5", stream4_->runs(), stream5_->runs());
  s += fmt::format(", {} corrections\n", correct_->runs());
  return s;
}

}  // namespace axon::c4g::apps
