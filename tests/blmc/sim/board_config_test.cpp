// Board and motor configuration from YAML.
#include "axon/blmc/sim/board_config.hpp"

#include <gtest/gtest.h>

using namespace axon;
using namespace axon::blmc::sim;
using namespace std::chrono_literals;

TEST(BlmcBoardConfig, YamlOverridesDefaultsPerMotor) {
  auto node = core::ConfigNode::load_string(R"(
motor: { torque_constant_nm_per_a: 0.03, load: { inertia_kgm2: 1.0e-5 } }
motors:
  - { index_offset_rev: 0.25 }
  - { current_limit_a: 5, coulomb_friction_nm: 0 }
adc: [ { kind: constant, offset: 0.1 }, { kind: sine, offset: 0.5, amplitude: 0.2, frequency_hz: 2 } ]
alignment_s: 0.5
over_current_trip_a: 10
data_while_disabled: true
)");
  ASSERT_TRUE(node);
  auto c = BoardConfig::from_config(node.value());
  ASSERT_TRUE(c) << c.error().message();
  const auto& b = c.value();
  EXPECT_DOUBLE_EQ(b.motors[0].torque_constant_nm_per_a, 0.03);
  EXPECT_DOUBLE_EQ(b.motors[1].torque_constant_nm_per_a, 0.03);
  EXPECT_DOUBLE_EQ(b.motors[1].load.inertia_kgm2, 1.0e-5);
  EXPECT_DOUBLE_EQ(b.motors[0].index_offset_rev, 0.25);
  EXPECT_DOUBLE_EQ(b.motors[1].index_offset_rev, 0.0);
  EXPECT_DOUBLE_EQ(b.motors[1].current_limit_a, 5.0);
  EXPECT_DOUBLE_EQ(b.motors[0].current_limit_a, MotorConfig{}.current_limit_a);
  EXPECT_EQ(b.adc[1].kind, AdcSignal::Kind::sine);
  EXPECT_DOUBLE_EQ(b.adc[0].value(3.0), 0.1);
  EXPECT_EQ(b.alignment_time, 500ms);
  EXPECT_DOUBLE_EQ(b.over_current_trip_a, 10.0);
  EXPECT_TRUE(b.data_while_disabled);
}

TEST(BlmcBoardConfig, UnknownOrBadKeysAreErrorsWithALocation) {
  for (const char* bad : {"motor: { torque_constant: 1 }", "motor: { rotor_inertia_kgm2: -1 }", "alignment_s: 100",
                          "adc: [ { kind: square } ]", "motors: [ {}, {}, {} ]", "colour: red"}) {
    auto node = core::ConfigNode::load_string(bad, "board.yaml");
    ASSERT_TRUE(node);
    auto c = BoardConfig::from_config(node.value());
    ASSERT_FALSE(c) << bad;
    EXPECT_NE(c.error().message().find("board.yaml:"), std::string::npos) << c.error().message();
  }
}

TEST(BlmcAdcSignal, SineIsClampedToTheConverterRange) {
  const AdcSignal s{AdcSignal::Kind::sine, 0.5, 0.8, 1.0, 0.0};
  EXPECT_DOUBLE_EQ(s.value(0.25), 1.0);
  EXPECT_DOUBLE_EQ(s.value(0.75), 0.0);
  EXPECT_NEAR(s.value(0.0), 0.5, 1e-12);
}
