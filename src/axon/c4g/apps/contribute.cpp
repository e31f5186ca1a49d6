#include "axon/c4g/apps/contribute.hpp"

#include "axon/c4g/protocol/mode.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace axon::c4g::apps {

using protocol::code;
using protocol::Mode;

ContributeApp::ContributeApp(ContributeOptions options) : options_(std::move(options)) {
  for (auto& a : last_) a.store(0, std::memory_order_relaxed);
  for (auto& a : peak_) a.store(0, std::memory_order_relaxed);
  if (options_.mode != 8 && options_.mode != 9)
    throw Exception(Error(CoreErrc::invalid_argument, "contribute: --mode must be 8 (velocity) or 9 (current)"));
  if (options_.amplitude.empty()) throw Exception(Error(CoreErrc::invalid_argument, "contribute: give --amplitude"));
  if (options_.ramp_s < 0 || options_.open_time_s < 0)
    throw Exception(Error(CoreErrc::invalid_argument, "contribute: times must not be negative"));
  for (double v : options_.amplitude)
    if (!std::isfinite(v)) throw Exception(Error(CoreErrc::invalid_argument, "contribute: amplitudes must be finite"));
  for (std::size_t j = 0; j < options_.amplitude.size() && options_.mode == 8; ++j)
    if (!(std::fabs(options_.amplitude[j]) <= options_.max_motor_speed))
      throw Exception(Error(CoreErrc::invalid_argument,
                            fmt::format("contribute: a velocity amplitude of {:g} motor turns/s on axis {} exceeds "
                                        "--max-motor-speed {:g}", options_.amplitude[j], j + 1, options_.max_motor_speed)));
}

void ContributeApp::setup(const protocol::InitPacket& init, const protocol::AxisMap& axes) {
  if (phase() == Phase::done || phase() == Phase::refused) return;
  set_phase(Phase::waiting);
  count_ = std::min(axes.arm_count(options_.arm), protocol::kAxesPerArm);
  first_ = axes.arm_first(options_.arm);
  period_s_ = init.period_ms > 0 ? init.period_ms * 1e-3 : 0.002;
  if (count_ == 0) {
    fail("contribute: arm %zu has no open axes", options_.arm);
    set_phase(Phase::refused);
    return;
  }
  const auto& a = options_.amplitude;
  const auto& f = options_.frequency_hz;
  for (std::size_t j = 0; j < count_; ++j) {
    amplitude_[j] = a.size() == 1 ? a[0] : (j < a.size() ? a[j] : 0.0);
    frequency_[j] = f.empty() ? 0.5 : (f.size() == 1 ? f[0] : (j < f.size() ? f[j] : 0.0));
  }
}

void ContributeApp::step(const host::CycleContext& ctx, host::ReplyBuilder& reply) {
  if (count_ == 0) return;
  const auto& req = ctx.request;
  if (first_ + count_ > req.count) return;
  const std::int32_t mode = options_.mode == 8 ? code(Mode::mode8) : code(Mode::mode9);
  bool all_in = true;
  for (std::size_t j = 0; j < count_; ++j) all_in = all_in && req.axes[first_ + j].mode == mode;
  const std::int32_t m0 = req.axes[first_].mode;
  Phase ph = phase();
  switch (ph) {
    case Phase::done: return;
    case Phase::refused:
      if (all_in) exit_from_open(reply, options_.arm);  // the safe reply adds nothing
      return;
    case Phase::waiting:
      if (!all_in || stop_requested()) return;
      ticks_ = 0;
      set_phase(Phase::running);
      ph = Phase::running;
      note(kNoteStarted);
      break;
    case Phase::exiting:
      if (m0 == code(Mode::mode0)) {
        set_phase(Phase::done);
        note(kNoteDone);
        return;
      }
      if (all_in) exit_from_open(reply, options_.arm);
      return;
    case Phase::running:
    case Phase::fading:
      if (!all_in) {
        fail("contribute: the controller left mode %d (axis 1 of arm %zu in mode %d)", options_.mode, options_.arm, m0);
        set_phase(Phase::refused);
        return;
      }
      break;
  }
  const double t = static_cast<double>(++ticks_) * period_s_;
  elapsed_.store(t, std::memory_order_relaxed);
  if (ph == Phase::running && (stop_requested() || (options_.open_time_s > 0 && t >= options_.open_time_s))) {
    fade_start_ = t;
    set_phase(Phase::fading);
    ph = Phase::fading;
    note(kNoteFading);
  }
  double env = options_.ramp_s > 0 ? std::min(1.0, t / options_.ramp_s) : 1.0;
  if (ph == Phase::fading) {
    env = options_.ramp_s > 0 ? std::max(0.0, 1.0 - (t - fade_start_) / options_.ramp_s) : 0.0;
    if (env <= 0.0) {
      env = 0.0;
      set_phase(Phase::exiting);
      ph = Phase::exiting;
    }
  }
  for (std::size_t j = 0; j < count_; ++j) {
    const double v = env * amplitude_[j] * std::sin(2.0 * std::numbers::pi * frequency_[j] * t);
    auto& ax = reply.axis(first_ + j);
    if (options_.mode == 8) ax.d4 = static_cast<float>(v * period_s_);  // turns/s -> turns per cycle
    else ax.d5 = static_cast<float>(v);
    last_[j].store(v, std::memory_order_relaxed);
    if (std::fabs(v) > peak_[j].load(std::memory_order_relaxed)) peak_[j].store(std::fabs(v), std::memory_order_relaxed);
  }
  if (ph == Phase::exiting) exit_from_open(reply, options_.arm);
}

std::string ContributeApp::note_text(std::int32_t c) const {
  switch (c) {
    case kNoteStarted:
      return fmt::format("contribute: {} contribution started (mode {}, arm {})", options_.mode == 8 ? "velocity" : "current",
                         options_.mode, options_.arm);
    case kNoteFading: return "contribute: fading the contribution out";
    case kNoteDone: return "contribute: done, the arm is back in mode 0";
    default: return App::note_text(c);
  }
}

std::string ContributeApp::status() const {
  static constexpr std::string_view names[] = {"waiting for the mode", "running", "fading", "exiting", "done", "refused"};
  std::string out = App::status() + fmt::format(" {} t={:.3f} s {}", names[static_cast<int>(phase())],
                                                elapsed_.load(std::memory_order_relaxed),
                                                options_.mode == 8 ? "velocity[turns/s]" : "current[A]");
  for (std::size_t j = 0; j < 6; ++j) out += fmt::format(" {:.3f}", last(j));
  return out;
}

std::string ContributeApp::summary() const {
  static constexpr std::string_view names[] = {"waiting", "running", "fading", "exiting", "done", "refused"};
  std::string out = App::summary() + fmt::format("contribute: mode {}, {:.3f} s, phase {}, peak per axis", options_.mode,
                                                 elapsed_.load(std::memory_order_relaxed), names[static_cast<int>(phase())]);
  for (std::size_t j = 0; j < 6; ++j) out += fmt::format(" {:.3f}", peak(j));
  return out + (options_.mode == 8 ? " turns/s\n" : " A\n");
}

}  // namespace axon::c4g::apps
