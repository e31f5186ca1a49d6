// Frame lengths on the wire. Expected values were worked out bit by bit (the simple cases by hand
// in the comments, the rest with an independent polynomial-division CRC and stuffing count).
#include "axon/can/wire.hpp"
#include "frame_text.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <span>
#include <vector>

using namespace axon::can;

namespace {
using axon::can::test::F;
}  // namespace

TEST(Wire, AllDominantEmptyFrame) {
  // SOF, 11 id bits, RTR, IDE, r0 and DLC are all 0: 19 zeros; the CRC of zeros is 0: 15 more.
  // 34 equal bits take a stuff bit after every 5th: 6 stuff bits. 34 + 6 + 13 = 53.
  const auto b = frame_bits(F("000#"));
  EXPECT_EQ(b.unstuffed, 34u);
  EXPECT_EQ(b.stuff, 6u);
  EXPECT_EQ(b.total, 53u);
}

TEST(Wire, BestCaseNoStuffing) {
  // Id 0x085 with eight 0xAA bytes never has five equal bits in a row: 98 + 0 + 13 = 111,
  // the shortest possible 8-byte standard frame.
  const auto b = frame_bits(F("085#AAAAAAAAAAAAAAAA"));
  EXPECT_EQ(b.unstuffed, 98u);
  EXPECT_EQ(b.stuff, 0u);
  EXPECT_EQ(b.total, 111u);
}

TEST(Wire, HeavyStuffing) {
  EXPECT_EQ(frame_bits(F("7FF#FFFFFFFFFFFFFFFF")).stuff, 15u);
  EXPECT_EQ(frame_bits(F("7FF#FFFFFFFFFFFFFFFF")).total, 126u);
  EXPECT_EQ(frame_bits(F("02F#3C3C3C3C3C3C3C3C")).stuff, 20u);
  EXPECT_EQ(frame_bits(F("02F#3C3C3C3C3C3C3C3C")).total, 131u);
  EXPECT_EQ(frame_bits(F("00000000#0000000000000000")).total, 150u);
  EXPECT_EQ(frame_bits(F("123#DEADBEEF")).total, 81u);
  EXPECT_EQ(frame_bits(F("1ABCDEF0#R8")).total, 68u);
}

TEST(Wire, Crc15MatchesReference) {
  // 0x123#DEADBEEF: CRC over SOF..data is 0x4E6B (independent long division).
  std::vector<std::uint8_t> bits;
  auto put = [&](unsigned v, int n) {
    for (int i = n - 1; i >= 0; --i) bits.push_back((v >> i) & 1);
  };
  put(0, 1);
  put(0x123, 11);
  put(0, 3);
  put(4, 4);
  for (unsigned byte : {0xDE, 0xAD, 0xBE, 0xEF}) put(byte, 8);
  EXPECT_EQ(crc15(bits.data(), bits.size()), 0x4E6B);
}

TEST(Wire, WorstCaseBudget) {
  EXPECT_EQ(worst_case_bits(IdFormat::standard, 8), 135u);
  EXPECT_EQ(worst_case_bits(IdFormat::extended, 8), 160u);
  EXPECT_EQ(worst_case_bits(IdFormat::standard, 0), 55u);
  // No real frame exceeds its budget.
  for (unsigned id = 0; id < 0x800; id += 7) {
    std::array<std::uint8_t, 8> d{};
    d.fill(static_cast<std::uint8_t>(id));
    EXPECT_LE(frame_bits(Frame::standard(id, d).value()).total, 135u);
    EXPECT_LE(frame_bits(Frame::extended(id << 18 | id, d).value()).total, 160u);
  }
}

TEST(Wire, FrameTimeAtBitrate) {
  EXPECT_EQ(frame_time(F("085#AAAAAAAAAAAAAAAA")).count(), 111'000);
  EXPECT_EQ(frame_time(F("085#AAAAAAAAAAAAAAAA"), 500'000).count(), 222'000);
}

TEST(Wire, ArbitrationOrder) {
  // Lower id wins; at the same base id, standard beats extended and data beats remote.
  std::vector<Frame> frames{F("00400000#"), F("100#R"), F("100#"), F("7FF#"), F("000#"),
                            F("04000000#R"), F("04000000#"), F("1FFFFFFF#")};
  std::sort(frames.begin(), frames.end(),
            [](const Frame& a, const Frame& b) { return arbitration_key(a) < arbitration_key(b); });
  std::vector<std::string> order;
  for (const auto& f : frames) order.push_back(f.to_string());
  // 0x00400000 has base id 0x001; 0x04000000 has base id 0x100.
  EXPECT_EQ(order, (std::vector<std::string>{"000#", "00400000#", "100#", "100#R", "04000000#", "04000000#R",
                                             "7FF#", "1FFFFFFF#"}));
}

namespace {

// The frame's bits laid out one per element and stuffed one by one, the plain way the tables in
// wire.cpp must agree with.
std::uint32_t reference_total(const Frame& f) {
  std::vector<std::uint8_t> bits;
  auto put = [&](std::uint32_t v, int n) {
    for (int i = n - 1; i >= 0; --i) bits.push_back(static_cast<std::uint8_t>((v >> i) & 1u));
  };
  const std::uint32_t rtr = f.is_remote() ? 1 : 0;
  put(0, 1);
  if (f.is_extended()) {
    put(f.id() >> 18, 11);
    put(3, 2);
    put(f.id() & 0x3FFFF, 18);
    put(rtr, 1);
    put(0, 2);
  } else {
    put(f.id(), 11);
    put(rtr, 1);
    put(0, 2);
  }
  put(f.dlc(), 4);
  for (auto b : f.payload()) put(b, 8);
  put(crc15(bits.data(), bits.size()), 15);
  std::uint32_t stuff = 0;
  int last = -1, run = 0;
  for (auto b : bits) {
    run = b == last ? run + 1 : 1;
    last = b;
    if (run == 5) {
      ++stuff;
      last ^= 1;
      run = 1;
    }
  }
  return static_cast<std::uint32_t>(bits.size()) + stuff + 13;
}

}  // namespace

TEST(Wire, ByteTablesAgreeWithBitByBitCount) {
  // Random ids, lengths and payloads (fixed seed), both formats, data and remote frames.
  std::uint32_t x = 12345;
  auto next = [&] {
    x = x * 1664525u + 1013904223u;
    return x >> 8;
  };
  for (int i = 0; i < 20000; ++i) {
    const bool ext = (i & 1) != 0;
    const std::uint32_t id = ext ? next() & 0x1FFFFFFF : next() & 0x7FF;
    std::array<std::uint8_t, 8> d{};
    const std::size_t len = next() % 9;
    // Runs of equal bytes now and then, where stuffing matters most.
    for (std::size_t k = 0; k < len; ++k) d[k] = (i % 5 == 0) ? static_cast<std::uint8_t>(i % 3 == 0 ? 0 : 0xFF) : static_cast<std::uint8_t>(next());
    const Frame f = i % 7 == 3 ? Frame::remote(id, ext ? IdFormat::extended : IdFormat::standard, static_cast<std::uint8_t>(len)).value()
                  : ext ? Frame::extended(id, std::span<const std::uint8_t>(d.data(), len)).value()
                        : Frame::standard(id, std::span<const std::uint8_t>(d.data(), len)).value();
    ASSERT_EQ(frame_bits(f).total, reference_total(f)) << f.to_string();
  }
}
