#include "axon/blmc/host/pd_controller.hpp"

#include "axon/blmc/host/error.hpp"

#include <fmt/format.h>

#include <cmath>
#include <numbers>

namespace axon::blmc::host {

double TrackingStats::rms_rev() const noexcept {
  return samples ? std::sqrt(sum_sq / static_cast<double>(samples)) : 0.0;
}

PdController::PdController(std::size_t boards, PdGains gains, std::array<PdTarget, 2> targets, core::Duration settle)
    : gains_(gains), targets_(targets), settle_(settle), start_(boards * 2, 0.0), stats_(boards * 2) {
  auto check = [](const char* what, double v) {
    if (!std::isfinite(v) || v < 0)
      throw Exception(Error(HostErrc::invalid_argument, fmt::format("pd: {} must be >= 0, got {}", what, v)));
  };
  check("kp", gains_.kp);
  check("kd", gains_.kd);
  for (const auto& t : targets_) {
    check("amplitude", t.amplitude_rev);
    check("frequency", t.frequency_hz);
  }
}

void PdController::start(const ControlInput& in) noexcept {
  t0_ = in.now;
  for (std::size_t b = 0; b < in.boards.size() && b * 2 < start_.size(); ++b) {
    start_[b * 2] = in.boards[b].position.value.motor1;
    start_[b * 2 + 1] = in.boards[b].position.value.motor2;
  }
}

void PdController::update(const ControlInput& in, std::span<MotorPair> currents) noexcept {
  const double t = std::chrono::duration<double>(in.now - t0_).count();
  const bool settled = in.now - t0_ >= settle_;
  for (std::size_t b = 0; b < in.boards.size() && b * 2 < start_.size(); ++b) {
    const auto& m = in.boards[b];
    const double pos[2] = {m.position.value.motor1, m.position.value.motor2};
    const double vel[2] = {krpm_to_rev_per_s(m.velocity.value.motor1), krpm_to_rev_per_s(m.velocity.value.motor2)};
    double out[2] = {0, 0};
    for (std::size_t k = 0; k < 2; ++k) {
      const auto& tg = targets_[k];
      if (!tg.enabled) continue;
      const double w = 2.0 * std::numbers::pi * tg.frequency_hz;
      const double target = start_[b * 2 + k] + tg.offset_rev + tg.amplitude_rev * std::sin(w * t);
      const double target_v = tg.amplitude_rev * w * std::cos(w * t);
      const double err = target - pos[k];
      out[k] = gains_.kp * err + gains_.kd * (target_v - vel[k]);
      if (settled) {
        auto& s = stats_[b * 2 + k];
        s.max_abs_error_rev = std::max(s.max_abs_error_rev, std::abs(err));
        s.sum_sq += err * err;
        ++s.samples;
      }
    }
    currents[b] = {out[0], out[1]};
  }
}

}  // namespace axon::blmc::host
