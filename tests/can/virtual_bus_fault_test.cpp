// A fault plan applied by the virtual bus: what the receivers get and what the medium counts.
#include "axon/can/virtual_bus.hpp"
#include "frame_text.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/io_context.hpp>
#include <gtest/gtest.h>

#include <string>
#include <vector>

using namespace axon;
using namespace axon::can;

namespace {

using Strings = std::vector<std::string>;

using axon::can::test::F;

FaultPlan one_rule(FaultRule::Action action, std::uint32_t id, core::Duration delay = {}) {
  FaultRule r;
  r.action = action;
  r.match = Filter{id, 0x7FF};
  r.delay = delay;
  FaultPlan p;
  p.rules.push_back(r);
  return p;
}

struct Rig {
  asio::io_context io;
  std::shared_ptr<VirtualBus> medium;
  std::unique_ptr<Bus> tx, rx;

  explicit Rig(WireModel wire = {}) : medium(VirtualBus::create(io.get_executor(), "vcan0", wire)) {
    tx = medium->attach("tx");
    rx = medium->attach("rx");
  }
  Strings send(const Strings& frames) {
    asio::co_spawn(io, [&]() -> asio::awaitable<void> {
      for (const auto& t : frames) (void)co_await tx->send(Frame::parse(t).value());
    }, asio::detached);
    io.run();
    io.restart();
    Strings out;
    while (auto f = rx->try_receive()) out.push_back(f->to_string());
    return out;
  }
};

}  // namespace

TEST(VirtualBusFaults, DropLosesTheFrameForEveryone) {
  Rig rig;
  auto other = rig.medium->attach("other");
  rig.medium->set_fault_plan(one_rule(FaultRule::Action::drop, 0x200));
  EXPECT_EQ(rig.send({"100#", "200#", "300#"}), (Strings{"100#", "300#"}));
  EXPECT_EQ(other->pending(), 2u);
  EXPECT_EQ(rig.medium->stats().fault_dropped, 1u);
  EXPECT_EQ(rig.tx->stats().frames_out, 3u);  // the sender did send it
}

TEST(VirtualBusFaults, DuplicateDeliversTwice) {
  Rig rig;
  rig.medium->set_fault_plan(one_rule(FaultRule::Action::duplicate, 0x100));
  EXPECT_EQ(rig.send({"100#01", "200#02"}), (Strings{"100#01", "100#01", "200#02"}));
  EXPECT_EQ(rig.medium->stats().fault_duplicated, 1u);
  EXPECT_EQ(rig.medium->stats().frames, 3u);  // the repeat went on the wire too
}

TEST(VirtualBusFaults, DelayLetsLaterFramesOvertake) {
  Rig rig;
  rig.medium->set_fault_plan(one_rule(FaultRule::Action::delay, 0x100, std::chrono::milliseconds(2)));
  EXPECT_EQ(rig.send({"100#", "200#", "300#"}), (Strings{"200#", "300#", "100#"}));
  EXPECT_EQ(rig.medium->stats().fault_delayed, 1u);
}

TEST(VirtualBusFaults, DelayedFramesKeepTheirOrderAmongThemselves) {
  Rig rig;
  FaultRule r;
  r.action = FaultRule::Action::delay;
  r.delay = std::chrono::milliseconds(1);
  r.match = Filter{0x100, 0x700};
  FaultPlan p;
  p.rules.push_back(r);
  rig.medium->set_fault_plan(p);
  EXPECT_EQ(rig.send({"101#", "200#", "102#", "103#"}), (Strings{"200#", "101#", "102#", "103#"}));
  EXPECT_EQ(rig.medium->stats().fault_delayed, 3u);
}

TEST(VirtualBusFaults, CorruptFlipsWhatReceiversSee) {
  Rig rig;
  rig.medium->set_fault_plan(one_rule(FaultRule::Action::corrupt, 0x100));
  EXPECT_EQ(rig.send({"100#00F0", "100#R2", "200#00"}), (Strings{"100#FF0F", "100#R2", "200#00"}));
  EXPECT_EQ(rig.medium->stats().fault_corrupted, 1u);
}

TEST(VirtualBusFaults, PlanFromYamlWithSkipAndCount) {
  Rig rig;
  auto node = core::ConfigNode::load_string("rules:\n  - action: drop\n    skip: 1\n    count: 2\n").value();
  rig.medium->set_fault_plan(FaultPlan::from_config(node).value());
  EXPECT_EQ(rig.send({"001#", "002#", "003#", "004#", "005#"}), (Strings{"001#", "004#", "005#"}));
}

TEST(VirtualBusFaults, SameSeedSameLosses) {
  auto run = [](std::uint64_t seed) {
    Rig rig;
    FaultRule r;
    r.probability = 0.5;
    FaultPlan p;
    p.rules.push_back(r);
    p.seed = seed;
    rig.medium->set_fault_plan(p);
    Strings frames;
    for (int i = 0; i < 64; ++i) frames.push_back(Frame::standard(static_cast<std::uint32_t>(i), {}).value().to_string());
    return rig.send(frames);
  };
  EXPECT_EQ(run(5), run(5));
  EXPECT_NE(run(5), run(6));
}

TEST(VirtualBusFaults, PacedDropStillOccupiesTheWire) {
  WireModel wire;
  wire.pace_realtime = true;
  Rig rig(wire);
  rig.medium->set_fault_plan(one_rule(FaultRule::Action::drop, 0x100));
  EXPECT_EQ(rig.send({"100#1122", "200#"}), (Strings{"200#"}));
  EXPECT_EQ(rig.medium->stats().bits, frame_bits(F("100#1122")).total + frame_bits(F("200#")).total);
}
