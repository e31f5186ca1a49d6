#include "axon/c4g/apps/pid.hpp"

#include "axon/c4g/protocol/mode.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace axon::c4g::apps {

using protocol::code;
using protocol::Mode;

double AxisPid::update(const PidGains& g, double p_target, double v_target, double p_actual, double v_actual,
                       double feedforward, double limit, double dt, double authority) noexcept {
  const double lim = limit > 0 ? limit : std::numeric_limits<double>::infinity();
  const double v_ref = v_target + g.kp * (p_target - p_actual);
  const double ev = v_ref - v_actual;
  const double u = g.kv * ev + integral_ + feedforward;
  const double out = std::clamp(u, -lim, lim);
  saturated_ = out != u;
  // Conditional integration: grow the integral only when that does not push further into saturation.
  const double share = std::clamp(authority, 0.0, 1.0);
  if (!saturated_ || (u > lim && ev < 0) || (u < -lim && ev > 0)) integral_ += share * g.kv * g.ki * ev * dt;
  integral_ = std::clamp(integral_, -lim, lim);
  return out;
}

PidApp::PidApp(PidOptions options) : options_(std::move(options)) {
  if (options_.ramp_s < 0 || options_.open_time_s < 0)
    throw Exception(Error(CoreErrc::invalid_argument, "pid: times must not be negative"));
  for (const auto& g : options_.gains)
    if (!(g.kp >= 0 && g.kv >= 0 && g.ki >= 0))
      throw Exception(Error(CoreErrc::invalid_argument, "pid: gains must not be negative"));
  if (auto v = validate(options_.limits); !v) throw Exception(v.error());
  if (auto v = check_sine("pid", options_.amplitude_rad, options_.frequency_hz, options_.limits); !v) throw Exception(v.error());
}

void PidApp::setup(const protocol::InitPacket& init, const protocol::AxisMap& axes) {
  if (phase() == Phase::done || phase() == Phase::refused) return;
  set_phase(Phase::waiting);
  auto v = make_arm_view(init, axes, options_.arm);
  if (!v) {
    fail("pid: %s", v.error().detail.c_str());
    set_phase(Phase::refused);
    return;
  }
  view_ = std::move(v).value();
  const auto limits = axes.per_open_axis(init.current_limit);
  for (std::size_t j = 0; j < view_->count; ++j) {
    const auto& g = options_.gains;
    gains_[j] = g.empty() ? PidGains{} : (g.size() == 1 ? g[0] : (j < g.size() ? g[j] : g.back()));
    const auto& a = options_.amplitude_rad;
    const auto& f = options_.frequency_hz;
    amplitude_[j] = a.empty() ? 0.0 : (a.size() == 1 ? a[0] : (j < a.size() ? a[j] : 0.0));
    frequency_[j] = f.empty() ? 0.5 : (f.size() == 1 ? f[0] : (j < f.size() ? f[j] : 0.0));
    limit_[j] = std::fabs(limits[view_->first + j]);
    const double step = sine_step_bound(amplitude_[j], frequency_[j], view_->period_s, options_.ramp_s);
    if (step > options_.limits.max_step(j) * (1 + 1e-9)) {
      fail("pid: the sine can change by %.4f deg in one cycle on axis %zu (fades included), beyond the limit %.4f deg per "
           "cycle (--max-correction-step)", step * kRadToDeg, j + 1, options_.limits.max_step(j) * kRadToDeg);
      set_phase(Phase::refused);
      return;
    }
  }
}

