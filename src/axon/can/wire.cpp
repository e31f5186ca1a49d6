#include "axon/can/wire.hpp"

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

// The frame's bits SOF..CRC packed most significant first into bytes: at most 1 + 38 + 4 + 64 + 15
// = 122 bits (extended id, 8 data bytes), so 16 bytes.
struct PackedBits {
  std::array<std::uint8_t, 16> byte{};
  std::uint32_t n = 0;
  void put(std::uint32_t value, unsigned count) noexcept {
    for (unsigned i = count; i-- > 0;) {
      if ((value >> i) & 1u) byte[n >> 3] = static_cast<std::uint8_t>(byte[n >> 3] | (0x80u >> (n & 7)));
      ++n;
    }
  }
  void put_byte(std::uint8_t value) noexcept {
    const unsigned shift = n & 7;
    byte[n >> 3] = static_cast<std::uint8_t>(byte[n >> 3] | (value >> shift));
    if (shift != 0) byte[(n >> 3) + 1] = static_cast<std::uint8_t>(value << (8 - shift));
    n += 8;
  }
  [[nodiscard]] unsigned bit(std::uint32_t i) const noexcept { return (byte[i >> 3] >> (7 - (i & 7))) & 1u; }
};

// CRC-15/CAN eight bits at a time: entry b is the register after shifting the byte b through a
// zero register.
constexpr std::array<std::uint16_t, 256> make_crc_table() {
  std::array<std::uint16_t, 256> t{};
  for (unsigned b = 0; b < 256; ++b) {
    unsigned crc = b << 7;
    for (int i = 0; i < 8; ++i) crc = (crc & 0x4000u) ? ((crc << 1) ^ 0x4599u) : (crc << 1);
    t[b] = static_cast<std::uint16_t>(crc & 0x7FFFu);
  }
  return t;
}
constexpr auto kCrcTable = make_crc_table();

std::uint16_t crc15_packed(const PackedBits& b) noexcept {
  std::uint32_t crc = 0;
  const std::uint32_t whole = b.n / 8;
  for (std::uint32_t i = 0; i < whole; ++i) crc = ((crc << 8) ^ kCrcTable[((crc >> 7) ^ b.byte[i]) & 0xFFu]) & 0x7FFFu;
  for (std::uint32_t i = whole * 8; i < b.n; ++i) {
    const unsigned next = b.bit(i) ^ ((crc >> 14) & 1u);
    crc = (crc << 1) & 0x7FFFu;
    if (next) crc ^= 0x4599u;
  }
  return static_cast<std::uint16_t>(crc);
}

// Bit stuffing as a state machine over bytes. State: the level of the last bit on the wire (stuff
// bits included) and how many equal bits end there (1..4); state 0 is the start (no bit yet).
// Entry [state][byte] holds the state after the byte (low 4 bits) and the stuff bits it needed.
struct StuffStep {
  std::uint8_t state;
  std::uint8_t stuff;
};
constexpr unsigned stuff_state(unsigned level, unsigned run) { return 1 + level * 4 + (run - 1); }
constexpr StuffStep stuff_bit(unsigned state, unsigned bit) {
  unsigned level = state == 0 ? 2 : (state - 1) / 4, run = state == 0 ? 0 : (state - 1) % 4 + 1;
  std::uint8_t stuff = 0;
  if (bit == level) {
    ++run;
  } else {
    level = bit;
    run = 1;
  }
  if (run == 5) {  // a complementary bit goes on the wire and starts the next run
    ++stuff;
    level ^= 1u;
    run = 1;
  }
  return {static_cast<std::uint8_t>(stuff_state(level, run)), stuff};
}
constexpr unsigned kStuffStates = 9;
constexpr std::array<std::array<StuffStep, 256>, kStuffStates> make_stuff_table() {
  std::array<std::array<StuffStep, 256>, kStuffStates> t{};
  for (unsigned s = 0; s < kStuffStates; ++s) {
    for (unsigned b = 0; b < 256; ++b) {
      unsigned state = s, stuff = 0;
      for (int i = 7; i >= 0; --i) {
        const auto step = stuff_bit(state, (b >> i) & 1u);
        state = step.state;
        stuff += step.stuff;
      }
      t[s][b] = {static_cast<std::uint8_t>(state), static_cast<std::uint8_t>(stuff)};
    }
  }
  return t;
}
constexpr auto kStuffTable = make_stuff_table();

std::uint32_t count_stuff_bits(const PackedBits& b) noexcept {
  unsigned state = 0;
  std::uint32_t stuff = 0;
  const std::uint32_t whole = b.n / 8;
  for (std::uint32_t i = 0; i < whole; ++i) {
    const auto step = kStuffTable[state][b.byte[i]];
    state = step.state;
    stuff += step.stuff;
  }
  for (std::uint32_t i = whole * 8; i < b.n; ++i) {
    const auto step = stuff_bit(state, b.bit(i));
    state = step.state;
    stuff += step.stuff;
  }
  return stuff;
}

constexpr std::uint32_t kFixedTail = 1 + 1 + 1 + 7 + 3;  // CRC delim, ACK, ACK delim, EOF, intermission

}  // namespace

FrameBits frame_bits(const Frame& f) noexcept {
  PackedBits b;
  const std::uint32_t rtr = f.is_remote() ? 1 : 0;
  if (f.is_extended()) {
    // SOF, base id, SRR = 1, IDE = 1, extension, RTR, r1, r0: 39 bits
    b.put(f.id() >> 18, 12);  // SOF (0) and the 11-bit base id
    b.put(0b11, 2);
    b.put(f.id() & 0x3FFFF, 18);
    b.put(rtr << 2, 3);
  } else {
    b.put(f.id(), 12);  // SOF (0) and the 11-bit id
    b.put(rtr << 2, 3);  // RTR, IDE = 0, r0
  }
  b.put(f.dlc(), 4);
  for (std::uint8_t byte : f.payload()) b.put_byte(byte);
  const std::uint16_t crc = crc15_packed(b);
  b.put(crc, 15);
  FrameBits r;
  r.unstuffed = b.n;
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
