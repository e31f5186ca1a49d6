// Simulated time and the two arms of a positioner.
//
// A simulated positioner never reads a clock: every call that can change its state takes the
// simulated time "now" (nanoseconds since the simulation started). Unit tests pass times by hand;
// the Simulator derives them from the real clock times a scale factor.
#pragma once

#include "axon/fps/protocol/units.hpp"

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string_view>

namespace axon::fps::sim {

using SimDuration = std::chrono::nanoseconds;
// A point in simulated time: the duration since the simulation started.
using SimTime = std::chrono::nanoseconds;

// One wire time step (0.5 ms).
inline constexpr SimDuration kWireTick = std::chrono::microseconds(500);

// Seconds as a duration, rounded to the nanosecond; saturates instead of overflowing, and maps
// negative or non-finite input to 0.
SimDuration seconds(double s) noexcept;
constexpr double to_seconds(SimDuration d) noexcept { return static_cast<double>(d.count()) * 1e-9; }

// A duration as the wire's 0.5 ms steps, rounded up (an ETA never promises too early); saturates at
// the largest uint32.
protocol::Time to_wire_time(SimDuration d) noexcept;
constexpr SimDuration from_wire_time(protocol::Time t) noexcept { return kWireTick * t.ticks(); }

enum class Arm : std::uint8_t { alpha = 0, beta = 1 };
inline constexpr std::array<Arm, 2> kArms{Arm::alpha, Arm::beta};
constexpr std::size_t index(Arm a) noexcept { return static_cast<std::size_t>(a); }
constexpr std::string_view arm_name(Arm a) noexcept { return a == Arm::alpha ? "alpha" : "beta"; }

// One value per arm, indexed by Arm.
template <class T>
struct PerArm {
  std::array<T, 2> v{};

  constexpr T& operator[](Arm a) noexcept { return v[index(a)]; }
  constexpr const T& operator[](Arm a) const noexcept { return v[index(a)]; }
  friend constexpr bool operator==(const PerArm&, const PerArm&) = default;
};

}  // namespace axon::fps::sim
