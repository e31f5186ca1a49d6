// A host-side PD position controller per motor, holding a position or tracking a sine around the
// position each motor had when the loop started. Used by `axon blmc pd`, by tests against the
// simulator and by the benchmark.
//
//   target(t) = start + amplitude * sin(2 pi f t)       [motor rev]
//   current   = kp * (target - position) + kd * (target' - velocity)   [A]
//
// with velocity in rev/s (converted from the board's krpm). Tracking error statistics (after a
// settle time) are kept for the caller to read once the loop stopped.
#pragma once

#include "axon/blmc/host/control_loop.hpp"

#include <array>
#include <vector>

namespace axon::blmc::host {

struct PdGains {
  double kp = 5.0;   // A per motor revolution
  double kd = 0.05;  // A per (rev/s)
};

struct PdTarget {
  bool enabled = true;       // false: the motor gets zero current
  double amplitude_rev = 0;  // 0 holds the start position
  double frequency_hz = 0;
  double offset_rev = 0;     // added to the start position
};

struct TrackingStats {
  double max_abs_error_rev = 0;
  double sum_sq = 0;
  std::uint64_t samples = 0;
  [[nodiscard]] double rms_rev() const noexcept;
};

class PdController final : public Controller {
 public:
  // One gains/target pair per motor, the same for every board. Throws axon::Exception
  // (HostErrc::invalid_argument, in words) for gains, amplitudes or frequencies that are negative
  // or not finite (a negative gain pushes the motor away from its target).
  PdController(std::size_t boards, PdGains gains, std::array<PdTarget, 2> targets,
               core::Duration settle = std::chrono::milliseconds(500));

  void start(const ControlInput& in) noexcept override;
  void update(const ControlInput& in, std::span<MotorPair> currents) noexcept override;

  // Read after the loop stopped.
  [[nodiscard]] const TrackingStats& tracking(std::size_t board, int motor) const noexcept {
    return stats_[board * 2 + static_cast<std::size_t>(motor)];
  }
  [[nodiscard]] double start_position(std::size_t board, int motor) const noexcept {
    return start_[board * 2 + static_cast<std::size_t>(motor)];
  }

 private:
  PdGains gains_;
  std::array<PdTarget, 2> targets_;
  core::Duration settle_;
  core::TimePoint t0_{};
  std::vector<double> start_;
  std::vector<TrackingStats> stats_;
};

}  // namespace axon::blmc::host
