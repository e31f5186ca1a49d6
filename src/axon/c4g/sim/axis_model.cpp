#include "axon/c4g/sim/axis_model.hpp"

#include "axon/c4g/protocol/soft_switch.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace axon::c4g::sim {
namespace {
constexpr double kTwoPi = 2.0 * std::numbers::pi;
double clamp_abs(double v, double limit) { return std::clamp(v, -limit, limit); }
}  // namespace

AxisModel::AxisModel(const AxisParams& params, double ratio) : p_(params), inertia_(params.total_inertia(ratio)) {
  // Velocity loop: current = kv * velocity error. With velocity in turns/s, the torque needed for a
  // bandwidth w is J * w * 2 pi per turn/s.
  kv_ = p_.torque_constant > 0 ? inertia_ * p_.velocity_bandwidth * kTwoPi / p_.torque_constant : 0.0;
  ki_ = kv_ * p_.velocity_integral;
}

void AxisModel::reset(double position) noexcept {
  pos_ = position;
  vel_ = 0;
  integral_ = 0;
  current_ = 0;
  dyn_current_ = 0;
  saturated_ = false;
}

void AxisModel::step(const AxisCommand& cmd, bool powered) noexcept {
  const double limit = std::fabs(p_.current_limit);
  const double kt = p_.torque_constant;
  // Dynamic model: the current that makes the reference move by itself (inertia and friction).
  dyn_current_ = kt > 0 ? (inertia_ * cmd.acceleration + p_.viscous_friction * cmd.velocity) * kTwoPi / kt : 0.0;
  if (!powered) {
    vel_ = 0;  // the brake holds
    integral_ = 0;
    current_ = 0;
    saturated_ = false;
    return;
  }
  double loop = 0;
  if (cmd.loops) {
    const double vel_ref = p_.kp * (cmd.position - pos_) + cmd.velocity + cmd.velocity_add;
    const double err = vel_ref - vel_;
    const double loop_limit = std::max(0.0, cmd.loop_limit) * limit;
    const double unclamped = kv_ * err + integral_;
    loop = protocol::limit_current(unclamped, std::max(0.0, cmd.loop_limit), limit);
    // Anti-windup: integrate only while the loop output is not held by its limiter, or when the
    // error drives it back.
    if (unclamped == loop || (unclamped > loop) != (err > 0)) integral_ = clamp_abs(integral_ + ki_ * err * kDsaPeriod, loop_limit);
  } else {
    integral_ = 0;
  }
  const double wanted = loop + cmd.current_add + (cmd.dynamic_model ? cmd.dynamic_gain * dyn_current_ : 0.0);
  current_ = clamp_abs(wanted, limit);
  saturated_ = current_ != wanted;
  // Mechanics at the current-loop rate (semi-implicit Euler).
  const int substeps = static_cast<int>(std::lround(kDsaPeriod / kDspPeriod));
  const double h = kDsaPeriod / substeps;
  for (int i = 0; i < substeps; ++i) {
    const double torque = kt * current_ - p_.viscous_friction * vel_ * kTwoPi;  // [N m]
    const double acc = torque / (inertia_ * kTwoPi);                          // [turns/s^2]
    vel_ += acc * h;
    pos_ += vel_ * h;
  }
}

}  // namespace axon::c4g::sim
