// Fault plans: YAML form, events at their time, stalled and lossy links.
#include "board_harness.hpp"

#include "axon/core/config.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

using namespace axon;
using namespace axon::blmc;
using namespace axon::blmc::sim;
using namespace axon::blmc::sim::test;
using protocol::ErrorCode;
using protocol::MessageId;

namespace {

BoardFaultPlan parse(std::string_view yaml) {
  auto node = core::ConfigNode::load_string(yaml);
  EXPECT_TRUE(node) << node.error().message();
  auto plan = BoardFaultPlan::from_config(node.value());
  EXPECT_TRUE(plan) << plan.error().message();
  return plan ? plan.value() : BoardFaultPlan{};
}

}  // namespace

TEST(BlmcFaultPlan, ReadsEveryKindFromYaml) {
  const auto plan = parse(R"(
seed: 42
events:
  - { at_s: 2.0, kind: encoder }
  - { at_s: 5.0, kind: over_current, duration_s: 1.5 }
  - { at_s: 9.0, kind: pos_converter, persistent: true }
stalls:
  - { from_s: 3.0, until_s: 3.5, direction: tx }
drops:
  - { direction: rx, probability: 0.25, from_s: 1, until_s: 10 }
)");
  EXPECT_EQ(plan.seed, 42u);
  ASSERT_EQ(plan.events.size(), 3u);
  EXPECT_EQ(plan.events[0].at, 2s);
  EXPECT_EQ(plan.events[0].kind, FaultKind::encoder);
  EXPECT_EQ(plan.events[1].duration, 1500ms);
  EXPECT_TRUE(plan.events[2].persistent);
  ASSERT_EQ(plan.stalls.size(), 1u);
  EXPECT_EQ(plan.stalls[0].direction, LinkDirection::tx);
  EXPECT_EQ(plan.stalls[0].until, 3500ms);
  ASSERT_EQ(plan.drops.size(), 1u);
  EXPECT_DOUBLE_EQ(plan.drops[0].probability, 0.25);
  EXPECT_EQ(plan.drops[0].from, 1s);
}

TEST(BlmcFaultPlan, RejectsMistakesWithTheirLocation) {
  for (const char* bad : {"events: [ { at_s: 1, kind: melted } ]", "stalls: [ { from_s: 2, until_s: 1 } ]",
                          "drops: [ { probability: 2 } ]", "evnts: []", "events: [ { at_s: 1, kind: encoder, when: 3 } ]"}) {
    auto node = core::ConfigNode::load_string(bad, "plan.yaml");
    ASSERT_TRUE(node);
    auto plan = BoardFaultPlan::from_config(node.value());
    ASSERT_FALSE(plan) << bad;
    EXPECT_NE(plan.error().message().find("plan.yaml:"), std::string::npos) << plan.error().message();
  }
}

TEST(BlmcFaultPlan, EncoderErrorAtItsTime) {
  BoardHarness h({}, parse("events: [ { at_s: 0.5, kind: encoder } ]"));
  h.command("ENABLE_SYS=1");
  h.run_until(499ms);
  EXPECT_EQ(h.board.status().error, ErrorCode::none);
  EXPECT_TRUE(h.board.status().system_enabled);
  h.run_until(500ms);
  EXPECT_EQ(h.board.status().error, ErrorCode::encoder);
  EXPECT_FALSE(h.board.status().system_enabled);
  h.run_until(1000ms);
  EXPECT_EQ(h.statuses().back().error, ErrorCode::encoder);
}

TEST(BlmcFaultPlan, PersistentFaultNeedsAPowerCycle) {
  BoardHarness h({}, parse("events: [ { at_s: 0.1, kind: pos_converter, persistent: true } ]"));
  h.run_until(200ms);
  h.command("ENABLE_SYS=1");
  h.run_for(1ms);
  EXPECT_EQ(h.board.status().error, ErrorCode::pos_converter);
  h.board.power_cycle();
  h.command("ENABLE_SYS=1");
  h.run_for(1ms);
  EXPECT_EQ(h.board.status().error, ErrorCode::none);
  EXPECT_TRUE(h.board.status().system_enabled);
}

