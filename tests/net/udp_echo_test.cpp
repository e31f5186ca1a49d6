#include "axon/net/udp_echo.hpp"

#include <gtest/gtest.h>

#include <array>

namespace {

using axon::net::SocketAddress;
using axon::net::UdpEchoServer;
using axon::net::UdpSocket;

// The c4g benchmark's and demo's baseline: every datagram comes back to its sender, unchanged.
TEST(UdpEchoServer, SendsEveryDatagramBackUnchanged) {
  auto echo = UdpEchoServer::start().value();
  EXPECT_EQ(echo->address().ip, 0x7f000001u);
  auto client = UdpSocket::open(SocketAddress{0x7f000001, 0}).value();
  std::array<std::byte, 228> tx{}, rx{};
  for (int i = 0; i < 3; ++i) {
    tx[0] = static_cast<std::byte>(i);
    ASSERT_TRUE(client.send_to(tx, echo->address()));
    auto got = client.receive(rx, std::chrono::seconds(5));
    ASSERT_TRUE(got) << got.error().message();
    EXPECT_EQ(got.value().size, tx.size());
    EXPECT_EQ(rx[0], static_cast<std::byte>(i));
  }
  echo->stop();
  EXPECT_EQ(echo->echoed(), 3u);
}

}  // namespace
