// The PLC emulator facing hostile peers (docs/reliability.md, "Hostile peers"): many connections,
// clients that stop half-way through a request, clients that never read, garbage and oversized
// frames. What must hold: the host's requests are still answered meanwhile, each hostile
// connection costs a bounded amount and is counted and logged once, nothing crashes.
#include "axon/fps/plc/client.hpp"
#include "axon/fps/plc/emulator.hpp"

#include "support/hostile_peer.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <algorithm>
#include <iostream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace axon::fps::plc::hostile_test {
namespace {

using namespace axon::fps::plc;

using hostile::RawPeer;
using hostile::WarningLog;
using hostile::wait_until;
using namespace std::chrono_literals;

// A Modbus TCP request: MBAP header (transaction `tid`, unit 0xFF) and the PDU.
std::string request(std::uint16_t tid, std::initializer_list<std::uint8_t> pdu) {
  std::string r{static_cast<char>(tid >> 8), static_cast<char>(tid & 0xFF), 0, 0, 0, static_cast<char>(pdu.size() + 1),
                static_cast<char>(0xFF)};
  for (auto b : pdu) r.push_back(static_cast<char>(b));
  return r;
}
// Read coils 0..count-1.
std::string read_coils(std::uint16_t tid, std::uint8_t count) { return request(tid, {0x01, 0, 0, 0, count}); }

// The host: a real client with a short timeout and no retry, so that a server that is held up
// shows as a failed call.
struct Host {
  PlcClient client;
  explicit Host(const PlcEmulator& emu) : client(emu.endpoint(), {}, PlcClientOptions{1s, 0}) {}
  // Status round trip; its time in microseconds, or -1 when it failed.
  double round_trip_us() {
    const auto t0 = std::chrono::steady_clock::now();
    if (!client.status()) return -1;
    return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
  }
};

double median_round_trip_us(Host& host) {
  return hostile::median_of(50, [&] { return host.round_trip_us(); });
}

TEST(PlcEmulatorHostile, TwoHundredConnectionsAtOnceAreEachServedAndTheHostToo) {
  EmulatorOptions o;
  o.max_clients = 256;
  auto emu = PlcEmulator::start(o).value();
  Host host(*emu);
  const double alone_us = median_round_trip_us(host);
  const long rss_before = hostile::resident_kb();
  std::vector<std::unique_ptr<RawPeer>> peers;
  for (int i = 0; i < 200; ++i) peers.push_back(std::make_unique<RawPeer>(emu->port()));
  ASSERT_TRUE(wait_until([&] { return emu->counters().clients == 201; })) << emu->counters().clients;
  const long rss_idle = hostile::resident_kb();
  const double crowded_us = median_round_trip_us(host);
  EXPECT_GT(crowded_us, 0) << "the host was not answered with 200 idle connections open";
  // Every one of them is answered too.
  for (std::size_t i = 0; i < peers.size(); ++i) ASSERT_TRUE(peers[i]->send_all(read_coils(static_cast<std::uint16_t>(i), 8)));
  for (auto& p : peers) EXPECT_EQ(p->read_at_least(10).size(), 10u);
  std::cout << "figure: plc host status round trip " << alone_us << " us alone, " << crowded_us
            << " us with 200 idle connections; process RSS +" << rss_idle - rss_before << " kB for them\n";
  peers.clear();
  EXPECT_TRUE(wait_until([&] { return emu->counters().clients == 1; }));
  EXPECT_EQ(emu->counters().refused, 0u);
  EXPECT_EQ(emu->counters().bad_requests, 0u);
}

TEST(PlcEmulatorHostile, ConnectionsBeyondTheLimitAreRefusedCountedAndLoggedOnce) {
  WarningLog log;
  EmulatorOptions o;
  o.max_clients = 8;
  auto emu = PlcEmulator::start(o).value();
  std::vector<std::unique_ptr<RawPeer>> peers;
  for (int i = 0; i < 8; ++i) peers.push_back(std::make_unique<RawPeer>(emu->port()));
  ASSERT_TRUE(wait_until([&] { return emu->counters().clients == 8; }));
  std::vector<std::unique_ptr<RawPeer>> extra;
  for (int i = 0; i < 20; ++i) extra.push_back(std::make_unique<RawPeer>(emu->port()));
  ASSERT_TRUE(wait_until([&] { return emu->counters().refused == 20; })) << emu->counters().refused;
  for (auto& p : extra) EXPECT_TRUE(p->closed_by_server());
  EXPECT_EQ(log.count("refusing"), 1u);
  // Room again: the host gets in and is served.
  peers.clear();
  ASSERT_TRUE(wait_until([&] { return emu->counters().clients == 0; }));
  Host host(*emu);
  EXPECT_GT(host.round_trip_us(), 0);
}

TEST(PlcEmulatorHostile, AClientStoppingHalfWayThroughARequestHoldsUpNoOne) {
  WarningLog log;
  EmulatorOptions o;
  o.request_timeout = 500ms;
  auto emu = PlcEmulator::start(o).value();
  Host host(*emu);
  ASSERT_GT(host.round_trip_us(), 0);
  // The slow-loris: a valid request, one byte every 200 ms.
  RawPeer loris(emu->port());
  const std::string req = read_coils(1, 8);
  std::atomic<bool> stop{false};
  std::thread trickle([&] {
    for (char c : req) {
      if (stop || loris.broken() || loris.send_some(std::string_view(&c, 1)) != 1) return;
      std::this_thread::sleep_for(200ms);
    }
  });
  std::this_thread::sleep_for(50ms);
  for (int i = 0; i < 5; ++i) EXPECT_GT(host.round_trip_us(), 0) << "round " << i << ": the host was held up";
  EXPECT_TRUE(wait_until([&] { return emu->counters().stalled_requests == 1; }, 3000ms));
  EXPECT_TRUE(loris.closed_by_server());
  stop = true;
  trickle.join();
  EXPECT_EQ(log.count("not completed within"), 1u);
  EXPECT_GT(host.round_trip_us(), 0);
}

TEST(PlcEmulatorHostile, AClientThatNeverReadsIsDisconnectedNotWaitedFor) {
  WarningLog log;
  auto emu = PlcEmulator::start({}).value();
  Host host(*emu);
  ASSERT_GT(host.round_trip_us(), 0);
  RawPeer reader(emu->port(), 4096);
  const std::uint16_t span = emu->map().input_register_span();
  std::string burst;
  for (std::uint16_t t = 0; t < 256; ++t)
    burst += request(t, {0x04, 0, 0, 0, static_cast<std::uint8_t>(span)});
  std::thread pump([&] {
    const auto end = std::chrono::steady_clock::now() + 10s;
    while (!reader.broken() && emu->counters().slow_readers == 0 && std::chrono::steady_clock::now() < end)
      if (reader.send_some(burst) == 0) std::this_thread::sleep_for(1ms);
  });
  // Meanwhile the host is served.
  std::this_thread::sleep_for(100ms);
  for (int i = 0; i < 5; ++i) EXPECT_GT(host.round_trip_us(), 0) << "round " << i << ": the host was held up";
  EXPECT_TRUE(wait_until([&] { return emu->counters().slow_readers == 1; }, 10000ms));
  pump.join();
  EXPECT_EQ(log.count("does not read its answers"), 1u);
  EXPECT_GT(host.round_trip_us(), 0);
  EXPECT_TRUE(wait_until([&] { return emu->counters().clients == 1; }));
}

TEST(PlcEmulatorHostile, GarbageAndOversizedFramesEndTheirOwnConnectionOnlyEachCountedAndLoggedOnce) {
  WarningLog log;
  auto emu = PlcEmulator::start({}).value();
  Host host(*emu);
  ASSERT_GT(host.round_trip_us(), 0);
  const std::vector<std::string> hostile{
      std::string(1 << 20, '\0'),                                       // 1 MB of zeros: length 0
      std::string(64 * 1024, 'G'),                                      // text: protocol id 0x4747
      std::string("\x00\x01\x00\x00\xFF\xFF\xFF\x03", 8) + std::string(4096, 'x'),  // length 65535
      request(7, {0x03, 0, 0, 0, 1, 0xAA, 0xBB, 0xCC}),                 // read registers, 3 bytes too many
      request(8, {0x10, 0, 0, 0, 1, 200, 1, 2}),                        // write registers, byte count 200, 2 bytes
  };
  std::vector<std::unique_ptr<RawPeer>> peers;
  for (const auto& bytes : hostile) {
    peers.push_back(std::make_unique<RawPeer>(emu->port()));
    peers.back()->send_all(bytes, 2000ms);
  }
  for (auto& p : peers) EXPECT_TRUE(p->closed_by_server());
  EXPECT_TRUE(wait_until([&] { return emu->counters().bad_requests == hostile.size(); })) << emu->counters().bad_requests;
  EXPECT_EQ(log.count("not Modbus TCP"), hostile.size());
  EXPECT_GT(host.round_trip_us(), 0);
  EXPECT_EQ(emu->counters().relay_changes, 0u);
}

TEST(PlcEmulatorHostile, ConnectionsClosedMidRequestLeaveNothingBehind) {
  auto emu = PlcEmulator::start({}).value();
  EXPECT_EQ(emu->endpoint().host, "127.0.0.1");  // loopback unless an address is given
  const std::size_t fds_before = hostile::open_descriptors();
  for (int i = 0; i < 50; ++i) {
    RawPeer p(emu->port());
    p.send_all(read_coils(1, 8).substr(0, static_cast<std::size_t>(i % 11) + 1));
  }
  EXPECT_TRUE(wait_until([&] { return emu->counters().connections == 50 && emu->counters().clients == 0; }));
  EXPECT_TRUE(wait_until([&] { return hostile::open_descriptors() == fds_before; })) << hostile::open_descriptors();
  EXPECT_EQ(emu->counters().bad_requests, 0u);
  EXPECT_EQ(emu->counters().requests, 0u);
  Host host(*emu);
  EXPECT_GT(host.round_trip_us(), 0);
}

}  // namespace
}  // namespace axon::fps::plc::hostile_test