TEST(BlmcFaultPlan, TransmitStallSendsNothingInTheWindow) {
  BoardHarness h({}, parse("stalls: [ { from_s: 0.9, until_s: 2.1, direction: tx } ]"));
  h.command("ENABLE_SYS=1");
  h.command("SEND_POSITION=1");
  h.run_until(3000ms);
  for (const auto& s : h.sent) EXPECT_TRUE(s.at < 900ms || s.at >= 2100ms);
  EXPECT_EQ(h.statuses().size(), 2u);  // 0 s and 3 s
  EXPECT_EQ(h.board.stats().tx_stalled, 1200u + 2u);
  EXPECT_TRUE(h.board.status().system_enabled);  // the board itself carried on
}

TEST(BlmcFaultPlan, ReceiveStallHearsNothingAndTriggersTheTimeout) {
  BoardHarness h({}, parse("stalls: [ { from_s: 2.5, until_s: 2.6, direction: rx } ]"));
  h.enable_and_align();
  h.command("SET_CAN_RECV_TIMEOUT=20");
  // A host sending IqRef every millisecond; the board hears none of them within the window.
  while (h.now < 2700ms && h.board.status().error == ErrorCode::none) {
    h.iq_ref(0.1);
    h.run_for(1ms);
  }
  EXPECT_EQ(h.board.status().error, ErrorCode::can_recv_timeout);
  EXPECT_GE(h.now, 2520ms);
  EXPECT_LE(h.now, 2523ms);
  EXPECT_GT(h.board.stats().rx_stalled, 15u);
}

TEST(BlmcFaultPlan, SeededDropsAreReproducible) {
  const auto plan = parse("seed: 7\ndrops: [ { direction: tx, probability: 0.5 } ]");
  std::vector<std::size_t> counts;
  std::vector<std::vector<BoardTime>> times;
  for (int run = 0; run < 2; ++run) {
    BoardHarness h({}, plan);
    h.command("ENABLE_SYS=1");
    h.command("SEND_CURRENT=1");
    h.run_until(1000ms);
    std::vector<BoardTime> t;
    for (const auto& s : h.sent) t.push_back(s.at);
    times.push_back(t);
    EXPECT_EQ(h.board.stats().tx_dropped + h.sent.size(), 1001u + 2u);  // cycles 0..1000, 2 status
    counts.push_back(h.sent.size());
  }
  EXPECT_EQ(times[0], times[1]);
  EXPECT_GT(counts[0], 400u);
  EXPECT_LT(counts[0], 600u);
}

// `axon sim blmc --fault-plan`: a list of plans, some for one board (`board: N`), some for all.
TEST(BlmcFaultPlan, LoadsOnePlanPerBoardFromAFile) {
  const auto path = std::filesystem::temp_directory_path() / ("axon_blmc_plans_" + std::to_string(::getpid()) + ".yaml");
  {
    std::ofstream f(path);
    f << "- { board: 1, events: [ { at_s: 4.0, kind: encoder } ] }\n"
         "- { seed: 7, drops: [ { direction: tx, probability: 0.001 } ] }\n";
  }
  auto loaded = load_fault_plans(path.string(), 2);
  ASSERT_TRUE(loaded) << loaded.error().message();
  const auto& plans = loaded.value();
  ASSERT_EQ(plans.size(), 2u);
  EXPECT_TRUE(plans[0].events.empty());
  ASSERT_EQ(plans[1].events.size(), 1u);
  EXPECT_EQ(plans[1].events[0].kind, FaultKind::encoder);
  EXPECT_EQ(plans[0].drops.size(), 1u);
  EXPECT_EQ(plans[1].drops.size(), 1u);
  EXPECT_EQ(plans[0].seed, 7u);
  EXPECT_TRUE(load_fault_plans("", 3).value().size() == 3u);
  auto bad = load_fault_plans(path.string(), 1);  // board 1 of one
  EXPECT_FALSE(bad);
  std::filesystem::remove(path);
}
