// A classic CAN frame: 11-bit (standard) or 29-bit (extended) id, data or remote, 0..8 bytes.
// Frames are validated when made: an id or length that does not fit is an error, never truncated.
#pragma once

#include "axon/can/error.hpp"
#include "axon/core/clock.hpp"

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

namespace axon::can {

enum class IdFormat : std::uint8_t { standard, extended };

class Frame {
 public:
  static constexpr std::uint32_t kMaxStandardId = 0x7FF;
  static constexpr std::uint32_t kMaxExtendedId = 0x1FFF'FFFF;
  static constexpr std::size_t kMaxData = 8;

  Frame() = default;  // standard id 0, no data

  // Validated factories.
  static Result<Frame> data(std::uint32_t id, IdFormat fmt, std::span<const std::uint8_t> bytes);
  static Result<Frame> remote(std::uint32_t id, IdFormat fmt, std::uint8_t dlc);
  static Result<Frame> standard(std::uint32_t id, std::span<const std::uint8_t> bytes) {
    return data(id, IdFormat::standard, bytes);
  }
  static Result<Frame> extended(std::uint32_t id, std::span<const std::uint8_t> bytes) {
    return data(id, IdFormat::extended, bytes);
  }
  // Parses cansend's notation: "123#DEADBEEF", "12345678#11.22", "123#R", "123#R4".
  // Three hex digits make a standard id, eight an extended one.
  static Result<Frame> parse(std::string_view text);

  [[nodiscard]] std::uint32_t id() const noexcept { return id_; }
  [[nodiscard]] IdFormat format() const noexcept { return fmt_; }
  [[nodiscard]] bool is_extended() const noexcept { return fmt_ == IdFormat::extended; }
  [[nodiscard]] bool is_remote() const noexcept { return remote_; }
  [[nodiscard]] std::uint8_t dlc() const noexcept { return dlc_; }
  // The payload (empty for remote frames).
  [[nodiscard]] std::span<const std::uint8_t> payload() const noexcept {
    return {bytes_.data(), remote_ ? 0u : static_cast<std::size_t>(dlc_)};
  }

  // When the frame was received (or logged), wall time since the Unix epoch; 0 when unknown.
  [[nodiscard]] core::WallTime timestamp() const noexcept { return ts_; }
  void set_timestamp(core::WallTime t) noexcept { ts_ = t; }

  // cansend notation, e.g. "123#DEADBEEF" or "1FFFFFFF#R2".
  [[nodiscard]] std::string to_string() const;

  // Equality ignores the timestamp.
  friend bool operator==(const Frame& a, const Frame& b) noexcept {
    return a.id_ == b.id_ && a.fmt_ == b.fmt_ && a.remote_ == b.remote_ && a.dlc_ == b.dlc_ &&
           (a.remote_ || std::equal(a.bytes_.begin(), a.bytes_.begin() + a.dlc_, b.bytes_.begin()));
  }

 private:
  std::uint32_t id_ = 0;
  IdFormat fmt_ = IdFormat::standard;
  bool remote_ = false;
  std::uint8_t dlc_ = 0;
  std::array<std::uint8_t, kMaxData> bytes_{};
  core::WallTime ts_{0};
};

// Checks an id against its format's range.
Result<void> check_id(std::uint32_t id, IdFormat fmt);

}  // namespace axon::can
