#include "axon/c4g/protocol/safety.hpp"

namespace axon::c4g::protocol {

std::optional<std::size_t> first_following_error(const Packet& from_controller,
                                                 std::span<const float> thresholds) noexcept {
  const auto axes = from_controller.open_axes();
  for (std::size_t i = 0; i < axes.size() && i < thresholds.size(); ++i)
    if (following_error_exceeded(axes[i].d1, axes[i].d3, thresholds[i])) return i;
  return std::nullopt;
}

std::size_t saturate_currents(Packet& reply, std::span<const float> limits) noexcept {
  std::size_t n = 0;
  auto axes = reply.open_axes();
  for (std::size_t i = 0; i < axes.size() && i < limits.size(); ++i) {
    const float c = saturate_current(axes[i].d5, limits[i]);
    if (c != axes[i].d5) {
      axes[i].d5 = c;
      ++n;
    }
  }
  return n;
}

}  // namespace axon::c4g::protocol
