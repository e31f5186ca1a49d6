// The 32-bit status word of the bootloader (GET_STATUS while the bootloader runs).
// Undocumented set bits are kept in raw() and printed as "BIT_<n>".
#pragma once

#include "axon/core/error.hpp"
#include "axon/fps/protocol/payload.hpp"

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace axon::fps::protocol {

enum class BootloaderBit : std::uint8_t {
  bootloader_init = 0,
  bootloader_timeout = 1,
  bsettings_changed = 9,
  receiving_new_firmware = 16,
  new_firmware_received = 24,
  new_firmware_check_ok = 25,
  new_firmware_check_bad = 26,
};

struct BootloaderBitInfo {
  BootloaderBit bit;
  std::string_view name;
  std::string_view meaning;
};

constexpr std::uint32_t mask(BootloaderBit b) noexcept { return std::uint32_t{1} << static_cast<unsigned>(b); }

inline constexpr std::array<BootloaderBitInfo, 7> kBootloaderBits{{
    {BootloaderBit::bootloader_init, "BOOTLOADER_INIT", "the bootloader has started"},
    {BootloaderBit::bootloader_timeout, "BOOTLOADER_TIMEOUT", "the bootloader's wait for commands ran out"},
    {BootloaderBit::bsettings_changed, "BSETTINGS_CHANGED",
     "the bootloader's settings changed (new firmware stored or validated)"},
    {BootloaderBit::receiving_new_firmware, "RECEIVING_NEW_FIRMWARE", "a firmware image is being received"},
    {BootloaderBit::new_firmware_received, "NEW_FIRMWARE_RECEIVED", "the whole firmware image has arrived"},
    {BootloaderBit::new_firmware_check_ok, "NEW_FIRMWARE_CHECK_OK", "the received image matches its CRC-32"},
    {BootloaderBit::new_firmware_check_bad, "NEW_FIRMWARE_CHECK_BAD", "the received image failed its CRC-32 check"},
}};

constexpr std::uint32_t known_bootloader_mask() noexcept {
  std::uint32_t m = 0;
  for (const auto& b : kBootloaderBits) m |= mask(b.bit);
  return m;
}

std::string_view bootloader_bit_name(BootloaderBit b) noexcept;
std::optional<BootloaderBit> bootloader_bit_from_name(std::string_view name) noexcept;

class BootloaderStatus {
 public:
  static constexpr std::size_t kWireSize = 4;
  static constexpr std::uint32_t kKnownMask = known_bootloader_mask();

  constexpr BootloaderStatus() = default;
  constexpr explicit BootloaderStatus(std::uint32_t raw) noexcept : raw_(raw) {}

  [[nodiscard]] constexpr std::uint32_t raw() const noexcept { return raw_; }
  [[nodiscard]] constexpr bool has(BootloaderBit b) const noexcept { return (raw_ & mask(b)) != 0; }
  constexpr BootloaderStatus& set(BootloaderBit b, bool on = true) noexcept {
    raw_ = on ? (raw_ | mask(b)) : (raw_ & ~mask(b));
    return *this;
  }
  [[nodiscard]] constexpr std::uint32_t unknown_bits() const noexcept { return raw_ & ~kKnownMask; }

  [[nodiscard]] std::vector<std::string> names() const;
  [[nodiscard]] std::string to_string() const;

  [[nodiscard]] constexpr bool receiving() const noexcept { return has(BootloaderBit::receiving_new_firmware); }
  // The image arrived and passed its CRC check: it will become the main application.
  [[nodiscard]] constexpr bool upgrade_succeeded() const noexcept {
    return has(BootloaderBit::new_firmware_received) && has(BootloaderBit::new_firmware_check_ok);
  }
  [[nodiscard]] constexpr bool upgrade_failed() const noexcept { return has(BootloaderBit::new_firmware_check_bad); }

  // The 4-byte GET_STATUS reply of the bootloader (little-endian uint32).
  [[nodiscard]] Payload encode() const;
  static Result<BootloaderStatus> decode(std::span<const std::uint8_t> bytes);

  friend constexpr bool operator==(const BootloaderStatus&, const BootloaderStatus&) noexcept = default;

 private:
  std::uint32_t raw_ = 0;
};

}  // namespace axon::fps::protocol
