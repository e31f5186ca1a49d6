#include "fps/protocol/bootloader_status.hpp"

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
    if (i.name.size() != name.size()) continue;
    bool same = true;
    for (std::size_t k = 0; k < name.size() && same; ++k) {
      same = std::toupper(static_cast<unsigned char>(name[k])) == static_cast<unsigned char>(i.name[k]);
    }
    if (same) return i.bit;
  }
  return std::nullopt;
}

std::vector<std::string> BootloaderStatus::names() const {
  std::vector<std::string> out;
  for (unsigned bit = 0; bit < 32; ++bit) {
    if ((raw_ & (std::uint32_t{1} << bit)) == 0) continue;
    const auto b = static_cast<BootloaderBit>(bit);
    if ((kKnownMask & mask(b)) != 0) {
      out.emplace_back(bootloader_bit_name(b));
    } else {
      out.push_back(fmt::format("BIT_{}", bit));
    }
  }
  return out;
}

std::string BootloaderStatus::to_string() const { return fmt::format("{}", fmt::join(names(), "|")); }

Payload BootloaderStatus::encode() const { return Payload().put_u32(raw_); }

Result<BootloaderStatus> BootloaderStatus::decode(std::span<const std::uint8_t> bytes) {
  AXON_TRY(expect_size(bytes, kWireSize, "bootloader status word"));
  return BootloaderStatus(read_u32(bytes, 0));
}

}  // namespace axon::fps::protocol
