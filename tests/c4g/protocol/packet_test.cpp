#include "axon/c4g/protocol/packet.hpp"

#include "axon/c4g/protocol/error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

using namespace axon::c4g::protocol;

namespace {

std::vector<std::byte> bytes(std::initializer_list<int> v) {
  std::vector<std::byte> out;
  for (int b : v) out.push_back(static_cast<std::byte>(b));
  return out;
}

Packet sample(std::size_t axes) {
  Packet p;
  p.num = 0x1234;
  p.infpar = 0x00000005;
  p.cmd = 0x00000300;
  p.count = axes;
  for (std::size_t i = 0; i < axes; ++i) {
    const float f = static_cast<float>(i);
    p.axes[i] = Axis{static_cast<std::int32_t>(i % 3), 1.5f + f, -2.25f, 3.0f * f, 0.125f, -7.5f, 1e-3f, 42.0f, -0.0f};
  }
  return p;
}

std::vector<std::byte> encoded(const Packet& p) {
  std::vector<std::byte> buf(packet_size(p.count));
  EXPECT_TRUE(encode_packet(p, buf).ok());
  return buf;
}

void put_float(std::vector<std::byte>& buf, std::size_t offset, float v) { std::memcpy(buf.data() + offset, &v, 4); }

}  // namespace

TEST(C4gPacket, SizesAreTwelvePlusThirtySixPerAxis) {
  EXPECT_EQ(packet_size(1), 48u);
  EXPECT_EQ(packet_size(6), 228u);
  EXPECT_EQ(packet_size(20), 732u);
  EXPECT_EQ(kMaxPacketSize, 732u);
  for (std::size_t n = 1; n <= kMaxAxes; ++n) EXPECT_EQ(encoded(sample(n)).size(), 12 + 36 * n);
}

TEST(C4gPacket, WireLayoutIsLittleEndianInStructOrder) {
  Packet p;
  p.num = 0x0102;
  p.infpar = 0x00000105;  // arm 1 drives on, arm 2 byte = 1
  p.cmd = -1;
  p.count = 1;
  p.axes[0] = Axis{0x0A0B0C0D, 1.0f, -2.0f, 0.5f, 0, 0, 0, 0, 3.0f};
  const auto buf = encoded(p);
  const auto expected = bytes({0x02, 0x01, 0, 0, 0x05, 0x01, 0, 0, 0xFF, 0xFF, 0xFF, 0xFF,  // header
                               0x0D, 0x0C, 0x0B, 0x0A,                                     // SM
                               0, 0, 0x80, 0x3F,                                           // D1 = 1.0
                               0, 0, 0, 0xC0,                                              // D2 = -2.0
                               0, 0, 0, 0x3F,                                              // D3 = 0.5
                               0, 0, 0, 0, 0, 0, 0, 0,                                     // D4, D5
                               0, 0, 0, 0, 0, 0, 0, 0,                                     // EXT1, EXT2
                               0, 0, 0x40, 0x40});                                         // EXT3 = 3.0
  EXPECT_EQ(buf, expected);
  Packet back;
  ASSERT_TRUE(decode_packet(buf, back).ok());
  EXPECT_EQ(back, p);
  EXPECT_TRUE(drives_on(back.infpar, 1));
  EXPECT_TRUE(exit_from_open(back.infpar, 2));
}

TEST(C4gPacket, RoundTripsEveryAxisCountBothWays) {
  for (std::size_t n = 1; n <= kMaxAxes; ++n) {
    const Packet p = sample(n);
    const auto buf = encoded(p);
    Packet back;
    ASSERT_TRUE(decode_packet(buf, back).ok()) << n;
    EXPECT_EQ(back, p);
    Packet checked;
    ASSERT_TRUE(decode_packet(buf, checked, n).ok()) << n;
    EXPECT_EQ(checked, p);
  }
}

TEST(C4gPacket, EncodeIntoALargerBufferWritesOnlyThePacket) {
  std::vector<std::byte> buf(kMaxPacketSize, std::byte{0xAA});
  ASSERT_TRUE(encode_packet(sample(2), buf).ok());
  for (std::size_t i = packet_size(2); i < buf.size(); ++i) EXPECT_EQ(buf[i], std::byte{0xAA});
}

