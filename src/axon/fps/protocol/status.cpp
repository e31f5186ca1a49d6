#include "axon/fps/protocol/status.hpp"

#include "axon/fps/protocol/error.hpp"
#include "axon/fps/protocol/names.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cctype>

namespace axon::fps::protocol {


std::string_view status_bit_name(StatusBit b) noexcept {
  for (const auto& i : kStatusBits) {
    if (i.bit == b) return i.name;
  }
  return "UNKNOWN";
}

std::optional<StatusBit> status_bit_from_name(std::string_view name) noexcept {
  if (iequals(name, "SYSTEM_INITIALIZED")) return StatusBit::system_initialized;
  for (const auto& i : kStatusBits) {
    if (iequals(i.name, name)) return i.bit;
  }
  return std::nullopt;
}

std::vector<std::string> PositionerStatus::names() const {
  return set_bit_names<StatusBit>(raw_, kKnownMask, status_bit_name);
}

std::string PositionerStatus::to_string() const { return fmt::format("{}", fmt::join(names(), "|")); }

Payload PositionerStatus::encode() const { return Payload().put_u64(raw_); }

Result<PositionerStatus> PositionerStatus::decode(std::span<const std::uint8_t> bytes) {
  AXON_TRY(expect_size(bytes, kWireSize, "status word"));
  return PositionerStatus(read_u64(bytes, 0));
}

}  // namespace axon::fps::protocol
