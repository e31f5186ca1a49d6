// The simulator's robot from a file: a captured initialization packet or its fields in YAML, with
// the manual's table limits (table 5.1) checked on load.
#include "axon/c4g/sim/robot_file.hpp"
#include "pc_responder.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <string>
#include <unistd.h>

namespace axon::c4g::sim::test {
namespace {

std::string temp_file(const std::string& suffix, const std::string& bytes) {
  const std::string path = ::testing::TempDir() + "/robot_" + std::to_string(::getpid()) + suffix;
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

// Two arms: a four-axis arm (a SCARA) and a single-axis positioner.
constexpr const char* kTwoArms = R"(name: cell
period: 1
arm1OpenAx: [1, 2, 3, 4]
arm1TxRate: [100, -120, 80, 50]
arm1CalData: [0.1, 0.2, 0.3, 0.4]
arm1AzLim: [20, 20, 10, 5]
arm1FollowError: [5, 5, 5, 5]
arm2OpenAx: [1]
arm2TxRate: [60]
arm2AzLim: [8]
)";

TEST(C4gRobotFile, ACapturedInitializationPacketIsTheRobot) {
  std::array<std::byte, P::kInitPacketSize> buf{};
  ASSERT_TRUE(P::encode_init(six_axis_init(), buf));
  const auto path = temp_file(".bin", std::string(reinterpret_cast<const char*>(buf.data()), buf.size()));
  const auto robot = load_robot_file(path);
  ASSERT_TRUE(robot) << robot.error().detail;
  EXPECT_EQ(robot.value().init, six_axis_init());
  EXPECT_FLOAT_EQ(static_cast<float>(robot.value().axes[0][3].current_limit), 9.5f);
  const auto by_name = find_robot(path);  // `axon sim c4g --robot FILE`
  ASSERT_TRUE(by_name) << by_name.error().detail;
  EXPECT_EQ(by_name.value().init, six_axis_init());
  std::remove(path.c_str());
}

TEST(C4gRobotFile, YamlFieldsMakeATwoArmCellThatTheControllerRuns) {
  const auto path = temp_file(".yaml", kTwoArms);
  const auto robot = load_robot_file(path);
  ASSERT_TRUE(robot) << robot.error().detail;
  const auto& init = robot.value().init;
  EXPECT_EQ(robot.value().name, "cell");
  EXPECT_EQ(init.open_axes, 5);  // counted from the lists
  EXPECT_EQ(init.period_ms, 1);
  EXPECT_EQ(init.fields_per_axis, 9);
  EXPECT_FLOAT_EQ(init.transmission_ratio[0][1], -120.0f);
  EXPECT_FLOAT_EQ(init.current_limit[1][0], 8.0f);
  auto c = make_controller("steps:\n  - drive_on\n  - move: {arm: 2, deg: [10], duration: 0.1}\n", robot.value());
  EXPECT_EQ(c.axis_count(), 5u);
  PcResponder pc;
  for (int i = 0; i < 500 && !c.finished(); ++i) pc.tick(c);
  EXPECT_TRUE(c.scenario_done()) << c.scenario_error();
  ASSERT_EQ(c.joint_degrees(2).size(), 1u);
  EXPECT_NEAR(c.joint_degrees(2)[0], 10.0, 0.1);
  std::remove(path.c_str());
}

TEST(C4gRobotFile, TheManualsTableLimitsAndTheFieldsAreCheckedOnLoad) {
  auto refused = [](const std::string& yaml, std::string_view why) {
    auto init = init_from_yaml(yaml);
    if (!init) return init.error().detail.find(why) != std::string::npos ? std::string() : init.error().detail;
    auto robot = robot_from_init(init.value(), "bad");
    if (robot) return std::string("accepted");
    return robot.error().detail.find(why) != std::string::npos ? std::string() : robot.error().detail;
  };
  // 3 arms of 7 axes: 21 open axes, the table allows 20.
  std::string many;
  for (int arm = 1; arm <= 3; ++arm)
    many += "arm" + std::to_string(arm) + "OpenAx: [1, 2, 3, 4, 5, 6, 7]\narm" + std::to_string(arm) + "TxRate: [1, 1, 1, 1, 1, 1, 1]\n";
  EXPECT_EQ(refused(many, "21 open axes; at most 20 (table 5.1)"), "");
  EXPECT_EQ(refused("arm1OpenAx: [1, 2]\narm1TxRate: [10, 0]\n", "transmission ratio"), "");
  EXPECT_EQ(refused("arm1OpenAx: [1, 3]\narm1TxRate: [10, 0, 5]\n", "ratio 0"), "");  // a gap below an open axis
  EXPECT_EQ(refused("arm1OpenAx: [1]\narm1TxRate: [10]\nnAxOpen: 3\n", "nAxOpen is 3 but the open-axis lists name 1"), "");
  EXPECT_EQ(refused("arm1OpenAx: [1]\narm1TxRate: [10]\narm1Ratio: [1]\n", "not a field of the initialization packet"), "");
  EXPECT_EQ(refused("arm1OpenAx: [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11]\n", "at most 10 values"), "");
  EXPECT_EQ(refused("period: 2\n", "no open axis"), "");
  EXPECT_EQ(refused("arm1OpenAx: [1]\narm1TxRate: [10]\nperiod: 11\n", "period = 11 ms"), "");
  // Found by the 30-minute fuzz run: a number too large for its integer field was cast (undefined
  // behaviour; UBSan stopped the fuzzer). Now every value must fit its field's type.
  EXPECT_EQ(refused("arm1OpenAx: [999999999999999999999999999999999999999999999991, 2]\narm1TxRate: [10, 10]\n",
                    "does not fit the field's type (a signed integer)"), "");
  EXPECT_EQ(refused("arm1OpenAx: [1.5]\narm1TxRate: [10]\n", "1.5 does not fit"), "");
  EXPECT_EQ(refused("arm1OpenAx: [1]\narm1TxRate: [1e300]\n", "does not fit the field's type (a 32-bit float)"), "");
  const auto missing = load_robot_file("/nonexistent/robot.yaml");
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().detail.find("cannot be opened"), std::string::npos);
}

}  // namespace
}  // namespace axon::c4g::sim::test
