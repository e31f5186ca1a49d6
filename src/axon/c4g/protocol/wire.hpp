// Little-endian 4-byte fields, the only wire element of the c4g open interface (the controller is
// x86: int32 and IEEE-754 float32, least significant byte first). Independent of the host's order.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <span>

namespace axon::c4g::protocol::wire {

inline void put_u32(std::byte* out, std::uint32_t v) noexcept {
  out[0] = static_cast<std::byte>(v & 0xFFu);
  out[1] = static_cast<std::byte>((v >> 8) & 0xFFu);
  out[2] = static_cast<std::byte>((v >> 16) & 0xFFu);
  out[3] = static_cast<std::byte>((v >> 24) & 0xFFu);
}
inline std::uint32_t get_u32(const std::byte* in) noexcept {
  return static_cast<std::uint32_t>(in[0]) | (static_cast<std::uint32_t>(in[1]) << 8) |
         (static_cast<std::uint32_t>(in[2]) << 16) | (static_cast<std::uint32_t>(in[3]) << 24);
}
inline void put_i32(std::byte* out, std::int32_t v) noexcept { put_u32(out, static_cast<std::uint32_t>(v)); }
inline std::int32_t get_i32(const std::byte* in) noexcept { return static_cast<std::int32_t>(get_u32(in)); }
inline void put_f32(std::byte* out, float v) noexcept { put_u32(out, std::bit_cast<std::uint32_t>(v)); }
inline float get_f32(const std::byte* in) noexcept { return std::bit_cast<float>(get_u32(in)); }

// True for NaN and both infinities, judged on the bit pattern (safe under -ffast-math too).
inline bool is_non_finite_bits(std::uint32_t bits) noexcept { return (bits & 0x7F800000u) == 0x7F800000u; }
inline bool is_finite(float v) noexcept { return !is_non_finite_bits(std::bit_cast<std::uint32_t>(v)); }

}  // namespace axon::c4g::protocol::wire
