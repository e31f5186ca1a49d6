// Start-up sequence and reply checking of the simulated controller.
#include "axon/c4g/sim/controller.hpp"
#include "pc_responder.hpp"

#include <gtest/gtest.h>

#include <cstring>

namespace axon::c4g::sim::test {
namespace {

constexpr std::string_view kRun = "steps:\n  - run\n";

TEST(C4gSimCommunication, SyncPacketsThenInitPacketThenCycle) {
  auto c = make_controller(kRun);
  PcResponder pc;
  pc.run(c, 6);
  ASSERT_EQ(pc.sent.size(), 6u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_TRUE(pc.sent[i].cyclic) << i;
    EXPECT_EQ(pc.sent[i].bytes.size(), P::packet_size(6));
    EXPECT_EQ(pc.sent[i].packet.num, i + 1);
    for (std::size_t a = 0; a < 6; ++a) EXPECT_EQ(pc.sent[i].packet.axes[a].mode, 0);
  }
  ASSERT_TRUE(pc.sent[3].init);
  ASSERT_EQ(pc.sent[3].bytes.size(), P::kInitPacketSize);
  auto init = P::decode_init(pc.sent[3].bytes);
  ASSERT_TRUE(init.has_value());
  P::InitPacket expected = six_axis_init();
  expected.protocol_number = 4;  // the number of the packet it travels in
  EXPECT_EQ(init.value(), expected);
  EXPECT_EQ(init.value().period_ms, 2);
  EXPECT_TRUE(pc.sent[4].cyclic);
  EXPECT_EQ(pc.sent[4].packet.num, 5);
  EXPECT_EQ(c.phase(), Phase::cycle);
  EXPECT_EQ(c.stats().sync_sent, 3u);
  EXPECT_EQ(c.stats().init_sent, 1u);
  EXPECT_EQ(pc.count_events(event::kSynchronised), 1u);
  // Cyclic packets report the calibrated motor positions: link 0 is the calibration constant.
  EXPECT_FLOAT_EQ(pc.sent[5].packet.axes[0].d3, 0.142965f);
  EXPECT_GT(pc.sent[5].packet.axes[0].ext2, 0.0f);  // diagonal inertia
}

TEST(C4gSimCommunication, SyncWaitsForAnswersAndPeriodOptionChangesTheInitPacket) {
  ControllerOptions o;
  o.period_ms = 1;
  auto c = make_controller(kRun, quick_robot(), o);
  PcResponder pc;
  pc.answer = false;
  pc.run(c, 50);
  EXPECT_EQ(c.phase(), Phase::sync);  // unanswered sync packets: still synchronising, no error
  EXPECT_FALSE(c.communication_error());
  pc.answer = true;
  pc.run(c, 4);
  ASSERT_TRUE(pc.sent.back().init);
  EXPECT_EQ(P::decode_init(pc.sent.back().bytes).value().period_ms, 1);
  EXPECT_DOUBLE_EQ(c.period_s(), 0.001);
}

TEST(C4gSimCommunication, CommunicationErrorAfterExactlyTenMisses) {
  auto c = make_controller("steps:\n  - drive_on\n  - run\n");
  PcResponder pc;
  ASSERT_TRUE(pc.run_until(c, [&] { return c.drives_on(1); }));
  pc.answer = false;
  pc.run(c, 9);
  EXPECT_FALSE(c.communication_error());
  EXPECT_EQ(c.stats().misses, 9u);
  EXPECT_EQ(pc.count_events(event::kCommunicationError), 0u);
  pc.tick(c);
  EXPECT_TRUE(c.communication_error());
  EXPECT_EQ(c.phase(), Phase::failed);
  EXPECT_EQ(c.stats().misses, 10u);
  ASSERT_EQ(pc.count_events(event::kCommunicationError), 1u);
  EXPECT_NE(pc.find_event(event::kCommunicationError)->text.find("C4GOpen: communication error"), std::string::npos);
  EXPECT_FALSE(c.drives_on(1));
  EXPECT_TRUE(c.finished());
  // The exchange is over: nothing more is sent.
  pc.tick(c);
  EXPECT_TRUE(pc.sent.back().bytes.empty());
}

TEST(C4gSimCommunication, AGoodReplyResetsTheMissCount) {
  auto c = make_controller(kRun);
  PcResponder pc;
  pc.run(c, 10);
  for (int round = 0; round < 3; ++round) {
    pc.answer = false;
    pc.run(c, 9);
    pc.answer = true;
    pc.tick(c);
  }
  EXPECT_FALSE(c.communication_error());
  EXPECT_EQ(c.stats().misses, 27u);
  EXPECT_EQ(c.stats().max_consecutive_misses, 9u);
}

TEST(C4gSimCommunication, WrongNumberWrongSizeAndMalformedRepliesAreMissesCountedByKind) {
  auto c = make_controller(kRun);
  PcResponder pc;
  pc.run(c, 10);
  int kind = 0;
  pc.raw = [&](const P::Packet& req) {
    P::Packet r;
    r.num = req.num;
    r.count = req.count;
    std::vector<std::byte> out(P::kMaxPacketSize);
    switch (kind % 3) {
      case 0: r.num = req.num + 1000; break;                 // wrong number
      case 1: r.count = req.count - 1; break;                // another axis count: wrong size
      case 2: r.axes[2].d4 = 1.0f; break;                    // made non-finite below
    }
    EXPECT_TRUE(P::encode_packet(r, out).ok());
    out.resize(P::packet_size(r.count));
    if (kind % 3 == 2) {
      const std::uint32_t nan_bits = 0x7FC00000u;
      std::memcpy(out.data() + P::kHeaderSize + 2 * P::kAxisSize + 16, &nan_bits, 4);
    }
    ++kind;
    return out;
  };
  pc.run(c, 9);
  EXPECT_FALSE(c.communication_error());
  EXPECT_EQ(c.stats().wrong_number, 3u);
  EXPECT_EQ(c.stats().wrong_size, 3u);
  EXPECT_EQ(c.stats().malformed, 3u);
  EXPECT_EQ(c.stats().misses, 9u);
  pc.tick(c);
  EXPECT_TRUE(c.communication_error());
}

TEST(C4gSimCommunication, LateRepliesAreRecognisedAndDoNotCountForTheCurrentPacket) {
  auto c = make_controller(kRun);
  PcResponder pc;
  pc.run(c, 10);
  // Answer each packet one tick late: every tick misses, each reply is late.
  std::optional<P::Packet> held;
  pc.answer = false;
  for (int i = 0; i < 5; ++i) {
    const auto d = c.begin_cycle();
    if (held) PcResponder::send(c, *held);
    P::Packet req;
    ASSERT_TRUE(P::decode_packet(d, req).ok());
    P::Packet r;
    r.num = req.num;
    r.count = req.count;
    held = r;
    c.end_cycle();
  }
  EXPECT_EQ(c.stats().late_replies, 4u);
  EXPECT_EQ(c.stats().misses, 5u);
}

TEST(C4gSimCommunication, NextNumberingIsAcceptedWhenConfigured) {
  ControllerOptions o;
  o.numbering = P::ReplyNumbering::next;
  auto c = make_controller(kRun, quick_robot(), o);
  PcResponder pc;
  pc.fill = [](const P::Packet& req, P::Packet& r) { r.num = P::next_protocol_number(req.num); };
  pc.run(c, 40);
  EXPECT_EQ(c.stats().misses, 0u);
  EXPECT_FALSE(c.communication_error());
  // The manual's numbering would count each of those replies as wrongly numbered.
  auto strict = make_controller(kRun);
  PcResponder pc2;
  pc2.run(strict, 5);
  pc2.fill = pc.fill;
  pc2.run(strict, 10);
  EXPECT_TRUE(strict.communication_error());
}

}  // namespace
}  // namespace axon::c4g::sim::test
