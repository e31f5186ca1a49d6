#include "axon/c4g/apps/open_mode.hpp"

#include "axon/c4g/protocol/mode.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <numbers>

namespace axon::c4g::apps {

using protocol::code;
using protocol::Mode;

std::string_view to_string(Phase p) noexcept {
  switch (p) {
    case Phase::waiting: return "waiting";
    case Phase::running: return "running";
    case Phase::fading: return "fading";
    case Phase::holding: return "holding";
    case Phase::idle: return "idle";
    case Phase::exiting: return "exiting";
    case Phase::done: return "done";
    case Phase::refused: return "refused";
  }
  return "?";
}

double per_axis(const std::vector<double>& values, std::size_t j, double none, double missing) noexcept {
  if (values.empty()) return none;
  if (values.size() == 1) return values[0];
  return j < values.size() ? values[j] : missing;
}

double Envelope::step(double period_s) noexcept {
  const double rate = ramp_s_ > 0 ? period_s / ramp_s_ : 1.0;
  level_ = fading_ ? std::max(0.0, level_ - rate) : std::min(1.0, level_ + rate);
  if (fading_ && level_ < 1e-9) level_ = 0.0;
  return level_;
}

void SineExcitation::configure(const std::vector<double>& amplitude, const std::vector<double>& frequency_hz,
                               std::size_t axes) noexcept {
  axes_ = std::min(axes, protocol::kAxesPerArm);
  for (std::size_t j = 0; j < axes_; ++j) {
    amplitude_[j] = per_axis(amplitude, j, 0.0);
    frequency_[j] = per_axis(frequency_hz, j, kDefaultFrequencyHz);
  }
}

double SineExcitation::value(std::size_t j, double t) const noexcept {
  return amplitude_[j] * std::sin(2.0 * std::numbers::pi * frequency_[j] * t);
}

OpenModeApp::OpenModeApp(Style style) : style_(std::move(style)), envelope_(style_.ramp_s) {}

OpenModeApp::Gate OpenModeApp::gate_for(const protocol::Packet& request, std::size_t first, std::size_t count,
                                        std::int32_t mode) noexcept {
  Gate g;
  g.present = count > 0 && first + count <= request.count;
  if (!g.present) return g;
  g.entered = true;
  for (std::size_t j = 0; j < count; ++j) g.entered = g.entered && request.axes[first + j].mode == mode;
  g.inside = g.entered;
  g.first_mode = request.axes[first].mode;
  g.at_rest = g.first_mode == code(Mode::mode0);
  return g;
}

bool OpenModeApp::begin_setup() noexcept {
  const Phase p = phase();
  if ((p == Phase::done && !style_.rearm) || p == Phase::refused) return false;
  set_phase(Phase::waiting);
  return true;
}

void OpenModeApp::refuse(const char* format, ...) noexcept {
  va_list ap;
  va_start(ap, format);
  fail_v(format, ap);
  va_end(ap);
  set_phase(Phase::refused);
}

OpenModeApp::Turn OpenModeApp::turn(const Gate& g, host::ReplyBuilder& reply, std::size_t arm) noexcept {
  if (!g.present) return Turn::skip;
  Phase p = phase();
  if (p == Phase::done && style_.rearm && g.at_rest) set_phase(p = Phase::waiting);
  switch (p) {
    case Phase::done: return Turn::skip;
    case Phase::refused:
      if (g.entered && !style_.pc_closes_loops) exit_from_open(reply, arm);  // the safe reply adds nothing
      return Turn::skip;
    case Phase::waiting:
      if (!g.entered || stop_requested()) return Turn::skip;
      ticks_ = 0;
      t_ = 0;
      elapsed_.store(0, std::memory_order_relaxed);
      envelope_.reset(style_.fade_in ? 0.0 : 1.0);
      set_phase(Phase::running);
      return Turn::start;
    default: break;
  }
  if (g.at_rest && (p == Phase::exiting || style_.pc_closes_loops)) {
    set_phase(Phase::done);
    note(kNoteDone);
    return Turn::skip;
  }
  if (p == Phase::exiting && !style_.exiting_runs) {  // through the standby codes back to mode 0
    if (g.entered) exit_from_open(reply, arm);
    return Turn::skip;
  }
  if (!g.inside) {
    refuse("%.*s: the controller left mode %.*s (axis 1 of arm %zu in mode %d) at t=%.3f s",
           static_cast<int>(style_.app.size()), style_.app.data(), static_cast<int>(style_.mode.size()),
           style_.mode.data(), arm, g.first_mode, t_);
    return Turn::skip;
  }
  return Turn::run;
}

void OpenModeApp::started(std::int32_t c, std::int32_t aux) noexcept {
  runs_.fetch_add(1, std::memory_order_relaxed);
  note(c, -1, aux);
}

double OpenModeApp::advance(double period_s) noexcept {
  t_ = static_cast<double>(++ticks_) * period_s;
  elapsed_.store(t_, std::memory_order_relaxed);
  return t_;
}

void OpenModeApp::start_fade() noexcept {
  envelope_.fade_out();
  set_phase(Phase::fading);
  note(kNoteFading);
}

std::string_view OpenModeApp::phase_text() const noexcept {
  const Phase p = phase();
  if (p == Phase::waiting) return style_.waiting;
  if (p == Phase::running) return style_.running;
  return to_string(p);
}

std::string OpenModeApp::status() const {
  return App::status() + fmt::format(" {} t={:.3f} s", phase_text(), elapsed_s());
}

std::string OpenModeApp::note_text(std::int32_t c) const {
  switch (c) {
    case kNoteFading: return fmt::format("{}: fading out", style_.app);
    case kNoteDone: return fmt::format("{}: done, the arm is back in mode 0", style_.app);
    default: return App::note_text(c);
  }
}

}  // namespace axon::c4g::apps
