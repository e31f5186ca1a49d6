// The frame as it appears on the wire: exact length in bits (with the stuff bits that its actual
// bit pattern and CRC-15 need), arbitration priority, and time at a given bitrate.
//
// Classic CAN frame layout, dominant = 0:
//   standard: SOF | id[10..0] | RTR | IDE=0 | r0 | DLC[3..0] | data | CRC[14..0]
//   extended: SOF | id[28..18] | SRR=1 | IDE=1 | id[17..0] | RTR | r1 | r0 | DLC | data | CRC
// followed by 13 bits that are never stuffed: CRC delimiter, ACK slot, ACK delimiter, 7-bit end of
// frame and the 3-bit intermission before the next frame may start.
#pragma once

#include "axon/can/frame.hpp"

#include <cstdint>

namespace axon::can {

inline constexpr std::uint32_t kDefaultBitrate = 1'000'000;

struct FrameBits {
  std::uint32_t unstuffed = 0;  // SOF through CRC, before stuffing
  std::uint32_t stuff = 0;      // stuff bits inserted in that region
  std::uint32_t total = 0;      // everything, including the 13 fixed bits and intermission
};

// CRC-15/CAN (polynomial 0x4599, initial value 0) over `nbits` bits, most significant first.
std::uint16_t crc15(const std::uint8_t* bits, std::size_t nbits) noexcept;

// Exact bit count of the frame on the wire.
FrameBits frame_bits(const Frame& f) noexcept;

// Bits of the longest possible frame of this shape (worst-case stuffing): for budgeting.
std::uint32_t worst_case_bits(IdFormat fmt, std::uint8_t dlc) noexcept;

// Time the frame occupies the bus at `bitrate` bits per second, intermission included.
inline core::Duration frame_time(const Frame& f, std::uint32_t bitrate = kDefaultBitrate) noexcept {
  return core::Duration(static_cast<std::int64_t>(frame_bits(f).total) * 1'000'000'000LL / bitrate);
}

// Arbitration priority: a lower key wins the bus. Reproduces the bitwise arbitration of the
// real bus: lower id first; at equal base id a standard frame beats an extended one and a data
// frame beats a remote one.
std::uint32_t arbitration_key(const Frame& f) noexcept;

}  // namespace axon::can
