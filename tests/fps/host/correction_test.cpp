// Correction moves, the pure part: measurement files and the angles a measured miss leads to.
#include "axon/fps/host/correction.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::host;

namespace {

// One robot at the origin, orientation 0, alpha arm 7.4 mm, one fibre on the beta arm's axis 15 mm
// from the beta axis: simple enough to do the kinematics by hand.
plan::CollisionModel hand_model() {
  plan::ArmDesign d;
  d.fibres = {{"axis", {15.0, 0.0}}};
  std::vector<plan::RobotSpec> robots(1);
  robots[0].id = 1;
  return plan::CollisionModel::build(robots, d).value();
}

plan::Target xy_target(std::int32_t robot, plan::Vec2 p, std::string fibre) {
  plan::Target t;
  t.robot = robot;
  t.position = p;
  t.fibre = std::move(fibre);
  return t;
}

MeasurementSet measured(std::int32_t robot, plan::Vec2 p) {
  MeasurementSet m;
  m.source = "m.csv";
  m.items.push_back({robot, p, std::nullopt, 2});
  return m;
}

}  // namespace

TEST(Correction, HandComputedCorrection) {
  const auto model = hand_model();
  // Commanded (90, 90): alpha arm along +y to the beta axis at (0, 7.4); beta arm pointing along
  // 90 + 90 = 180 deg, so the fibre is at (0 - 15, 7.4) = (-15, 7.4). That is the target.
  // The camera finds the fibre 0.1 mm higher, at (-15, 7.5).
  //
  // Inverse kinematics of the measured point (ccw elbow, fibre on the axis so beta = g):
  //   d^2 = 15^2 + 7.5^2 = 281.25, d = 16.770510
  //   cos g = (d^2 - 7.4^2 - 15^2) / (2 * 7.4 * 15) = (281.25 - 54.76 - 225) / 222 = 0.0067117
  //   g = 89.615444 deg -> beta_m = 89.615444
  //   alpha_m = atan2(7.5, -15) - atan2(15 sin g, 7.4 + 15 cos g)
  //           = 153.434949 - atan2(14.999662, 7.500676) = 153.434949 - 63.432368 = 90.002581
  // The target's inverse kinematics is the commanded pose itself, (90, 90), so the correction is
  //   (90 - 90.002581, 90 - 89.615444) = (-0.002581, +0.384556) deg
  // and the new command (90 - 0.002581, 90 + 0.384556) = (89.997419, 90.384556).
  const std::vector targets{xy_target(1, {-15.0, 7.4}, "axis")};
  const auto plan = plan_corrections(model, targets, measured(1, {-15.0, 7.5}), {{1, plan::Pose{90, 90}}});
  ASSERT_EQ(plan.robots.size(), 1u);
  const auto& r = plan.robots[0];
  EXPECT_EQ(r.status, CorrectionStatus::move) << r.detail;
  EXPECT_EQ(r.elbow, plan::Elbow::ccw);
  EXPECT_NEAR(r.error_mm, 0.1, 1e-12);
  EXPECT_NEAR(r.error.y, 0.1, 1e-12);
  EXPECT_NEAR(r.delta.alpha_deg, -0.002581, 1e-6);
  EXPECT_NEAR(r.delta.beta_deg, 0.384556, 1e-6);
  EXPECT_NEAR(r.command.alpha_deg, 89.997419, 1e-6);
  EXPECT_NEAR(r.command.beta_deg, 90.384556, 1e-6);
  EXPECT_FALSE(plan.converged());
  EXPECT_EQ(plan.moves().size(), 1u);
}

TEST(Correction, TheCorrectionIsAddedToWhatWasCommanded) {
  // Same measurement, but the robot was commanded (90.5, 89.5) (say an earlier correction): the
  // same angular difference is added to that command, not to the target's angles.
  const auto model = hand_model();
  const std::vector targets{xy_target(1, {-15.0, 7.4}, "axis")};
  const auto plan = plan_corrections(model, targets, measured(1, {-15.0, 7.5}), {{1, plan::Pose{90.5, 89.5}}});
  const auto& r = plan.robots.at(0);
  ASSERT_EQ(r.status, CorrectionStatus::move) << r.detail;
  EXPECT_NEAR(r.command.alpha_deg, 90.5 - 0.002581, 1e-6);
  EXPECT_NEAR(r.command.beta_deg, 89.5 + 0.384556, 1e-6);
}

