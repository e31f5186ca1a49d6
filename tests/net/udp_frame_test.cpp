#include "axon/net/udp_frame.hpp"

#include <gtest/gtest.h>

#include <array>
#include <vector>

using namespace axon::net;

namespace {
std::vector<std::byte> bytes(std::initializer_list<int> v) {
  std::vector<std::byte> out;
  for (int b : v) out.push_back(std::byte(static_cast<unsigned char>(b)));
  return out;
}
std::uint16_t get16(const std::byte* p) { return static_cast<std::uint16_t>((std::to_integer<int>(p[0]) << 8) | std::to_integer<int>(p[1])); }
}  // namespace

TEST(UdpFrame, OnesComplementSumOfTheRfc1071Example) {
  const auto d = bytes({0x00, 0x01, 0xf2, 0x03, 0xf4, 0xf5, 0xf6, 0xf7});
  EXPECT_EQ(ones_complement_sum(d), 0xddf2u);
  EXPECT_EQ(fold_checksum(ones_complement_sum(d)), 0x220d);
  // An odd byte counts as the high byte of a zero-padded word.
  EXPECT_EQ(ones_complement_sum(bytes({0x12})), 0x1200u);
}

TEST(UdpFrame, Ipv4HeaderChecksumMatchesAKnownHeader) {
  // 192.168.0.1 -> 192.168.0.199, total length 0x73, id 0, DF, TTL 64, UDP: checksum 0xb861.
  std::array<std::byte, 42 + 87> out{};
  std::vector<std::byte> payload(87);
  write_udp_frame(out, SocketAddress{0xc0a80001, 1}, SocketAddress{0xc0a800c7, 2}, payload, payload.size(), 0);
  EXPECT_EQ(get16(out.data() + 14 + 2), 0x73);
  EXPECT_EQ(get16(out.data() + 14 + 10), 0xb861);
}

TEST(UdpFrame, UdpChecksumVerifiesWithThePseudoHeader) {
  const auto payload = bytes({1, 2, 3, 4, 5});  // odd length
  std::array<std::byte, 42 + 5> out{};
  const SocketAddress src{0x0a020c96, 1000}, dst{0x0a020c95, 40000};
  EXPECT_EQ(write_udp_frame(out, src, dst, payload, payload.size(), 7), 47u);
  const std::byte* udp = out.data() + 34;
  EXPECT_EQ(get16(udp), 1000);
  EXPECT_EQ(get16(udp + 2), 40000);
  EXPECT_EQ(get16(udp + 4), 13);
  const auto pseudo = bytes({0x0a, 0x02, 0x0c, 0x96, 0x0a, 0x02, 0x0c, 0x95, 0, 17, 0, 13});
  std::uint32_t sum = ones_complement_sum(pseudo);
  sum = ones_complement_sum({udp, 13}, sum);
  EXPECT_EQ(fold_checksum(sum), 0) << "a correct checksum sums to all ones";
  // MACs carry the IPv4 addresses.
  EXPECT_EQ(std::to_integer<int>(out[0]), 0x02);
  EXPECT_EQ(std::to_integer<int>(out[5]), 0x95);
  EXPECT_EQ(std::to_integer<int>(out[11]), 0x96);
}
