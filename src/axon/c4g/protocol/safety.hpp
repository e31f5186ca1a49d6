// PC-side safety checks the manual asks for in modes where the PC closes the loops (1 and 2): the
// following error |target - actual| against its threshold, and the current contribution saturated to
// the axis's limit. Thresholds and limits come from the initialization packet, in open order
// (AxisMap::per_open_axis). A threshold of 0 or less means "not checked" (the manual's example has
// 0 for an axis without a threshold); a limit is used as its absolute value.
#pragma once

#include "axon/c4g/protocol/packet.hpp"

#include <cmath>
#include <cstddef>
#include <optional>
#include <span>

namespace axon::c4g::protocol {

inline bool following_error_exceeded(double target, double actual, double threshold) noexcept {
  return threshold > 0.0 && !(std::fabs(target - actual) <= threshold);  // NaN counts as exceeded
}

inline float saturate_current(float value, float limit) noexcept {
  const float l = std::fabs(limit);
  if (std::isnan(value)) return 0.0f;
  return value > l ? l : (value < -l ? -l : value);
}

// The first open axis whose D1 (target) and D3 (actual) differ by more than its threshold.
std::optional<std::size_t> first_following_error(const Packet& from_controller,
                                                 std::span<const float> thresholds) noexcept;
// Clamps D5 (current contribution) of every open axis of a reply; returns how many were clamped.
std::size_t saturate_currents(Packet& reply, std::span<const float> limits) noexcept;

}  // namespace axon::c4g::protocol
