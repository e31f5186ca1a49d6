// The cold-temperature policy at and around its thresholds.
#include "axon/fps/plc/cold_policy.hpp"

#include <gtest/gtest.h>

namespace axon::fps::plc {
namespace {

ColdDecision at(std::vector<SensorReading> t, const ColdPolicyConfig& c = {}) { return cold_policy(t, c); }
SensorReading temp(const char* name, std::optional<double> v) { return SensorReading{name, v, "degC"}; }

TEST(ColdPolicy, WarmIsNormalOperation) {
  const auto d = at({temp("a", 12.0), temp("b", 3.0)});
  EXPECT_EQ(d.settings, (ColdSettings{5000, 0.0, 30.0, false, false}));
  EXPECT_EQ(d.coldest_sensor, "b");
  EXPECT_NE(d.report().find("speed 5000 rpm"), std::string::npos) << d.report();
}

TEST(ColdPolicy, ZeroIsNotBelowZero) {
  EXPECT_FALSE(at({temp("a", 0.0)}).settings.speed_limited);
  const auto d = at({temp("a", 5.0), temp("b", -0.1)});
  EXPECT_TRUE(d.settings.speed_limited);
  EXPECT_EQ(d.settings.motor_rpm, 3000u);
  EXPECT_FALSE(d.settings.heating);
  EXPECT_EQ(d.settings.alpha_holding_pct, 0.0);
  EXPECT_NE(d.report().find("limited"), std::string::npos) << d.report();
}

TEST(ColdPolicy, BelowMinusTenHeatsAlphaAndKeepsBeta) {
  EXPECT_FALSE(at({temp("a", -10.0)}).settings.heating);
  const auto d = at({temp("a", -10.1)});
  EXPECT_EQ(d.settings, (ColdSettings{3000, 45.0, 30.0, true, true}));
  EXPECT_NE(d.report().find("alpha holding current 45 %"), std::string::npos) << d.report();
}

TEST(ColdPolicy, FaultySensorsAreIgnoredAndNoReadingMeansColdestCase) {
  auto d = at({temp("a", std::nullopt), temp("b", 20.0)});
  EXPECT_FALSE(d.settings.speed_limited);
  EXPECT_EQ(d.coldest_sensor, "b");
  d = at({temp("a", std::nullopt)});
  EXPECT_FALSE(d.coldest_c.has_value());
  EXPECT_TRUE(d.settings.speed_limited);
  EXPECT_TRUE(d.settings.heating);
  EXPECT_NE(d.report().find("no valid temperature"), std::string::npos) << d.report();
  EXPECT_TRUE(at({}).settings.heating);
}

TEST(ColdPolicy, ConfiguredSensorsThresholdsAndValues) {
  auto node = core::ConfigNode::load_string(
      "limit_speed_below_c: 2\ncold_motor_rpm: 2500\nheat_below_c: -5\ncold_alpha_holding_pct: 50\n"
      "sensors: [plate]\n",
      "cold.yaml");
  ASSERT_TRUE(node.has_value());
  auto c = ColdPolicyConfig::from_config(node.value());
  ASSERT_TRUE(c.has_value()) << c.error().message();
  // The air sensor is colder but does not count.
  auto d = at({temp("plate", 1.0), temp("air", -20.0)}, c.value());
  EXPECT_EQ(d.settings, (ColdSettings{2500, 0.0, 30.0, true, false}));
  d = at({temp("plate", -6.0)}, c.value());
  EXPECT_EQ(d.settings.alpha_holding_pct, 50.0);
  auto bad = core::ConfigNode::load_string("beta_holding_pct: 130\n", "cold.yaml");
  EXPECT_FALSE(ColdPolicyConfig::from_config(bad.value()).has_value());
  auto typo = core::ConfigNode::load_string("heat_below: -5\n", "cold.yaml");
  EXPECT_FALSE(ColdPolicyConfig::from_config(typo.value()).has_value());
}

}  // namespace
}  // namespace axon::fps::plc
