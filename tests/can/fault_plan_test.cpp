// Fault plans: reading them from YAML (with errors that point at the offending line) and the
// injector's decisions, frame by frame.
#include "axon/can/fault_plan.hpp"
#include "frame_text.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

using namespace axon;
using namespace axon::can;

namespace {

using axon::can::test::F;

FaultRule rule(FaultRule::Action action) {
  FaultRule r;
  r.action = action;
  return r;
}

FaultPlan plan_of(std::vector<FaultRule> rules, std::uint64_t seed = 1) {
  FaultPlan p;
  p.rules = std::move(rules);
  p.seed = seed;
  return p;
}

Result<FaultPlan> parse(std::string_view yaml) {
  auto node = core::ConfigNode::load_string(yaml, "faults.yaml");
  if (!node) return node.error();
  return FaultPlan::from_config(node.value());
}

// Which of `n` identical frames a plan drops, as a string of '.' (passed) and 'x' (dropped).
std::string drop_pattern(FaultInjector& inj, int n, const Frame& f = Frame{}) {
  std::string out;
  for (int i = 0; i < n; ++i) out += inj.apply(f).drop ? 'x' : '.';
  return out;
}

}  // namespace

// ---- injector ----

TEST(FaultInjector, EmptyPlanChangesNothing) {
  FaultInjector inj;
  EXPECT_TRUE(inj.empty());
  const auto d = inj.apply(F("123#DEADBEEF"));
  EXPECT_FALSE(d.drop);
  EXPECT_FALSE(d.duplicate);
  EXPECT_FALSE(d.corrupted);
  EXPECT_EQ(d.delay, core::Duration::zero());
  EXPECT_EQ(d.frame, F("123#DEADBEEF"));
}

TEST(FaultInjector, EachAction) {
  auto delay = rule(FaultRule::Action::delay);
  delay.delay = std::chrono::milliseconds(5);
  FaultInjector d(plan_of({delay}));
  EXPECT_EQ(d.apply(F("001#")).delay, std::chrono::milliseconds(5));

  FaultInjector dup(plan_of({rule(FaultRule::Action::duplicate)}));
  EXPECT_TRUE(dup.apply(F("001#")).duplicate);

  FaultInjector drop(plan_of({rule(FaultRule::Action::drop)}));
  EXPECT_TRUE(drop.apply(F("001#")).drop);
}

TEST(FaultInjector, MatchesOnlyFilteredFrames) {
  auto r = rule(FaultRule::Action::drop);
  r.match = Filter{0x123, 0x7FF, Filter::Format::standard};
  FaultInjector inj(plan_of({r}));
  EXPECT_TRUE(inj.apply(F("123#")).drop);
  EXPECT_FALSE(inj.apply(F("124#")).drop);
  EXPECT_FALSE(inj.apply(F("00000123#")).drop);
}

TEST(FaultInjector, SkipThenCount) {
  auto r = rule(FaultRule::Action::drop);
  r.skip = 2;
  r.count = 3;
  FaultInjector inj(plan_of({r}));
  EXPECT_EQ(drop_pattern(inj, 8), "..xxx...");
}

TEST(FaultInjector, SkipCountsOnlyMatchingFrames) {
  auto r = rule(FaultRule::Action::drop);
  r.match = Filter{0x100, 0x7FF};
  r.skip = 1;
  r.count = 1;
  FaultInjector inj(plan_of({r}));
  EXPECT_FALSE(inj.apply(F("100#")).drop);  // skipped
  EXPECT_FALSE(inj.apply(F("200#")).drop);  // does not match, does not count
  EXPECT_TRUE(inj.apply(F("100#")).drop);
  EXPECT_FALSE(inj.apply(F("100#")).drop);  // count used up
}