void PidApp::step(const host::CycleContext& ctx, host::ReplyBuilder& reply) {
  if (!view_) return;
  const auto& req = ctx.request;
  const std::size_t n = view_->count, first = view_->first;
  if (first + n > req.count) return;
  const std::int32_t m0 = req.axes[first].mode;
  bool same = true;
  for (std::size_t j = 1; j < n; ++j) same = same && req.axes[first + j].mode == m0;
  const bool mode1 = m0 == code(Mode::mode1) || m0 == code(Mode::mode1_standby);
  const bool mode2 = m0 == code(Mode::mode2) || m0 == code(Mode::mode2_standby);
  const double period = view_->period_s;
  Phase ph = phase();

  if (ph == Phase::done || ph == Phase::refused) return;
  if (ph == Phase::waiting) {
    if (!same || !(mode1 || mode2) || stop_requested()) return;
    for (std::size_t j = 0; j < n; ++j) {
      loops_[j].reset();
      hold_[j] = req.axes[first + j].d3;
      last_ref_[j] = hold_[j];
    }
    t_ = 0;
    ticks_ = 0;
    env_ = 0;
    mode_ = mode1 ? 1 : 2;
    active_mode_.store(mode_, std::memory_order_relaxed);
    set_phase(Phase::controlling);
    ph = Phase::controlling;
    note(kNoteStarted, -1, mode_);
  }
  if (m0 == code(Mode::mode0)) {
    set_phase(Phase::done);
    note(kNoteDone);
    return;
  }
  if (!same || !(mode1 || mode2)) {
    fail("pid: the controller left the loop modes (axis 1 of arm %zu in mode %d)", view_->arm, m0);
    set_phase(Phase::refused);
    return;
  }

  const bool leaving_by_pc = mode_ == 1;
  // Soft switching: mode 1's own trajectory waits until the switch to the PC is done.
  const bool switched = ctx.switching == nullptr || ctx.switching->axis(first).interval == protocol::SwitchInterval::done;
  if (m0 == code(Mode::mode1) && switched) {
    t_ = static_cast<double>(++ticks_) * period;
    elapsed_.store(t_, std::memory_order_relaxed);
    if (ph == Phase::controlling) {
      env_ = options_.ramp_s > 0 ? std::min(1.0, t_ / options_.ramp_s) : 1.0;
      if (leaving_by_pc && (stop_requested() || (options_.open_time_s > 0 && t_ >= options_.open_time_s))) {
        set_phase(Phase::fading);
        ph = Phase::fading;
        settle_s_ = 0;
        note(kNoteLeaving);
      }
    }
    if (ph == Phase::fading) {
      env_ = options_.ramp_s > 0 ? std::max(0.0, env_ - period / options_.ramp_s) : 0.0;
      if (env_ < 1e-9) {
        env_ = 0.0;
        // Soft switching back needs a still robot: ask for the exit once every axis has settled on
        // the hold position (or after kMaxSettle_s, when the watchdog will tell).
        bool settled = true;
        for (std::size_t j = 0; j < n; ++j) {
          const auto& q = req.axes[first + j];
          settled = settled && std::fabs(q.d3 - hold_[j]) < kSettleTurns && std::fabs(q.d4) / period < kSettleTurnsPerS;
        }
        settle_s_ += period;
        if (settled || settle_s_ >= kMaxSettle_s) {
          set_phase(Phase::exiting);
          ph = Phase::exiting;
        }
      }
    }
  } else if (m0 == code(Mode::mode2)) {
    t_ = static_cast<double>(++ticks_) * period;
    elapsed_.store(t_, std::memory_order_relaxed);
  }

  protocol::ArmTransform::Vector link(static_cast<Eigen::Index>(n));
  for (std::size_t j = 0; j < n; ++j)
    link[static_cast<Eigen::Index>(j)] = env_ * amplitude_[j] * std::sin(2.0 * std::numbers::pi * frequency_[j] * t_);
  const auto offset = view_->transform.motor_velocity(link);

  double worst = max_error_.load(std::memory_order_relaxed);
  double worst_switch = max_switch_error_.load(std::memory_order_relaxed);
  double worst_current = max_switch_current_.load(std::memory_order_relaxed);
  bool any_saturated = false;
  for (std::size_t j = 0; j < n; ++j) {
    const auto& q = req.axes[first + j];
    double ref = 0, vel = 0;  // [turns], [turns/s]
    if (m0 == code(Mode::mode1)) {
      ref = hold_[j] + offset[static_cast<Eigen::Index>(j)];
      vel = (ref - last_ref_[j]) / period;
    } else if (m0 == code(Mode::mode1_standby)) {
      ref = last_ref_[j];  // 1': keep holding where the PC left it
    } else {
      ref = q.d1;  // 2 / 2': the controller's trajectory
      vel = q.d2 / period;
    }
    const double ff = options_.dynamic_model_feedforward ? q.ext1 : 0.0;
    // The reducer's factor: eta entering, rho leaving, 1 once the PC has the axis (no tracker: 1).
    const protocol::SwitchSample* sw = ctx.switching ? &ctx.switching->axis(first + j) : nullptr;
    const double factor = sw ? sw->pc_gain() : 1.0;
    if (j == 0) factor_.store(factor, std::memory_order_relaxed);
    double current = loops_[j].update(gains_[j], ref, vel, q.d3, q.d4 / period, ff, limit_[j], period, factor);
    if (options_.reduce_in_pc) current *= factor;
    if (sw && sw->robot_must_be_still()) {
      worst_switch = std::max(worst_switch, std::fabs(ref - q.d3));
      worst_current = std::max(worst_current, std::fabs(current));
    }
    any_saturated = any_saturated || loops_[j].saturated();
    auto& r = reply.axis(first + j);
    if (mode1) {
      r.d1 = static_cast<float>(ref);
      r.d2 = static_cast<float>(ref - last_ref_[j]);
      last_ref_[j] = ref;
    }
    r.d4 = 0;
    r.d5 = static_cast<float>(current);
    worst = std::max(worst, std::fabs(ref - q.d3));
  }
  max_error_.store(worst, std::memory_order_relaxed);
  max_switch_error_.store(worst_switch, std::memory_order_relaxed);
  max_switch_current_.store(worst_current, std::memory_order_relaxed);
  if (any_saturated) saturated_cycles_.fetch_add(1, std::memory_order_relaxed);
  if (ph == Phase::exiting && m0 == code(Mode::mode1)) exit_from_open(reply, view_->arm);
}

std::string PidApp::note_text(std::int32_t c) const {
  switch (c) {
    case kNoteStarted: return fmt::format("pid: closing the loops (arm {})", options_.arm);
    case kNoteLeaving: return "pid: leaving mode 1";
    case kNoteDone: return "pid: done, the arm is back in mode 0";
    default: return App::note_text(c);
  }
}

std::string PidApp::status() const {
  static constexpr std::string_view names[] = {"waiting for mode 1/2", "controlling", "fading", "exiting", "done", "refused"};
  return App::status() + fmt::format(" {} mode {} t={:.3f} s max following error {:.5f} turns, saturated {}",
                                     names[static_cast<int>(phase())], active_mode_.load(std::memory_order_relaxed),
                                     elapsed_.load(std::memory_order_relaxed), max_following_error(), saturated_cycles());
}

std::string PidApp::summary() const {
  return App::summary() + fmt::format("pid: max following error {:.5f} motor turns, {} cycles with a saturated current\n"
                                      "pid: soft switching: max following error {:.5f} motor turns, max current {:.3f} A\n",
                                      max_following_error(), saturated_cycles(), max_switch_error(), max_switch_current());
}

}  // namespace axon::c4g::apps
