// The physics of one motor: a rigid rotor (plus an optional load) driven by the q-axis current,
// slowed by viscous and Coulomb friction, integrated with semi-implicit Euler at a fixed substep.
//
//   J w' = kt i - b w - tau_c sign(w) - k (theta - theta0),   J = rotor + load inertia
//
// The applied current is the command clamped to the current limit and, with a supply voltage set,
// to what the back-EMF leaves: (V - kt w) / R in the direction of rotation. A standing rotor stays
// put while the other torques do not exceed the Coulomb friction (static friction equals Coulomb
// friction here), and a rotor that friction brings to rest stops instead of reversing.
//
// The encoder reads the shaft in revolutions, quantised to its counts, and rolls over at +-100
// revolutions like the firmware's position (a reading of 100 becomes -100). Its index mark passes
// once per revolution at `index_offset_rev` within the turn; every pass is recorded with the
// reading at the mark.
#pragma once

#include "axon/blmc/protocol/frames.hpp"
#include "axon/blmc/sim/motor_config.hpp"

#include <cstdint>
#include <vector>

namespace axon::blmc::sim {

using protocol::kPositionRolloverRev;  // readings lie in [-100, 100)
// The physics step.
inline constexpr double kSubstepS = 1.0e-4;

class MotorModel {
 public:
  // `config` must be valid (MotorConfig::validate()).
  explicit MotorModel(MotorConfig config);

  // Drives the motor with `current_cmd_a` for `duration_s` (in substeps of kSubstepS; a remainder
  // shorter than a substep is integrated as one shorter step).
  void advance(double current_cmd_a, double duration_s) noexcept;
  // Holds the rotor still (alignment: the driver locks it with d-axis current) for `duration_s`.
  void hold(double duration_s) noexcept;

  // The encoder reading [rev], within [-100, 100).
  [[nodiscard]] double position_rev() const noexcept;
  // Shaft velocity [rev/s] and as the wire carries it [krpm].
  [[nodiscard]] double velocity_rev_s() const noexcept { return velocity_rev_s_; }
  [[nodiscard]] double velocity_krpm() const noexcept { return velocity_rev_s_ * 60.0 / 1000.0; }
  // The current the driver applied in the last substep [A] (0 while held).
  [[nodiscard]] double current_a() const noexcept { return current_a_; }
  // The unwrapped shaft position [rev] (no rollover, no quantisation).
  [[nodiscard]] double continuous_position_rev() const noexcept { return position_rev_; }
  // How often the reading wrapped around (either direction) since construction.
  [[nodiscard]] std::uint64_t rollovers() const noexcept { return rollovers_; }

  // Encoder readings at the index marks passed since clear_index_events() (oldest first; at most
  // 1024 are kept, index_count() counts them all).
  [[nodiscard]] const std::vector<double>& index_events() const noexcept { return index_events_; }
  void clear_index_events() noexcept { index_events_.clear(); }
  [[nodiscard]] std::uint64_t index_count() const noexcept { return index_count_; }

  // Places the shaft (for tests and power-up states); clears pending index events.
  void set_state(double position_rev, double velocity_rev_s) noexcept;
  [[nodiscard]] const MotorConfig& config() const noexcept { return config_; }

 private:
  void substep(double current_cmd_a, double dt) noexcept;
  [[nodiscard]] double applied_current(double cmd) const noexcept;
  [[nodiscard]] double wrapped(double continuous) const noexcept;
  void record_crossings(double before, double after);

  MotorConfig config_;
  double inertia_;
  double position_rev_ = 0;  // continuous
  double velocity_rev_s_ = 0;
  double current_a_ = 0;
  std::uint64_t rollovers_ = 0;
  std::uint64_t index_count_ = 0;
  std::vector<double> index_events_;
};

}  // namespace axon::blmc::sim
