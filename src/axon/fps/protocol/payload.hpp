// Payload: the 0..8 data bytes of one fps frame, plus the little-endian field readers and writers
// every codec uses. All multi-byte numbers on the fps bus are little-endian.
#pragma once

#include "axon/core/error.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace axon::fps::protocol {

class Payload {
 public:
  static constexpr std::size_t kMaxSize = 8;

  constexpr Payload() = default;
  // Copies up to 8 bytes; more is an error (ProtocolErrc::wrong_length).
  static Result<Payload> from(std::span<const std::uint8_t> bytes);

  [[nodiscard]] constexpr std::size_t size() const noexcept { return size_; }
  [[nodiscard]] constexpr bool empty() const noexcept { return size_ == 0; }
  [[nodiscard]] constexpr const std::uint8_t* data() const noexcept { return bytes_.data(); }
  [[nodiscard]] constexpr std::span<const std::uint8_t> span() const noexcept { return {bytes_.data(), size_}; }
  constexpr operator std::span<const std::uint8_t>() const noexcept { return span(); }  // NOLINT: implicit on purpose
  [[nodiscard]] constexpr std::uint8_t operator[](std::size_t i) const noexcept { return bytes_[i]; }

  // Appenders for encoders. The layouts are fixed and never exceed 8 bytes; appending to a full
  // payload is a programming error (asserted in debug builds, ignored otherwise).
  constexpr Payload& put_u8(std::uint8_t v) noexcept {
    assert(size_ < kMaxSize);
    if (size_ < kMaxSize) bytes_[size_++] = v;
    return *this;
  }
  constexpr Payload& put_u32(std::uint32_t v) noexcept {
    for (int i = 0; i < 4; ++i) put_u8(static_cast<std::uint8_t>(v >> (8 * i)));
    return *this;
  }
  constexpr Payload& put_i32(std::int32_t v) noexcept { return put_u32(static_cast<std::uint32_t>(v)); }
  constexpr Payload& put_u64(std::uint64_t v) noexcept {
    for (int i = 0; i < 8; ++i) put_u8(static_cast<std::uint8_t>(v >> (8 * i)));
    return *this;
  }

  // Hex bytes separated by spaces, e.g. "03 00 00 00".
  [[nodiscard]] std::string to_hex() const;

  friend constexpr bool operator==(const Payload& a, const Payload& b) noexcept {
    return a.size_ == b.size_ && std::equal(a.bytes_.begin(), a.bytes_.begin() + a.size_, b.bytes_.begin());
  }

 private:
  std::array<std::uint8_t, kMaxSize> bytes_{};
  std::size_t size_ = 0;
};

// Little-endian readers; the caller has checked that offset + width <= bytes.size().
constexpr std::uint32_t read_u32(std::span<const std::uint8_t> b, std::size_t offset) noexcept {
  return static_cast<std::uint32_t>(b[offset]) | (static_cast<std::uint32_t>(b[offset + 1]) << 8) |
         (static_cast<std::uint32_t>(b[offset + 2]) << 16) | (static_cast<std::uint32_t>(b[offset + 3]) << 24);
}
constexpr std::int32_t read_i32(std::span<const std::uint8_t> b, std::size_t offset) noexcept {
  return static_cast<std::int32_t>(read_u32(b, offset));
}
constexpr std::uint64_t read_u64(std::span<const std::uint8_t> b, std::size_t offset) noexcept {
  return static_cast<std::uint64_t>(read_u32(b, offset)) | (static_cast<std::uint64_t>(read_u32(b, offset + 4)) << 32);
}

// Fails with ProtocolErrc::wrong_length unless bytes.size() == expected; `what` names the payload.
Result<void> expect_size(std::span<const std::uint8_t> bytes, std::size_t expected, std::string_view what);

}  // namespace axon::fps::protocol
