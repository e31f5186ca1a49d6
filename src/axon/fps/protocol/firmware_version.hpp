// Firmware version "XX.YY.ZZ" (three decimal numbers 0..99 in practice, one byte each).
//
// On the wire it is the little-endian uint32 0x00XXYYZZ, that is the bytes ZZ YY XX 00; hosts in
// service read the first three bytes backwards to print "XX.YY.ZZ". The interface document's prose
// lists the bytes the other way round (00 XX YY ZZ); VersionByteOrder::document reads and writes that
// order for firmware that really does it, the field order is the default. A non-zero byte where the
// 00 belongs is rejected in either order.
//
// YY == 80 marks the bootloader (e.g. 03.80.01); the main application in service is 04.01.xx.
#pragma once

#include "axon/core/error.hpp"
#include "axon/fps/protocol/payload.hpp"

#include <compare>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

namespace axon::fps::protocol {

enum class VersionByteOrder : std::uint8_t {
  field,     // ZZ YY XX 00 (little-endian 0x00XXYYZZ), as devices in service send it
  document,  // 00 XX YY ZZ, as the interface document's prose describes it
};

struct FirmwareVersion {
  static constexpr std::uint8_t kBootloaderMinor = 80;

  std::uint8_t major = 0;  // XX
  std::uint8_t minor = 0;  // YY
  std::uint8_t patch = 0;  // ZZ

  [[nodiscard]] constexpr bool is_bootloader() const noexcept { return minor == kBootloaderMinor; }
  // The 64-bit status word of status.hpp applies from 04.01.00 on.
  [[nodiscard]] constexpr bool has_64bit_status() const noexcept { return !is_bootloader() && *this >= FirmwareVersion{4, 1, 0}; }
  // Hosts in service send the precise-move switches (128..131) only from 04.01.17 on.
  [[nodiscard]] constexpr bool has_precise_move_switches() const noexcept {
    return !is_bootloader() && *this >= FirmwareVersion{4, 1, 17};
  }

  // 0x00XXYYZZ
  [[nodiscard]] constexpr std::uint32_t to_u32() const noexcept {
    return (std::uint32_t{major} << 16) | (std::uint32_t{minor} << 8) | patch;
  }
  // The high byte must be zero.
  static Result<FirmwareVersion> from_u32(std::uint32_t value);

  // The 4-byte GET_FIRMWARE_VERSION reply.
  [[nodiscard]] Payload encode(VersionByteOrder order = VersionByteOrder::field) const;
  static Result<FirmwareVersion> decode(std::span<const std::uint8_t> bytes,
                                        VersionByteOrder order = VersionByteOrder::field);

  // "XX.YY.ZZ", each part at least two digits ("04.01.13").
  [[nodiscard]] std::string to_string() const;
  // Accepts "4.1.13" or "04.01.13"; each part 0..255.
  static Result<FirmwareVersion> parse(std::string_view text);

  friend constexpr auto operator<=>(const FirmwareVersion&, const FirmwareVersion&) noexcept = default;
};

}  // namespace axon::fps::protocol