TEST(Correction, WithinToleranceIsLeftAlone) {
  const auto model = hand_model();
  const std::vector targets{xy_target(1, {-15.0, 7.4}, "axis")};
  // 3 um in x and y: 4.2 um off, inside the default 5 um.
  auto plan = plan_corrections(model, targets, measured(1, {-15.003, 7.403}), {{1, plan::Pose{90, 90}}});
  EXPECT_EQ(plan.robots.at(0).status, CorrectionStatus::within_tolerance);
  EXPECT_TRUE(plan.converged());
  EXPECT_TRUE(plan.moves().empty());
  // A tighter tolerance makes it a move.
  CorrectionOptions o;
  o.tolerance_mm = 0.001;
  plan = plan_corrections(model, targets, measured(1, {-15.003, 7.403}), {{1, plan::Pose{90, 90}}}, o);
  EXPECT_EQ(plan.robots.at(0).status, CorrectionStatus::move);
}

TEST(Correction, ConstantAngularOffsetIsRemovedInOneStepOnBothElbows) {
  // The robot's arms sit at command + offset; measuring that and correcting once lands the fibre
  // on the target exactly, whichever elbow it uses.
  plan::ArmDesign d;  // the nominal three fibres
  std::vector<plan::RobotSpec> robots(1);
  robots[0].id = 5;
  robots[0].centre = {22.4, -38.8};
  robots[0].calibration.orientation_deg = 17;
  const auto model = plan::CollisionModel::build(robots, d).value();
  const auto& robot = model.robot(0);
  const std::size_t boss = plan::kBossFibre;
  const plan::Pose offset{0.7, -1.1};
  for (const plan::Pose cmd : {plan::Pose{40, 120}, plan::Pose{200, 250}}) {
    const plan::Vec2 target = robot.fibre(cmd, boss);
    const plan::Vec2 seen = robot.fibre({cmd.alpha_deg + offset.alpha_deg, cmd.beta_deg + offset.beta_deg}, boss);
    const std::vector targets{xy_target(5, target, "boss")};
    const auto plan = plan_corrections(model, targets, measured(5, seen), {{5, cmd}});
    const auto& r = plan.robots.at(0);
    ASSERT_EQ(r.status, CorrectionStatus::move) << r.detail;
    EXPECT_EQ(r.elbow, cmd.beta_deg < 180 ? plan::Elbow::ccw : plan::Elbow::cw);
    EXPECT_NEAR(r.delta.alpha_deg, -offset.alpha_deg, 1e-9);
    EXPECT_NEAR(r.delta.beta_deg, -offset.beta_deg, 1e-9);
    const plan::Vec2 after = robot.fibre({r.command.alpha_deg + offset.alpha_deg, r.command.beta_deg + offset.beta_deg}, boss);
    EXPECT_LT(plan::norm(after - target), 1e-9);
  }
}

TEST(Correction, ProblemsAreReportedNotSent) {
  const auto model = hand_model();
  std::vector targets{xy_target(1, {-15.0, 7.4}, "axis")};
  // Measured beyond the arms' reach: no inverse kinematics for it.
  auto plan = plan_corrections(model, targets, measured(1, {-30.0, 7.4}), {{1, plan::Pose{90, 90}}});
  EXPECT_EQ(plan.robots.at(0).status, CorrectionStatus::unreachable);
  EXPECT_NE(plan.robots.at(0).detail.find("measured point"), std::string::npos) << plan.robots.at(0).detail;
  EXPECT_TRUE(plan.moves().empty());
  // A large miss (2 mm) would need more than the 5 deg allowed.
  plan = plan_corrections(model, targets, measured(1, {-15.0, 9.4}), {{1, plan::Pose{90, 90}}});
  EXPECT_EQ(plan.robots.at(0).status, CorrectionStatus::unreachable);
  EXPECT_NE(plan.robots.at(0).detail.find("exceeds"), std::string::npos) << plan.robots.at(0).detail;
  // Not measured, no current position, a robot measured without a target.
  targets.push_back(xy_target(1, {0, 0}, "axis"));
  plan = plan_corrections(model, std::vector{targets[0]}, measured(2, {1, 1}), {});
  EXPECT_EQ(plan.robots.at(0).status, CorrectionStatus::not_measured);
  ASSERT_EQ(plan.notes.size(), 1u);
  EXPECT_NE(plan.notes[0].find("robot 2 has no target"), std::string::npos);
  plan = plan_corrections(model, std::vector{targets[0]}, measured(1, {-15.0, 7.5}), {});
  EXPECT_EQ(plan.robots.at(0).status, CorrectionStatus::no_position);
  // The measured fibre must be the target's.
  auto m = measured(1, {-15.0, 7.5});
  m.items[0].fibre = "apogee";
  plan = plan_corrections(model, std::vector{targets[0]}, m, {{1, plan::Pose{90, 90}}});
  EXPECT_EQ(plan.robots.at(0).status, CorrectionStatus::unreachable);
  EXPECT_NE(plan.robots.at(0).detail.find("m.csv:2: measured fibre 'apogee'"), std::string::npos);
}

