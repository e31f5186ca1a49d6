#include "axon/c4g/protocol/axis_map.hpp"

#include "axon/c4g/protocol/error.hpp"

#include <fmt/format.h>

namespace axon::c4g::protocol {

Result<AxisMap> AxisMap::from_init(const InitPacket& init) {
  AxisMap m;
  for (std::size_t arm = 0; arm < kMaxArms; ++arm) {
    std::array<bool, kAxesPerArm> seen{};
    for (std::size_t slot = 0; slot < kAxesPerArm; ++slot) {
      const std::int32_t v = init.open_axis_list[arm][slot];
      if (v <= 0) continue;  // empty slot
      if (v > static_cast<std::int32_t>(kAxesPerArm))
        return Error(ProtocolErrc::bad_axis_map,
                     fmt::format("arm{}OpenAx[{}] = {}: logical axes are 1..10", arm + 1, slot, v));
      const auto axis = static_cast<std::size_t>(v);
      if (seen[axis - 1])
        return Error(ProtocolErrc::bad_axis_map, fmt::format("arm {} lists logical axis {} twice", arm + 1, axis));
      seen[axis - 1] = true;
      if (m.count_ == kMaxAxes)
        return Error(ProtocolErrc::bad_axis_map, fmt::format("more than {} open axes listed", kMaxAxes));
      m.refs_[m.count_] = AxisRef{static_cast<std::uint8_t>(arm + 1), static_cast<std::uint8_t>(axis)};
      m.startup_modes_[m.count_] = init.modes[arm][axis - 1];
      ++m.count_;
    }
  }
  if (m.count_ != static_cast<std::size_t>(init.open_axes))
    return Error(ProtocolErrc::bad_axis_map,
                 fmt::format("the open-axis lists name {} axes, nAxOpen says {}", m.count_, init.open_axes));
  return m;
}

AxisRef AxisMap::logical(std::size_t i) const noexcept { return i < count_ ? refs_[i] : AxisRef{}; }

std::optional<std::size_t> AxisMap::open_index(std::size_t arm, std::size_t axis) const noexcept {
  for (std::size_t i = 0; i < count_; ++i)
    if (refs_[i].arm == arm && refs_[i].axis == axis) return i;
  return std::nullopt;
}

std::size_t AxisMap::arm_count(std::size_t arm) const noexcept {
  std::size_t n = 0;
  for (std::size_t i = 0; i < count_; ++i) n += refs_[i].arm == arm ? 1 : 0;
  return n;
}

std::size_t AxisMap::arm_first(std::size_t arm) const noexcept {
  for (std::size_t i = 0; i < count_; ++i)
    if (refs_[i].arm == arm) return i;
  return count_;
}

std::int32_t AxisMap::startup_mode(std::size_t i) const noexcept { return i < count_ ? startup_modes_[i] : 0; }

std::array<float, kMaxAxes> AxisMap::per_open_axis(const ArmFloats& table) const noexcept {
  std::array<float, kMaxAxes> out{};
  for (std::size_t i = 0; i < count_; ++i) out[i] = table[refs_[i].arm - 1u][refs_[i].axis - 1u];
  return out;
}

}  // namespace axon::c4g::protocol
