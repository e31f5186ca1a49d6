// A firmware image prepared for upload to the bootloader: START_FIRMWARE_UPGRADE announces its size
// and zlib CRC-32, then FIRMWARE_DATA frames carry it 8 bytes at a time in order (the last frame
// 1..8 bytes). The bootloader checks the CRC once everything has arrived.
#pragma once

#include "axon/core/error.hpp"
#include "axon/fps/protocol/payloads.hpp"

#include <cstddef>
#include <cstdint>
#include <span>

namespace axon::fps::protocol {

// zlib's crc32 over the whole buffer (crc32 of nothing is 0).
std::uint32_t firmware_crc32(std::span<const std::uint8_t> image) noexcept;

class FirmwareImage {
 public:
  static constexpr std::size_t kChunkSize = 8;

  // The image must be non-empty and smaller than 4 GiB (the size field is 32 bits). The bytes are
  // not copied: they must outlive this object.
  static Result<FirmwareImage> make(std::span<const std::uint8_t> image);

  [[nodiscard]] const FirmwareUpgradeHeader& header() const noexcept { return header_; }
  [[nodiscard]] std::size_t chunk_count() const noexcept { return (bytes_.size() + kChunkSize - 1) / kChunkSize; }
  // Chunk i (0-based), i < chunk_count().
  [[nodiscard]] FirmwareChunk chunk(std::size_t i) const noexcept;

 private:
  std::span<const std::uint8_t> bytes_;
  FirmwareUpgradeHeader header_;
};

}  // namespace axon::fps::protocol
