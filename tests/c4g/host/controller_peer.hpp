// The robot controller's side of the c4g server tests: the initialization packet of a small
// two-axis robot, cyclic packets, and a UDP peer on loopback that sends them and reads the answers.
#pragma once

#include "axon/c4g/protocol/init_packet.hpp"
#include "axon/c4g/protocol/packet.hpp"
#include "axon/net/udp_socket.hpp"

#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <span>

namespace axon::c4g::test {

using namespace std::chrono_literals;

// Two open axes on arm 1 (logical 1 and 2), thresholds 0.5 / 0.25 turns, current limits 3 / 4 A.
inline protocol::InitPacket make_init(std::int32_t number = 10) {
  protocol::InitPacket p;
  p.protocol_number = number;
  p.open_axes = 2;
  p.period_ms = 1;
  p.open_axis_list[0][0] = 1;
  p.open_axis_list[0][1] = 2;
  p.following_error[0][0] = 0.5f;
  p.following_error[0][1] = 0.25f;
  p.current_limit[0][0] = 3.0f;
  p.current_limit[0][1] = 4.0f;
  p.transmission_ratio[0][0] = 100.0f;
  p.transmission_ratio[0][1] = 100.0f;
  return p;
}

inline protocol::Packet cyclic(std::int32_t num, std::int32_t mode, std::size_t axes = 2) {
  protocol::Packet p;
  p.num = num;
  p.infpar = protocol::kDrivesOn;
  p.count = axes;
  for (std::size_t i = 0; i < axes; ++i) p.axes[i].mode = mode;
  return p;
}

// The robot controller's side: sends packets, reads the answers.
class Peer {
 public:
  explicit Peer(net::SocketAddress server) : server_(server), socket_(net::UdpSocket::open(net::SocketAddress{0x7f000001, 0}).value()) {}
  [[nodiscard]] net::SocketAddress local() const { return socket_.local_address(); }
  void aim_at(net::SocketAddress server) { server_ = server; }

  void send_raw(std::span<const std::byte> bytes) { ASSERT_TRUE(socket_.send_to(bytes, server_)); }
  void send(const protocol::Packet& p) {
    std::array<std::byte, protocol::kMaxPacketSize> buf{};
    ASSERT_TRUE(protocol::encode_packet(p, buf).ok());
    send_raw({buf.data(), protocol::packet_size(p.count)});
  }
  void send(const protocol::InitPacket& p) {
    std::array<std::byte, protocol::kInitPacketSize> buf{};
    ASSERT_TRUE(protocol::encode_init(p, buf));
    send_raw(buf);
  }
  // The next answer, decoded; count 0 when nothing came within the timeout.
  protocol::Packet answer(std::chrono::milliseconds timeout = 2000ms) {
    std::array<std::byte, 2048> buf{};
    protocol::Packet p;
    auto r = socket_.receive(buf, timeout);
    if (!r) return p;
    EXPECT_TRUE(protocol::decode_packet({buf.data(), r.value().size}, p).ok());
    return p;
  }
  protocol::Packet ask(const protocol::Packet& p) {
    send(p);
    return answer();
  }

 private:
  net::SocketAddress server_;
  net::UdpSocket socket_;
};

}  // namespace axon::c4g::test
