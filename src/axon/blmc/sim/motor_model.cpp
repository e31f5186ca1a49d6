#include "axon/blmc/sim/motor_model.hpp"

#include "axon/blmc/protocol/units.hpp"

#include <algorithm>
#include <cmath>

namespace axon::blmc::sim {
namespace {

constexpr double kTwoPi = protocol::kTwoPi;
// Below this speed [rev/s] a rotor counts as standing (static friction applies).
constexpr double kRestEpsilon = 1e-9;

double sign(double v) noexcept { return v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0); }

}  // namespace

MotorModel::MotorModel(MotorConfig config)
    : config_(config), inertia_(config.rotor_inertia_kgm2 + config.load.inertia_kgm2),
      position_rev_(config.initial_position_rev) {
  index_events_.reserve(16);
}

double MotorModel::applied_current(double cmd) const noexcept {
  if (!std::isfinite(cmd)) return 0.0;
  double i = std::clamp(cmd, -config_.current_limit_a, config_.current_limit_a);
  if (config_.supply_voltage_v > 0) {
    const double emf = config_.torque_constant_nm_per_a * velocity_rev_s_ * kTwoPi;
    const double hi = (config_.supply_voltage_v - emf) / config_.winding_resistance_ohm;
    const double lo = (-config_.supply_voltage_v - emf) / config_.winding_resistance_ohm;
    i = std::clamp(i, std::min(lo, 0.0), std::max(hi, 0.0));
  }
  return i;
}

void MotorModel::substep(double current_cmd_a, double dt) noexcept {
  current_a_ = applied_current(current_cmd_a);
  const double w = velocity_rev_s_ * kTwoPi;  // rad/s
  const double spring =
      -config_.load.spring_nm_per_rad * (position_rev_ - config_.load.spring_center_rev) * kTwoPi;
  const double drive = config_.torque_constant_nm_per_a * current_a_ + spring;
  const double fc = config_.coulomb_friction_nm;
  double w_next = 0;
  if (std::abs(w) < kRestEpsilon * kTwoPi) {
    // Standing: breaks away only when the drive beats static friction.
    if (std::abs(drive) > fc) w_next = (drive - fc * sign(drive)) / inertia_ * dt;
  } else {
    const double torque = drive - config_.viscous_friction_nms * w - fc * sign(w);
    w_next = w + torque / inertia_ * dt;
    // Friction alone cannot reverse the motion: it stops the rotor.
    if (sign(w_next) != sign(w) && std::abs(drive) <= fc) w_next = 0;
  }
  velocity_rev_s_ = w_next / kTwoPi;
  const double before = position_rev_;
  position_rev_ += velocity_rev_s_ * dt;  // semi-implicit: the new velocity moves the shaft
  record_crossings(before, position_rev_);
}

void MotorModel::record_crossings(double before, double after) {
  if (before == after) return;
  const double off = config_.index_offset_rev;
  const double a = std::floor(before - off);
  const double b = std::floor(after - off);
  if (a != b) {
    // Marks at k + off for every integer k between the two readings, in the order passed.
    const double step = b > a ? 1.0 : -1.0;
    double k = b > a ? a + 1 : a;
    const double last = b > a ? b : b + 1;
    for (int guard = 0; guard < 64; ++guard) {
      ++index_count_;
      if (index_events_.size() < 1024) index_events_.push_back(wrapped(k + off));
      if (k == last) break;
      k += step;
    }
  }
  const auto turn = [](double p) { return std::floor((p + kPositionRolloverRev) / (2 * kPositionRolloverRev)); };
  const double ta = turn(before);
  const double tb = turn(after);
  if (ta != tb) rollovers_ += static_cast<std::uint64_t>(std::abs(tb - ta));
}

void MotorModel::advance(double current_cmd_a, double duration_s) noexcept {
  if (!(duration_s > 0)) return;
  const auto n = static_cast<long>(std::floor(duration_s / kSubstepS + 1e-9));
  for (long i = 0; i < n; ++i) substep(current_cmd_a, kSubstepS);
  const double rest = duration_s - static_cast<double>(n) * kSubstepS;
  if (rest > 1e-12) substep(current_cmd_a, rest);
}

void MotorModel::hold(double) noexcept {
  velocity_rev_s_ = 0;
  current_a_ = 0;
}

double MotorModel::wrapped(double continuous) const noexcept {
  const double span = 2 * kPositionRolloverRev;
  double p = std::fmod(continuous + kPositionRolloverRev, span);
  if (p < 0) p += span;
  p -= kPositionRolloverRev;
  if (config_.encoder_counts_per_rev > 0) {
    const double cpr = config_.encoder_counts_per_rev;
    p = std::floor(p * cpr + 1e-9) / cpr;
  }
  return p;
}

double MotorModel::position_rev() const noexcept { return wrapped(position_rev_); }

void MotorModel::set_state(double position_rev, double velocity_rev_s) noexcept {
  position_rev_ = position_rev;
  velocity_rev_s_ = velocity_rev_s;
  index_events_.clear();
}

}  // namespace axon::blmc::sim