TEST(C4gPacket, RejectsWrongSizes) {
  Packet out;
  for (std::size_t size : {0u, 1u, 11u, 12u, 13u, 47u, 49u, 83u, 85u, 1200u, 768u, 1000u}) {
    std::vector<std::byte> buf(size);
    const Fault f = decode_packet(buf, out);
    EXPECT_FALSE(f.ok()) << size;
    EXPECT_TRUE(f.code == ProtocolErrc::wrong_size || f.code == ProtocolErrc::too_many_axes) << size;
  }
  // 12 + 36 * 21 is well formed but has too many axes.
  std::vector<std::byte> wide(packet_size(21));
  EXPECT_EQ(decode_packet(wide, out).code, ProtocolErrc::too_many_axes);
}

TEST(C4gPacket, RejectsAxisCountThatDisagreesWithTheInitPacket) {
  const auto buf = encoded(sample(5));
  Packet out;
  const Fault f = decode_packet(buf, out, 6);
  EXPECT_EQ(f.code, ProtocolErrc::axis_count_mismatch);
  EXPECT_EQ(f.got, 5);
  EXPECT_EQ(f.expected, 6);
  const auto e = to_error(f);
  EXPECT_EQ(e, ProtocolErrc::axis_count_mismatch);
  EXPECT_NE(e.message().find("5 axes"), std::string::npos);
  // A truncated datagram is a size error, not a count disagreement.
  std::vector<std::byte> cut(buf.begin(), buf.end() - 1);
  EXPECT_EQ(decode_packet(cut, out, 5).code, ProtocolErrc::wrong_size);
  EXPECT_EQ(decode_packet(buf, out, 0).code, ProtocolErrc::too_many_axes);
  EXPECT_EQ(decode_packet(buf, out, 21).code, ProtocolErrc::too_many_axes);
}

TEST(C4gPacket, RejectsNonFiniteFloatsAndLeavesTheLastGoodPacket) {
  const Packet good = sample(3);
  const auto good_buf = encoded(good);
  for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                    -std::numeric_limits<float>::infinity(), std::numeric_limits<float>::signaling_NaN()}) {
    for (int field = 1; field <= 8; ++field) {
      auto buf = good_buf;
      put_float(buf, kHeaderSize + 2 * kAxisSize + 4 * static_cast<std::size_t>(field), bad);
      Packet out = good;
      const Fault f = decode_packet(buf, out, 3);
      EXPECT_EQ(f.code, ProtocolErrc::not_finite);
      EXPECT_EQ(f.axis, 2);
      EXPECT_EQ(f.field, field);
      EXPECT_EQ(out, good);
    }
  }
  // The largest finite float is accepted.
  auto buf = good_buf;
  put_float(buf, kHeaderSize + 4, std::numeric_limits<float>::max());
  Packet out;
  EXPECT_TRUE(decode_packet(buf, out).ok());
}

TEST(C4gPacket, EncodeRefusesWhatDecodeWouldReject) {
  std::vector<std::byte> buf(kMaxPacketSize);
  Packet p = sample(2);
  p.axes[1].d5 = std::nanf("");
  Fault f = encode_packet(p, buf);
  EXPECT_EQ(f.code, ProtocolErrc::not_finite);
  EXPECT_EQ(f.field, 5);
  p = sample(2);
  p.axes[0].ext3 = -std::numeric_limits<float>::infinity();
  EXPECT_EQ(encode_packet(p, buf).code, ProtocolErrc::not_finite);
  p = sample(0);
  EXPECT_EQ(encode_packet(p, buf).code, ProtocolErrc::too_many_axes);
  p = sample(2);
  p.count = 21;
  EXPECT_EQ(encode_packet(p, buf).code, ProtocolErrc::too_many_axes);
  p = sample(2);
  std::vector<std::byte> small(packet_size(2) - 1);
  EXPECT_EQ(encode_packet(p, small).code, ProtocolErrc::wrong_size);
  p.num = 0x8000;
  EXPECT_EQ(encode_packet(p, buf).code, ProtocolErrc::value_out_of_range);
  p.num = -1;
  EXPECT_EQ(encode_packet(p, buf).code, ProtocolErrc::value_out_of_range);
}

