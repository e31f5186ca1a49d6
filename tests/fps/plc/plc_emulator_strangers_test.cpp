// The PLC emulator facing clients that are not the host: what they send never changes a relay
// unnoticed, and bad frames are counted without disturbing anyone else.
#include "axon/fps/plc/client.hpp"
#include "axon/fps/plc/emulator.hpp"

#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <thread>

namespace axon::fps::plc {
namespace {

// A bare TCP connection to the emulator (blocking, loopback).
struct RawClient {
  int fd = -1;
  explicit RawClient(std::uint16_t port) {
    fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    EXPECT_EQ(::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    timeval tv{5, 0};
    ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  }
  ~RawClient() { ::close(fd); }
  void send(std::initializer_list<std::uint8_t> bytes) {
    const std::vector<std::uint8_t> b(bytes);
    ASSERT_EQ(::send(fd, b.data(), b.size(), 0), static_cast<ssize_t>(b.size()));
  }
  // Bytes until the peer closes (0) or the 5 s limit (-1).
  ssize_t read_some(std::array<std::uint8_t, 512>& buf) { return ::recv(fd, buf.data(), buf.size(), 0); }
};

EmulatorCounters wait_for_bad_requests(const PlcEmulator& emu, std::uint64_t n) {
  for (int i = 0; i < 200 && emu.counters().bad_requests < n; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  return emu.counters();
}

TEST(PlcEmulatorStrangers, AFrameThatIsNotModbusIsCountedAndEndsOnlyThatConnection) {
  auto emu = PlcEmulator::start({}).value();
  PlcClient host(emu->endpoint());
  ASSERT_TRUE(host.status().has_value());
  RawClient stranger(emu->port());
  // MBAP header announcing a 65535-byte PDU: no Modbus TCP request is that long.
  stranger.send({0x00, 0x01, 0x00, 0x00, 0xFF, 0xFF, 0x01, 0x05});
  std::array<std::uint8_t, 512> buf{};
  EXPECT_EQ(stranger.read_some(buf), 0);  // closed by the emulator
  EXPECT_EQ(wait_for_bad_requests(*emu, 1).bad_requests, 1u);
  // The host's session goes on; no relay changed.
  const auto s = host.status();
  ASSERT_TRUE(s.has_value()) << s.error().message();
  EXPECT_FALSE(s.value().sync_line);
  for (bool on : s.value().positioner_power) EXPECT_TRUE(on);
  EXPECT_EQ(emu->counters().relay_changes, 0u);
}

TEST(PlcEmulatorStrangers, AnUnknownFunctionIsAnsweredWithTheModbusExceptionAndTheConnectionStays) {
  auto emu = PlcEmulator::start({}).value();
  RawClient stranger(emu->port());
  // Function 0x2B (encapsulated interface) is not served: exception 01, illegal function.
  stranger.send({0x00, 0x07, 0x00, 0x00, 0x00, 0x03, 0xFF, 0x2B, 0x0E});
  std::array<std::uint8_t, 512> buf{};
  const ssize_t n = stranger.read_some(buf);
  ASSERT_EQ(n, 9);
  EXPECT_EQ(buf[7], 0x2B | 0x80);
  EXPECT_EQ(buf[8], 0x01);
  // Still connected: a read of coil 0 is answered.
  stranger.send({0x00, 0x08, 0x00, 0x00, 0x00, 0x06, 0xFF, 0x01, 0x00, 0x00, 0x00, 0x01});
  EXPECT_GT(stranger.read_some(buf), 0);
  EXPECT_EQ(emu->counters().bad_requests, 0u);
}

}  // namespace
}  // namespace axon::fps::plc
