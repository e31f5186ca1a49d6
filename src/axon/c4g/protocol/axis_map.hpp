// Axis indexes: the packet carries only the open axes, in "open" order; the operator names an axis by
// arm (1..4) and logical axis (1..10). The initialization packet's open-axis lists (armNOpenAx) give
// the mapping: arm 1's list first, then arm 2's, ...; within a list, the entries in order. An entry
// 1..10 is a logical axis number (1-based, as the controller's printout labels them); 0 or a
// negative value is an empty slot (the printout's "X").
//
// Open indexes are 0-based packet positions; arms and logical axes are 1-based everywhere here.
#pragma once

#include "axon/c4g/protocol/init_packet.hpp"
#include "axon/core/error.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>

namespace axon::c4g::protocol {

struct AxisRef {
  std::uint8_t arm = 0;   // 1..4 (0: none)
  std::uint8_t axis = 0;  // logical axis 1..10 (0: none)
  friend bool operator==(const AxisRef&, const AxisRef&) = default;
};

class AxisMap {
 public:
  // Checks: entries above 10, a logical axis listed twice in one arm, or a total that differs from
  // nAxOpen are bad_axis_map.
  static Result<AxisMap> from_init(const InitPacket& init);

  std::size_t count() const noexcept { return count_; }
  AxisRef logical(std::size_t open_index) const noexcept;  // {0, 0} when out of range
  std::optional<std::size_t> open_index(std::size_t arm, std::size_t axis) const noexcept;
  std::size_t arm_count(std::size_t arm) const noexcept;  // open axes of the arm
  // Open index of the arm's first open axis (its axes are consecutive); count() if the arm has none.
  std::size_t arm_first(std::size_t arm) const noexcept;
  // The start-up mode (armNOpenMask) of each open axis.
  std::int32_t startup_mode(std::size_t open_index) const noexcept;
  // A per-arm table (limits, thresholds, ...) laid out in open order: element i is open axis i.
  std::array<float, kMaxAxes> per_open_axis(const ArmFloats& table) const noexcept;

 private:
  std::size_t count_ = 0;
  std::array<AxisRef, kMaxAxes> refs_{};
  std::array<std::int32_t, kMaxAxes> startup_modes_{};
};

}  // namespace axon::c4g::protocol
