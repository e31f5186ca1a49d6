#include "axon/fps/protocol/firmware_image.hpp"

#include "axon/fps/protocol/error.hpp"

#include <fmt/format.h>
#include <zlib.h>

#include <algorithm>
#include <limits>

namespace axon::fps::protocol {

std::uint32_t firmware_crc32(std::span<const std::uint8_t> image) noexcept {
  uLong crc = crc32(0L, Z_NULL, 0);
  // zlib takes uInt lengths: feed very large buffers in pieces.
  constexpr std::size_t kPiece = std::numeric_limits<uInt>::max();
  while (!image.empty()) {
    const auto n = std::min(image.size(), kPiece);
    crc = crc32(crc, image.data(), static_cast<uInt>(n));
    image = image.subspan(n);
  }
  return static_cast<std::uint32_t>(crc);
}

Result<FirmwareImage> FirmwareImage::make(std::span<const std::uint8_t> image) {
  if (image.empty() || image.size() > std::numeric_limits<std::uint32_t>::max()) {
    return Error(ProtocolErrc::value_out_of_range,
                 fmt::format("firmware image of {} bytes (must be 1..2^32-1)", image.size()));
  }
  FirmwareImage f;
  f.bytes_ = image;
  f.header_ = FirmwareUpgradeHeader{static_cast<std::uint32_t>(image.size()), firmware_crc32(image)};
  return f;
}

FirmwareChunk FirmwareImage::chunk(std::size_t i) const noexcept {
  const auto start = std::min(i * kChunkSize, bytes_.size());
  const auto n = std::min(kChunkSize, bytes_.size() - start);
  FirmwareChunk c;
  for (auto b : bytes_.subspan(start, n)) c.data.put_u8(b);
  return c;
}

}  // namespace axon::fps::protocol
