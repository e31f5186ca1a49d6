// Scenario files: the steps and the errors, located by file, line and column.
#include "axon/c4g/sim/scenario.hpp"

#include <gtest/gtest.h>

namespace axon::c4g::sim {
namespace {

std::string error_of(std::string_view yaml) {
  auto s = Scenario::parse(yaml, "bad.yaml");
  EXPECT_FALSE(s.has_value());
  return s ? std::string() : s.error().detail;
}

TEST(C4gSimScenario, ParsesEveryStep) {
  auto s = Scenario::parse(
      "name: demo\nsteps:\n"
      "  - drive_on\n"
      "  - go_open: {type: B, mode: \"0'\", arms: [1]}\n"
      "  - go_open: {mode: mode7}\n"
      "  - move: {arm: 1, deg: [10, null, 5], duration: 2}\n"
      "  - wait_for_pc: {timeout: 3}\n"
      "  - delay: 0.5\n"
      "  - cmd: {arm: 1, value: 3}\n"
      "  - freeze_passive: 0.2\n"
      "  - restart\n"
      "  - drive_off: {arms: [1]}\n"
      "  - exit_open\n",
      "ok.yaml");
  ASSERT_TRUE(s.has_value()) << s.error().detail;
  const auto& st = s.value().steps;
  ASSERT_EQ(st.size(), 11u);
  EXPECT_EQ(s.value().name, "demo");
  EXPECT_EQ(st[1].kind, StepKind::go_open);
  EXPECT_EQ(st[1].mode, 10);
  EXPECT_EQ(st[1].type, OpenType::b);
  EXPECT_EQ(st[2].mode, 7);
  EXPECT_EQ(st[2].type, OpenType::a);
  EXPECT_EQ(st[3].deg.size(), 3u);
  EXPECT_FALSE(st[3].deg[1].has_value());
  EXPECT_DOUBLE_EQ(*st[3].deg[2], 5.0);
  EXPECT_DOUBLE_EQ(st[4].seconds, 3.0);
  EXPECT_EQ(st[6].value, 3);
  EXPECT_EQ(st[9].arms, std::vector<int>{1});
  EXPECT_EQ(st[3].where, "ok.yaml:6:5");
}

TEST(C4gSimScenario, ErrorsNameFileLineAndColumn) {
  auto has = [](const std::string& text, std::string_view part) { return text.find(part) != std::string::npos; };
  const auto unknown = error_of("steps:\n  - drive_on\n  - jump: 3\n");
  EXPECT_TRUE(has(unknown, "bad.yaml:3:5")) << unknown;
  EXPECT_TRUE(has(unknown, "unknown step 'jump'")) << unknown;
  const auto mode = error_of("steps:\n  - go_open: {type: A, mode: 6}\n");
  EXPECT_TRUE(has(mode, "bad.yaml:2:30")) << mode;
  EXPECT_TRUE(has(mode, "cannot be opened")) << mode;
  const auto nomode = error_of("steps:\n  - go_open: {type: A, mode: 77}\n");
  EXPECT_TRUE(has(nomode, "unknown mode '77'")) << nomode;
  const auto type = error_of("steps:\n  - go_open: {type: C, mode: 4}\n");
  EXPECT_TRUE(has(type, "type is A or B")) << type;
  const auto key = error_of("steps:\n  - move: {deg: [1], duration: 1, speed: 3}\n");
  EXPECT_TRUE(has(key, "speed")) << key;
  const auto dur = error_of("steps:\n  - move: {deg: [1], duration: 0}\n");
  EXPECT_TRUE(has(dur, "duration > 0")) << dur;
  const auto cmd = error_of("steps:\n  - cmd: {arm: 1, value: 300}\n");
  EXPECT_TRUE(has(cmd, "bad.yaml:2:26")) << cmd;
  const auto last = error_of("steps:\n  - run\n  - drive_on\n");
  EXPECT_TRUE(has(last, "must be the last step")) << last;
  const auto arm = error_of("steps:\n  - drive_on: {arms: [5]}\n");
  EXPECT_TRUE(has(arm, "an arm is 1..4")) << arm;
  const auto syntax = error_of("steps: [\n");
  EXPECT_TRUE(has(syntax, "bad.yaml")) << syntax;
  const auto delay = error_of("steps:\n  - delay\n");
  EXPECT_TRUE(has(delay, "needs seconds")) << delay;
}

TEST(C4gSimScenario, DefaultScenarioParses) {
  const auto s = Scenario::default_scenario();
  ASSERT_EQ(s.steps.size(), 5u);
  EXPECT_EQ(s.steps.front().kind, StepKind::drive_on);
  EXPECT_EQ(s.steps.back().kind, StepKind::run);
}

}  // namespace
}  // namespace axon::c4g::sim