TEST(C4gPacket, ProtocolNumberRange) {
  Packet p = sample(1);
  p.num = kMaxProtocolNumber;
  auto buf = encoded(p);
  Packet out;
  EXPECT_TRUE(decode_packet(buf, out).ok());
  buf[1] = std::byte{0x80};  // 0x8000 + low byte
  EXPECT_EQ(decode_packet(buf, out).code, ProtocolErrc::value_out_of_range);
  buf[1] = std::byte{0};
  buf[3] = std::byte{0x80};  // negative
  EXPECT_EQ(decode_packet(buf, out).code, ProtocolErrc::value_out_of_range);
  EXPECT_FALSE(to_result(decode_packet(buf, out)).has_value());
}

TEST(C4gPacket, ReplyNumbering) {
  EXPECT_EQ(reply_number(10, ReplyNumbering::same), 10);
  EXPECT_EQ(reply_number(10, ReplyNumbering::next), 11);
  EXPECT_EQ(reply_number(0x7FFE, ReplyNumbering::next), 0x7FFF);
  EXPECT_EQ(reply_number(0x7FFF, ReplyNumbering::next), 1);  // wraps to 1, not 0
  EXPECT_EQ(reply_number(0, ReplyNumbering::next), 1);
}

TEST(C4gPacket, PerArmBytes) {
  std::int32_t infpar = 0;
  infpar = with_arm_byte(infpar, 1, kDrivesOn);
  infpar = with_arm_byte(infpar, 3, kDrivesOn);
  EXPECT_EQ(infpar, 0x00050005);
  EXPECT_TRUE(drives_on(infpar, 1));
  EXPECT_FALSE(drives_on(infpar, 2));
  EXPECT_TRUE(drives_on(infpar, 3));
  EXPECT_FALSE(drives_on(infpar, 4));
  EXPECT_EQ(request_exit_from_open(0, 4), static_cast<std::int32_t>(0x01000000));
  EXPECT_EQ(request_exit_from_open(0, 1), 1);
  EXPECT_TRUE(exit_from_open(1, 1));
  EXPECT_EQ(arm_byte(-1, 4), 0xFF);
  EXPECT_EQ(arm_byte(0x7F, 0), 0);  // no arm 0
  EXPECT_EQ(with_arm_byte(7, 5, 1), 7);
}

TEST(C4gPacket, ClassifiesDatagramsBySize) {
  EXPECT_EQ(classify(1200), DatagramKind::init);
  EXPECT_EQ(classify(48), DatagramKind::cyclic);
  EXPECT_EQ(classify(732), DatagramKind::cyclic);
  EXPECT_EQ(classify(768), DatagramKind::unknown);
  EXPECT_EQ(classify(12), DatagramKind::unknown);
  EXPECT_EQ(classify(49), DatagramKind::unknown);
}

TEST(C4gPacket, FieldNamesForPrinting) {
  EXPECT_EQ(field_name(0), "SM");
  EXPECT_EQ(field_name(5), "D5");
  EXPECT_EQ(field_name(8), "EXT3");
  EXPECT_EQ(field_name(9), "?");
  EXPECT_EQ(field_meaning(Direction::to_pc, 3), "actual position [motor turns]");
  EXPECT_EQ(field_meaning(Direction::to_controller, 5), "current contribution [A]");
  const auto s = to_string(sample(2));
  EXPECT_NE(s.find("NUM=4660"), std::string::npos);
  EXPECT_NE(s.find("[1] SM=1"), std::string::npos);
}

TEST(C4gPacket, RealTimeEntryPointsAreNoexceptAndWorkOnCallerStorage) {
  Packet p = sample(6);
  std::array<std::byte, kMaxPacketSize> buf{};
  static_assert(noexcept(encode_packet(p, std::span<std::byte>(buf))));
  static_assert(noexcept(decode_packet(std::span<const std::byte>(buf), p)));
  static_assert(noexcept(decode_packet(std::span<const std::byte>(buf), p, 6)));
  ASSERT_TRUE(encode_packet(p, buf).ok());
  Packet out;
  ASSERT_TRUE(decode_packet(std::span<const std::byte>(buf.data(), packet_size(6)), out, 6).ok());
  EXPECT_EQ(out, p);
}
