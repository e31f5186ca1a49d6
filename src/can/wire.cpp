#include "can/wire.hpp"

#include <array>

namespace axon::can {

std::uint16_t crc15(const std::uint8_t* bits, std::size_t nbits) noexcept {
  std::uint16_t crc = 0;
  for (std::size_t i = 0; i < nbits; ++i) {
    const bool next = (bits[i] & 1u) ^ ((crc >> 14) & 1u);
    crc = static_cast<std::uint16_t>((crc << 1) & 0x7FFF);
    if (next) crc ^= 0x4599;
  }
  return crc;
}

namespace {

// Up to 19 + 13 + 18 + 64 + 15 bits.
struct BitBuffer {
  std::array<std::uint8_t, 160> bit{};
  std::size_t n = 0;
  void put(std::uint32_t value, int count) noexcept {
    for (int i = count - 1; i >= 0; --i) bit[n++] = static_cast<std::uint8_t>((value >> i) & 1u);
  }
};

std::uint32_t count_stuff_bits(const BitBuffer& b) noexcept {
  std::uint32_t stuff = 0;
  std::uint8_t last = 2;
  int run = 0;
  for (std::size_t i = 0; i < b.n; ++i) {
    if (b.bit[i] == last) {
      ++run;
    } else {
      last = b.bit[i];
      run = 1;
    }
    if (run == 5) {
      // A complementary bit goes on the wire; it starts the next run.
      ++stuff;
      last = static_cast<std::uint8_t>(last ^ 1u);
      run = 1;
    }
  }
  return stuff;
}

constexpr std::uint32_t kFixedTail = 1 + 1 + 1 + 7 + 3;  // CRC delim, ACK, ACK delim, EOF, intermission

}  // namespace

FrameBits frame_bits(const Frame& f) noexcept {
  BitBuffer b;
  const std::uint32_t rtr = f.is_remote() ? 1 : 0;
  b.put(0, 1);  // SOF
  if (f.is_extended()) {
    b.put(f.id() >> 18, 11);
    b.put(1, 1);  // SRR
    b.put(1, 1);  // IDE
    b.put(f.id() & 0x3FFFF, 18);
    b.put(rtr, 1);
    b.put(0, 2);  // r1, r0
  } else {
    b.put(f.id(), 11);
    b.put(rtr, 1);
    b.put(0, 1);  // IDE
    b.put(0, 1);  // r0
  }
  b.put(f.dlc(), 4);
  for (std::uint8_t byte : f.payload()) b.put(byte, 8);
  const std::uint16_t crc = crc15(b.bit.data(), b.n);
  b.put(crc, 15);
  FrameBits r;
  r.unstuffed = static_cast<std::uint32_t>(b.n);
  r.stuff = count_stuff_bits(b);
  r.total = r.unstuffed + r.stuff + kFixedTail;
  return r;
}

std::uint32_t worst_case_bits(IdFormat fmt, std::uint8_t dlc) noexcept {
  const std::uint32_t region = (fmt == IdFormat::extended ? 39u : 19u) + 8u * dlc + 15u;
  return region + (region - 1) / 4 + kFixedTail;
}

std::uint32_t arbitration_key(const Frame& f) noexcept {
  const std::uint32_t rtr = f.is_remote() ? 1 : 0;
  if (f.is_extended()) {
    // base id (11) | SRR=1 | IDE=1 | extension (18) | RTR: exactly 32 bits
    return (f.id() >> 18) << 21 | 1u << 20 | 1u << 19 | (f.id() & 0x3FFFF) << 1 | rtr;
  }
  // id (11) | RTR | IDE=0, left-aligned like the extended key
  return f.id() << 21 | rtr << 20;
}

}  // namespace axon::can
