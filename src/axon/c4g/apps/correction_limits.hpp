// Bounds on a position offset the PC adds on top of the robot's own motion: a mode-7 correction
// (correct.hpp) or the sine a PC loop tracks around its hold point (pid.hpp). Link side, per axis
// of the arm: the offset's size (max_abs) and its change from one cycle to the next (max_step).
#pragma once

#include "axon/core/error.hpp"

#include <algorithm>
#include <numbers>
#include <string_view>
#include <vector>

namespace axon::c4g::apps {

// The defaults: 5 degrees at most, 0.1 degree per cycle at most (50 deg/s at 2 ms).
inline constexpr double kDefaultMaxCorrectionDeg = 5.0;
inline constexpr double kDefaultMaxCorrectionStepDeg = 0.1;

// One value applies to every axis; with several, the last one also applies to the axes after it.
struct CorrectionLimits {
  std::vector<double> max_abs_rad{kDefaultMaxCorrectionDeg * std::numbers::pi / 180.0};
  std::vector<double> max_step_rad{kDefaultMaxCorrectionStepDeg * std::numbers::pi / 180.0};
  [[nodiscard]] double max_abs(std::size_t axis) const noexcept { return pick(max_abs_rad, axis); }
  [[nodiscard]] double max_step(std::size_t axis) const noexcept { return pick(max_step_rad, axis); }

 private:
  static double pick(const std::vector<double>& v, std::size_t axis) noexcept {
    return v.empty() ? 0.0 : v[std::min(axis, v.size() - 1)];
  }
};

// Every limit finite and > 0, 1..kAxesPerArm values each; invalid_argument in words otherwise.
Result<void> validate(const CorrectionLimits& limits);

// A sine's amplitudes (one value: every axis) within max_abs and finite, its frequencies finite
// and >= 0; invalid_argument naming `app`, the axis and the values in degrees otherwise.
Result<void> check_sine(std::string_view app, const std::vector<double>& amplitude_rad,
                        const std::vector<double>& frequency_hz, const CorrectionLimits& limits);

// The largest change in one cycle of env(t) A sin(2 pi f t), the envelope fading over ramp_s (0:
// at once): the sine's own step plus the fade's.
double sine_step_bound(double amplitude, double frequency, double period_s, double ramp_s) noexcept;
// The envelope's change per cycle while fading over ramp_s (1 when ramp_s is 0).
double fade_per_cycle(double period_s, double ramp_s) noexcept;

inline constexpr double kRadToDeg = 180.0 / std::numbers::pi;

}  // namespace axon::c4g::apps
