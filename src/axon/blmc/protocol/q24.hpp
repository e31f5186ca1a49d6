// Q24 fixed point, the number format of every motor quantity on the blmc wire: a signed 32-bit
// integer whose value is raw / 2^24. It covers -128 up to just under +128 in steps of 2^-24.
//
// to_q24 rounds to the nearest step (halves away from zero). A value that is not finite or falls
// outside the representable range after rounding is ProtocolErrc::value_out_of_range; nothing is
// ever wrapped or saturated. from_q24 is exact (every int32 / 2^24 is a double).
#pragma once

#include "axon/core/error.hpp"

#include <cstdint>

namespace axon::blmc::protocol {

inline constexpr double kQ24Scale = 16777216.0;  // 2^24
inline constexpr double kQ24Min = -128.0;
inline constexpr double kQ24Max = 2147483647.0 / kQ24Scale;  // 128 - 2^-24

Result<std::int32_t> to_q24(double value);
constexpr double from_q24(std::int32_t raw) noexcept { return static_cast<double>(raw) / kQ24Scale; }

}  // namespace axon::blmc::protocol
