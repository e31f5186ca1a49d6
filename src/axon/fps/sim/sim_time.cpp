#include "axon/fps/sim/sim_time.hpp"

#include <cmath>
#include <limits>

namespace axon::fps::sim {

SimDuration seconds(double s) noexcept {
  if (!std::isfinite(s) || s <= 0) return SimDuration::zero();
  const double ns = std::round(s * 1e9);
  if (ns >= static_cast<double>(std::numeric_limits<std::int64_t>::max())) return SimDuration::max();
  return SimDuration(static_cast<std::int64_t>(ns));
}

protocol::Time to_wire_time(SimDuration d) noexcept {
  if (d <= SimDuration::zero()) return protocol::Time::from_ticks(0);
  const auto ticks = (d.count() + kWireTick.count() - 1) / kWireTick.count();
  if (ticks >= static_cast<std::int64_t>(std::numeric_limits<std::uint32_t>::max())) {
    return protocol::Time::from_ticks(std::numeric_limits<std::uint32_t>::max());
  }
  return protocol::Time::from_ticks(static_cast<std::uint32_t>(ticks));
}

}  // namespace axon::fps::sim
