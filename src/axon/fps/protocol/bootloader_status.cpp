#include "axon/fps/protocol/bootloader_status.hpp"

#include "axon/fps/protocol/names.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cctype>

namespace axon::fps::protocol {

std::string_view bootloader_bit_name(BootloaderBit b) noexcept {
  for (const auto& i : kBootloaderBits) {
    if (i.bit == b) return i.name;
  }
  return "UNKNOWN";
}

std::optional<BootloaderBit> bootloader_bit_from_name(std::string_view name) noexcept {
  for (const auto& i : kBootloaderBits) {
    if (iequals(i.name, name)) return i.bit;
  }
  return std::nullopt;
}

std::vector<std::string> BootloaderStatus::names() const {
  return set_bit_names<BootloaderBit>(raw_, kKnownMask, bootloader_bit_name);
}

std::string BootloaderStatus::to_string() const { return fmt::format("{}", fmt::join(names(), "|")); }

Payload BootloaderStatus::encode() const { return Payload().put_u32(raw_); }

Result<BootloaderStatus> BootloaderStatus::decode(std::span<const std::uint8_t> bytes) {
  AXON_TRY(expect_size(bytes, kWireSize, "bootloader status word"));
  return BootloaderStatus(read_u32(bytes, 0));
}

}  // namespace axon::fps::protocol
