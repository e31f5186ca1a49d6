#include "axon/blmc/protocol/q24.hpp"

#include "axon/blmc/protocol/error.hpp"

#include <fmt/format.h>

#include <cmath>

namespace axon::blmc::protocol {

Result<std::int32_t> to_q24(double value) {
  if (!std::isfinite(value)) {
    return Error(ProtocolErrc::value_out_of_range, fmt::format("Q24 value {} is not finite", value));
  }
  // Scaling by a power of two is exact, so the only rounding is std::round's.
  const double scaled = std::round(value * kQ24Scale);
  if (scaled < -2147483648.0 || scaled > 2147483647.0) {
    return Error(ProtocolErrc::value_out_of_range,
                 fmt::format("Q24 value {} outside [-128, 128 - 2^-24]", value));
  }
  return static_cast<std::int32_t>(scaled);
}

}  // namespace axon::blmc::protocol