TEST(FaultInjector, CorruptFlipsPayloadBits) {
  auto r = rule(FaultRule::Action::corrupt);
  r.corrupt_xor = 0x0F;
  FaultInjector inj(plan_of({r}));
  auto in = F("123#00FF5A");
  in.set_timestamp(core::WallTime(42));
  const auto d = inj.apply(in);
  EXPECT_TRUE(d.corrupted);
  EXPECT_FALSE(d.drop);
  EXPECT_EQ(d.frame, F("123#0FF055"));
  EXPECT_EQ(d.frame.timestamp(), core::WallTime(42));
}

TEST(FaultInjector, RemoteAndEmptyFramesAreNotCorrupted) {
  auto corrupt = rule(FaultRule::Action::corrupt);
  corrupt.count = 1;
  FaultInjector inj(plan_of({corrupt}));
  for (const char* t : {"123#R8", "123#"}) {
    const auto d = inj.apply(F(t));
    EXPECT_FALSE(d.corrupted) << t;
    EXPECT_EQ(d.frame, F(t)) << t;
  }
  // Those frames did not use up the rule's single shot.
  EXPECT_TRUE(inj.apply(F("123#01")).corrupted);
}

TEST(FaultInjector, FirstRuleThatFiresDecides) {
  auto drop_first = rule(FaultRule::Action::drop);
  drop_first.count = 1;
  FaultInjector inj(plan_of({drop_first, rule(FaultRule::Action::duplicate)}));
  const auto a = inj.apply(F("100#"));
  EXPECT_TRUE(a.drop);
  EXPECT_FALSE(a.duplicate);
  const auto b = inj.apply(F("100#"));
  EXPECT_FALSE(b.drop);
  EXPECT_TRUE(b.duplicate);
}

TEST(FaultInjector, ProbabilityIsReproducibleWithTheSameSeed) {
  auto r = rule(FaultRule::Action::drop);
  r.probability = 0.3;
  FaultInjector a(plan_of({r}, 7)), b(plan_of({r}, 7)), c(plan_of({r}, 8));
  const auto pa = drop_pattern(a, 1000), pb = drop_pattern(b, 1000), pc = drop_pattern(c, 1000);
  EXPECT_EQ(pa, pb);
  EXPECT_NE(pa, pc);
  const auto dropped = std::count(pa.begin(), pa.end(), 'x');
  EXPECT_GT(dropped, 200);  // 300 expected; the seed fixes the actual number
  EXPECT_LT(dropped, 400);
}

TEST(FaultInjector, ProbabilityZeroNeverFires) {
  auto r = rule(FaultRule::Action::drop);
  r.probability = 0.0;
  FaultInjector inj(plan_of({r}));
  EXPECT_EQ(drop_pattern(inj, 50), std::string(50, '.'));
}

// ---- YAML ----

TEST(FaultPlanConfig, ReadsEveryField) {
  auto plan = parse(R"(
seed: 42
rules:
  - action: drop
    id: 0x123
    mask: 0x7F0
    format: standard
    skip: 2
    count: 1
    probability: 0.5
  - action: delay
    delay_ms: 2.5
  - action: duplicate
    id: 0x18FF0001
  - action: corrupt
    xor: 0x01
)");
  ASSERT_TRUE(plan.has_value()) << plan.error().message();
  const auto& p = plan.value();
  EXPECT_EQ(p.seed, 42u);
  ASSERT_EQ(p.rules.size(), 4u);
  const auto& r0 = p.rules[0];
  EXPECT_EQ(r0.action, FaultRule::Action::drop);
  EXPECT_EQ(r0.match.id, 0x123u);
  EXPECT_EQ(r0.match.mask, 0x7F0u);
  EXPECT_EQ(r0.match.format, Filter::Format::standard);
  EXPECT_EQ(r0.skip, 2u);
  EXPECT_EQ(r0.count, 1u);
  EXPECT_EQ(r0.probability, 0.5);
  EXPECT_EQ(p.rules[1].action, FaultRule::Action::delay);
  EXPECT_EQ(p.rules[1].delay, std::chrono::microseconds(2500));
  EXPECT_EQ(p.rules[1].match.mask, 0u);  // no id: every frame
  EXPECT_EQ(p.rules[2].match.id, 0x18FF0001u);
  EXPECT_EQ(p.rules[2].match.mask, Frame::kMaxExtendedId);  // an id alone: exactly that id
  EXPECT_EQ(p.rules[3].corrupt_xor, 0x01);
}

