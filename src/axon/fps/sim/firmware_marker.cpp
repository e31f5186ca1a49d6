#include "axon/fps/sim/firmware_marker.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <string>

namespace axon::fps::sim {

namespace {

Result<std::vector<std::uint8_t>> with_tag(std::string_view tag, std::size_t size) {
  const std::size_t offset = 16;
  if (size < offset + tag.size() + 1) {
    return make_error(CoreErrc::invalid_argument,
                      fmt::format("firmware image of {} bytes cannot hold its tag ({} bytes needed)", size,
                                  offset + tag.size() + 1));
  }
  std::vector<std::uint8_t> image(size);
  std::uint32_t x = 0x12345678;
  for (auto& b : image) {  // xorshift filler: looks like data, never contains the tag by chance
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    b = static_cast<std::uint8_t>(x & 0x7F);  // 7-bit: keeps ':' sequences rare but harmless
  }
  std::copy(tag.begin(), tag.end(), image.begin() + static_cast<std::ptrdiff_t>(offset));
  image[offset + tag.size()] = 0;  // ends the tag: filler digits must not extend the version
  return image;
}

}  // namespace

FirmwareMarker read_firmware_marker(std::span<const std::uint8_t> image) {
  const std::string_view bytes(reinterpret_cast<const char*>(image.data()), image.size());
  std::size_t pos = 0;
  while ((pos = bytes.find(kFirmwareTag, pos)) != std::string_view::npos) {
    const std::string_view rest = bytes.substr(pos + kFirmwareTag.size());
    if (rest.starts_with(kBrickTag)) return FirmwareMarker{false, std::nullopt};
    // "XX.YY.ZZ": digits and dots, at most 11 characters.
    std::size_t n = 0;
    while (n < rest.size() && n < 11 && (rest[n] == '.' || (rest[n] >= '0' && rest[n] <= '9'))) ++n;
    if (auto v = protocol::FirmwareVersion::parse(rest.substr(0, n)); v && !v.value().is_bootloader()) {
      return FirmwareMarker{true, v.value()};
    }
    pos += kFirmwareTag.size();
  }
  return FirmwareMarker{};
}

Result<std::vector<std::uint8_t>> make_firmware_image(protocol::FirmwareVersion version, std::size_t size) {
  return with_tag(std::string(kFirmwareTag) + version.to_string(), size);
}

Result<std::vector<std::uint8_t>> make_bricked_firmware_image(std::size_t size) {
  return with_tag(std::string(kFirmwareTag) + std::string(kBrickTag), size);
}

}  // namespace axon::fps::sim
