#include "axon/fps/protocol/firmware_version.hpp"

#include "axon/fps/protocol/error.hpp"

#include <fmt/format.h>

#include <charconv>

namespace axon::fps::protocol {

Result<FirmwareVersion> FirmwareVersion::from_u32(std::uint32_t value) {
  if ((value >> 24) != 0) {
    return Error(ProtocolErrc::value_out_of_range,
                 fmt::format("firmware version 0x{:08X}: the top byte must be zero", value));
  }
  return FirmwareVersion{static_cast<std::uint8_t>(value >> 16), static_cast<std::uint8_t>(value >> 8),
                         static_cast<std::uint8_t>(value)};
}

Payload FirmwareVersion::encode(VersionByteOrder order) const {
  Payload p;
  if (order == VersionByteOrder::field) return p.put_u32(to_u32());
  return p.put_u8(0).put_u8(major).put_u8(minor).put_u8(patch);
}

Result<FirmwareVersion> FirmwareVersion::decode(std::span<const std::uint8_t> bytes, VersionByteOrder order) {
  AXON_TRY(expect_size(bytes, 4, "firmware version"));
  if (order == VersionByteOrder::field) return from_u32(read_u32(bytes, 0));
  // Document order: 00 XX YY ZZ.
  const std::uint32_t value = (std::uint32_t{bytes[0]} << 24) | (std::uint32_t{bytes[1]} << 16) |
                              (std::uint32_t{bytes[2]} << 8) | bytes[3];
  return from_u32(value);
}

std::string FirmwareVersion::to_string() const { return fmt::format("{:02d}.{:02d}.{:02d}", major, minor, patch); }

Result<FirmwareVersion> FirmwareVersion::parse(std::string_view text) {
  std::uint8_t parts[3]{};
  const char* p = text.data();
  const char* end = text.data() + text.size();
  for (int i = 0; i < 3; ++i) {
    unsigned v = 0;
    auto [next, ec] = std::from_chars(p, end, v);
    if (ec != std::errc() || next == p || v > 255) {
      return Error(ProtocolErrc::value_out_of_range, fmt::format("firmware version '{}': expected XX.YY.ZZ", text));
    }
    parts[i] = static_cast<std::uint8_t>(v);
    p = next;
    if (i < 2) {
      if (p == end || *p != '.') {
        return Error(ProtocolErrc::value_out_of_range, fmt::format("firmware version '{}': expected XX.YY.ZZ", text));
      }
      ++p;
    }
  }
  if (p != end) {
    return Error(ProtocolErrc::value_out_of_range, fmt::format("firmware version '{}': expected XX.YY.ZZ", text));
  }
  return FirmwareVersion{parts[0], parts[1], parts[2]};
}

}  // namespace axon::fps::protocol