TEST(FaultPlanConfig, EmptyPlan) {
  auto plan = parse("seed: 3\n");
  ASSERT_TRUE(plan.has_value());
  EXPECT_TRUE(plan.value().rules.empty());
  EXPECT_EQ(plan.value().seed, 3u);
}

struct BadPlan {
  const char* yaml;
  CoreErrc code;
  const char* where;  // must appear in the message: file:line and the key path
};

class FaultPlanConfigErrors : public ::testing::TestWithParam<BadPlan> {};

TEST_P(FaultPlanConfigErrors, NameFileLineAndKey) {
  const auto& c = GetParam();
  auto plan = parse(c.yaml);
  ASSERT_FALSE(plan.has_value()) << c.yaml;
  EXPECT_EQ(plan.error(), c.code) << plan.error().message();
  EXPECT_NE(plan.error().detail.find(c.where), std::string::npos) << plan.error().detail;
}

INSTANTIATE_TEST_SUITE_P(
    Cases, FaultPlanConfigErrors,
    ::testing::Values(
        BadPlan{"rules:\n  - action: drop\n  - action: explode\n", CoreErrc::config_bad_value, "faults.yaml:3:"},
        BadPlan{"rules:\n  - action: drop\n  - action: explode\n", CoreErrc::config_bad_value, "rules[1].action"},
        BadPlan{"rules:\n  - action: drop\n    idd: 0x10\n", CoreErrc::config_unknown_key, "faults.yaml:3:"},
        BadPlan{"rules:\n  - action: drop\n    idd: 0x10\n", CoreErrc::config_unknown_key, "rules[0].idd"},
        BadPlan{"sead: 1\n", CoreErrc::config_unknown_key, "sead"},
        BadPlan{"rules:\n  - id: 0x10\n", CoreErrc::config_missing_key, "rules[0].action"},
        BadPlan{"rules:\n  - action: drop\n    probability: 1.5\n", CoreErrc::config_bad_value,
                "faults.yaml:3:"},
        BadPlan{"rules:\n  - action: drop\n    id: 0x20000000\n", CoreErrc::config_bad_value, "rules[0].id"},
        BadPlan{"rules:\n  - action: drop\n    count: 0\n", CoreErrc::config_bad_value, "rules[0].count"},
        BadPlan{"rules:\n  - action: drop\n    xor: 0xFF\n", CoreErrc::config_bad_value, "rules[0].xor"},
        BadPlan{"rules:\n  - action: corrupt\n    xor: 0\n", CoreErrc::config_bad_value, "rules[0].xor"},
        BadPlan{"rules:\n  - action: delay\n", CoreErrc::config_missing_key, "rules[0].delay_ms"},
        BadPlan{"rules:\n  - action: delay\n    delay_ms: -1\n", CoreErrc::config_bad_value, "faults.yaml:3:"},
        BadPlan{"rules:\n  - action: duplicate\n    delay_ms: 1\n", CoreErrc::config_bad_value, "rules[0].delay_ms"},
        BadPlan{"rules:\n  - action: drop\n    format: fd\n", CoreErrc::config_bad_value, "rules[0].format"},
        BadPlan{"rules:\n  - action: drop\n    skip: -1\n", CoreErrc::config_bad_value, "rules[0].skip"},
        BadPlan{"rules:\n  - drop\n", CoreErrc::config_bad_value, "rules[0]"},
        BadPlan{"rules: drop\n", CoreErrc::config_bad_value, "rules"},
        BadPlan{"seed: -3\n", CoreErrc::config_bad_value, "seed"}));
