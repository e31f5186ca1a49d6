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

namespace {
OpenModeApp::Style pid_style(const PidOptions& o) {
  return {.app = "pid", .waiting = "waiting for mode 1/2", .running = "controlling", .mode = "1/2", .ramp_s = o.ramp_s,
          .exiting_runs = true, .pc_closes_loops = true};
}
}  // namespace

PidApp::PidApp(PidOptions options) : OpenModeApp(pid_style(options)), options_(std::move(options)) {
  if (options_.ramp_s < 0 || options_.open_time_s < 0)
    throw Exception(Error(CoreErrc::invalid_argument, "pid: times must not be negative"));
  for (const auto& g : options_.gains)
    if (!(g.kp >= 0 && g.kv >= 0 && g.ki >= 0))
      throw Exception(Error(CoreErrc::invalid_argument, "pid: gains must not be negative"));
  if (auto v = validate(options_.limits); !v) throw Exception(v.error());
  if (auto v = check_sine("pid", options_.amplitude_rad, options_.frequency_hz, options_.limits); !v) throw Exception(v.error());
}

void PidApp::setup(const protocol::InitPacket& init, const protocol::AxisMap& axes) {
  if (!begin_setup()) return;
  auto v = make_arm_view(init, axes, options_.arm);
  if (!v) return refuse("pid: %s", v.error().detail.c_str());
  view_ = std::move(v).value();
  const auto limits = axes.per_open_axis(init.current_limit);
  sine_.configure(options_.amplitude_rad, options_.frequency_hz, view_->count);
  for (std::size_t j = 0; j < view_->count; ++j) {
    const auto& g = options_.gains;
    gains_[j] = g.empty() ? PidGains{} : g[std::min(j, g.size() - 1)];
    limit_[j] = std::fabs(limits[view_->first + j]);
    const double step = sine_step_bound(sine_.amplitude(j), sine_.frequency(j), view_->period_s, options_.ramp_s);
    if (step > options_.limits.max_step(j) * (1 + 1e-9))
      return refuse("pid: the sine can change by %.4f deg in one cycle on axis %zu (fades included), beyond the limit "
                    "%.4f deg per cycle (--max-correction-step)", step * kRadToDeg, j + 1,
                    options_.limits.max_step(j) * kRadToDeg);
  }
}

void PidApp::step(const host::CycleContext& ctx, host::ReplyBuilder& reply) {
  if (!view_) return;
  const auto& req = ctx.request;
  Gate g = gate_for(req, view_->first, view_->count, req.axes[view_->first].mode);  // every axis in one mode
  const bool loop_mode = g.first_mode == code(Mode::mode1) || g.first_mode == code(Mode::mode1_standby) ||
                         g.first_mode == code(Mode::mode2) || g.first_mode == code(Mode::mode2_standby);
  g.entered = g.inside = g.entered && loop_mode;
  const Turn turned = turn(g, reply, view_->arm);
  if (turned == Turn::skip) return;
  if (turned == Turn::start) {
    for (std::size_t j = 0; j < view_->count; ++j) {
      loops_[j].reset();
      hold_[j] = req.axes[view_->first + j].d3;
      last_ref_[j] = hold_[j];
    }
    env_ = 0;
    mode_ = g.first_mode == code(Mode::mode1) || g.first_mode == code(Mode::mode1_standby) ? 1 : 2;
    active_mode_.store(mode_, std::memory_order_relaxed);
    started(kNoteStarted, mode_);
  }
  // Soft switching: mode 1's own trajectory waits until the switch to the PC is done.
  const bool switched = ctx.switching == nullptr || ctx.switching->axis(view_->first).interval == protocol::SwitchInterval::done;
  if (g.first_mode == code(Mode::mode1) && switched) advance_mode1(req);
  else if (g.first_mode == code(Mode::mode2)) advance(view_->period_s);
  control(ctx, reply);
}

void PidApp::advance_mode1(const protocol::Packet& req) noexcept {
  const std::size_t n = view_->count, first = view_->first;
  const double period = view_->period_s;
  const double t = advance(period);
  // Mode 1 is the PC's to leave (mode 2 the controller's).
  if (phase() == Phase::running && mode_ == 1 && (stop_requested() || (options_.open_time_s > 0 && t >= options_.open_time_s))) {
    start_fade();
    settle_s_ = 0;
  }
  env_ = envelope().step(period);
  if (phase() != Phase::fading || !envelope().faded()) return;
  // Soft switching back needs a still robot: ask for the exit once every axis has settled on the
  // hold position (or after kMaxSettle_s, when the watchdog will tell).
  bool settled = true;
  for (std::size_t j = 0; j < n; ++j) {
    const auto& q = req.axes[first + j];
    settled = settled && std::fabs(q.d3 - hold_[j]) < kSettleTurns && std::fabs(q.d4) / period < kSettleTurnsPerS;
  }
  settle_s_ += period;
  if (settled || settle_s_ >= kMaxSettle_s) set_phase(Phase::exiting);
}

void PidApp::control(const host::CycleContext& ctx, host::ReplyBuilder& reply) noexcept {
  const auto& req = ctx.request;
  const std::size_t n = view_->count, first = view_->first;
  const double period = view_->period_s;
  const std::int32_t m0 = req.axes[first].mode;
  const bool mode1 = m0 == code(Mode::mode1) || m0 == code(Mode::mode1_standby);
  protocol::ArmTransform::Vector link(static_cast<Eigen::Index>(n));
  for (std::size_t j = 0; j < n; ++j)
    link[static_cast<Eigen::Index>(j)] = env_ * sine_.value(j, run_time());
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
  if (phase() == Phase::exiting && m0 == code(Mode::mode1)) exit_from_open(reply, view_->arm);
}

std::string PidApp::note_text(std::int32_t c) const {
  switch (c) {
    case kNoteStarted: return fmt::format("pid: closing the loops (arm {})", options_.arm);
    case kNoteFading: return "pid: leaving mode 1";
    default: return OpenModeApp::note_text(c);
  }
}

std::string PidApp::status() const {
  return OpenModeApp::status() + fmt::format(" mode {} max following error {:.5f} turns, saturated {}",
                                             active_mode_.load(std::memory_order_relaxed), max_following_error(),
                                             saturated_cycles());
}

std::string PidApp::summary() const {
  return App::summary() + fmt::format("pid: max following error {:.5f} motor turns, {} cycles with a saturated current\n"
                                      "pid: soft switching: max following error {:.5f} motor turns, max current {:.3f} A\n",
                                      max_following_error(), saturated_cycles(), max_switch_error(), max_switch_current());
}

}  // namespace axon::c4g::apps