TEST(Correction, TargetGivenAsAPoseUsesItsFibrePosition) {
  const auto model = hand_model();
  plan::Target t;
  t.robot = 1;
  t.pose = plan::Pose{90, 90};
  t.fibre = "axis";
  const auto plan = plan_corrections(model, std::vector{t}, measured(1, {-15.0, 7.5}), {{1, plan::Pose{90, 90}}});
  EXPECT_NEAR(plan.robots.at(0).target.x, -15.0, 1e-12);
  EXPECT_NEAR(plan.robots.at(0).target.y, 7.4, 1e-12);
  EXPECT_NEAR(plan.robots.at(0).command.beta_deg, 90.384556, 1e-6);
}

TEST(MeasurementFile, ParsesColumnsInAnyOrderWithComments) {
  const auto m = parse_measurements_csv("# camera exposure 17\ny, robot, x ,fibre\n7.5, 1, -15, boss\n\n1e-3,2,+3.25,\n",
                                        "m.csv", std::vector<std::int32_t>{1, 2});
  ASSERT_TRUE(m.has_value()) << m.error().message();
  ASSERT_EQ(m.value().items.size(), 2u);
  EXPECT_EQ(m.value().items[0].robot, 1);
  EXPECT_EQ(m.value().items[0].position.x, -15.0);
  EXPECT_EQ(m.value().items[0].position.y, 7.5);
  EXPECT_EQ(m.value().items[0].fibre, "boss");
  EXPECT_EQ(m.value().items[0].line, 3);
  EXPECT_EQ(m.value().items[1].position.x, 3.25);
  EXPECT_FALSE(m.value().items[1].fibre.has_value());
  EXPECT_EQ(m.value().items[1].line, 5);
}

TEST(MeasurementFile, ErrorsNameTheFileAndLine) {
  const std::vector<std::int32_t> known{1, 2, 3};
  struct Case {
    const char* text;
    CorrectionErrc code;
    const char* where;
  };
  const Case cases[] = {
      {"robot,x,y\n1,0,0\n9,0,0\n", CorrectionErrc::unknown_robot, "m.csv:3: robot 9 is not part"},
      {"robot,x,y\n1,0,0\n2,1,1\n1,2,2\n", CorrectionErrc::duplicate_robot, "m.csv:4: robot 1 measured twice"},
      {"robot,x,y\n1,0,zero\n", CorrectionErrc::not_a_number, "m.csv:2: y 'zero' is not a number"},
      {"robot,x,y\n1,nan,0\n", CorrectionErrc::not_a_number, "m.csv:2: x 'nan'"},
      {"robot,x,y\none,0,0\n", CorrectionErrc::not_a_number, "m.csv:2: robot id 'one'"},
      {"# header next\nrobot,x\n1,0\n", CorrectionErrc::missing_column, "m.csv:2: the header needs a 'y' column"},
      {"robot,x,y\n1,0\n", CorrectionErrc::missing_column, "m.csv:2: 2 cells, the header has 3"},
      {"robot,x,y,z\n", CorrectionErrc::unknown_column, "m.csv:1: unknown column 'z'"},
      {"", CorrectionErrc::missing_column, "no header line"},
  };
  for (const auto& c : cases) {
    const auto m = parse_measurements_csv(c.text, "m.csv", known);
    ASSERT_FALSE(m.has_value()) << c.text;
    EXPECT_EQ(m.error(), c.code) << c.text;
    EXPECT_NE(m.error().message().find(c.where), std::string::npos) << m.error().message();
  }
  // Without a list of known robots any id 1..2047 is accepted.
  EXPECT_TRUE(parse_measurements_csv("robot,x,y\n9,0,0\n", "m.csv").has_value());
  EXPECT_EQ(load_measurements("/nonexistent/m.csv").error(), CorrectionErrc::cannot_open);
}
