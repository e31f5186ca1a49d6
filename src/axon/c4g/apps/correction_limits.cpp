#include "axon/c4g/apps/correction_limits.hpp"

#include "axon/c4g/protocol/packet.hpp"

#include <fmt/format.h>

#include <cmath>

namespace axon::c4g::apps {
namespace {

Result<void> validate_list(const std::vector<double>& v, const char* what) {
  if (v.empty() || v.size() > protocol::kAxesPerArm)
    return Error(CoreErrc::invalid_argument,
                 fmt::format("correct: {} needs 1 to {} values, got {}", what, protocol::kAxesPerArm, v.size()));
  for (std::size_t j = 0; j < v.size(); ++j)
    if (!(v[j] > 0) || !std::isfinite(v[j]))
      return Error(CoreErrc::invalid_argument,
                   fmt::format("correct: {} of axis {} must be > 0 and finite, got {} deg", what, j + 1, v[j] * kRadToDeg));
  return ok();
}

}  // namespace

Result<void> validate(const CorrectionLimits& limits) {
  AXON_TRY(validate_list(limits.max_abs_rad, "the correction limit"));
  return validate_list(limits.max_step_rad, "the correction limit per cycle");
}

Result<void> check_sine(std::string_view app, const std::vector<double>& a, const std::vector<double>& f,
                        const CorrectionLimits& limits) {
  for (std::size_t j = 0; j < a.size() && j < protocol::kAxesPerArm; ++j) {
    // One amplitude applies to every axis: it must fit each axis's limit.
    const std::size_t first = a.size() == 1 ? 0 : j, last = a.size() == 1 ? protocol::kAxesPerArm - 1 : j;
    for (std::size_t axis = first; axis <= last; ++axis)
      if (!(std::fabs(a[j]) <= limits.max_abs(axis)))
        return Error(CoreErrc::invalid_argument,
                     fmt::format("{}: the sine amplitude {:g} deg on axis {} exceeds the correction limit {:g} deg "
                                 "(--max-correction)", app, a[j] * kRadToDeg, axis + 1, limits.max_abs(axis) * kRadToDeg));
  }
  for (double v : f)
    if (!(v >= 0) || !std::isfinite(v))
      return Error(CoreErrc::invalid_argument, fmt::format("{}: a sine frequency must be >= 0 and finite, got {}", app, v));
  return ok();
}

double fade_per_cycle(double period_s, double ramp_s) noexcept { return ramp_s > 0 ? std::min(1.0, period_s / ramp_s) : 1.0; }

double sine_step_bound(double amplitude, double frequency, double period_s, double ramp_s) noexcept {
  const double a = std::fabs(amplitude);
  return 2.0 * std::numbers::pi * std::fabs(frequency) * a * period_s + a * fade_per_cycle(period_s, ramp_s);
}

}  // namespace axon::c4g::apps
