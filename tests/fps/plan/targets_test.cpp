// Target files (YAML, CSV) and their validation against a small focal plane.
#include "axon/fps/plan/targets.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace axon::fps::plan {
namespace {

using Status = RobotOutcome::Status;

// Robots 1 and 2 face each other 48 mm apart (head-on at alpha 0 / 180: clearance -0.2 mm).
// Robot 3 stands alone at (200, 0) with fiducial 9 at (215, 4.5): 4.5 mm above its stretched
// segment, clearance 4.5 - (2 + 3) = -0.5.
CollisionModel plane() {
  std::vector<RobotSpec> r{{1, {0, 0}, {}, {}, 2.0}, {2, {48, 0}, {}, {}, 2.0}, {3, {200, 0}, {}, {}, 2.0}};
  std::vector<FiducialSpec> f{{9, {215, 4.5}, 3.0}};
  return CollisionModel::build(r, ArmDesign{}, f).value();
}

Target pose(std::int32_t id, double a, double b) { return Target{id, Pose{a, b}, std::nullopt, "boss", {}, 0}; }
Target at(std::int32_t id, Vec2 p, std::string fibre = "boss") { return Target{id, std::nullopt, p, fibre, {}, 0}; }

TEST(PlanTargets, ParsesYamlAndCsvAlike) {
  for (const char* file : {"targets.yaml", "targets.csv"}) {
    auto t = load_targets(std::string(AXON_TESTS_DIR) + "/fps/plan/data/" + file);
    ASSERT_TRUE(t) << t.error().message();
    ASSERT_EQ(t.value().size(), 2u) << file;
    const Target& a = t.value()[0];
    EXPECT_EQ(a.robot, 1);
    ASSERT_TRUE(a.pose);
    EXPECT_EQ(*a.pose, (Pose{0, 0}));
    const Target& b = t.value()[1];
    EXPECT_EQ(b.robot, 3);
    ASSERT_TRUE(b.position);
    EXPECT_EQ(*b.position, (Vec2{210, 5}));
    EXPECT_EQ(b.fibre, "apogee");
    EXPECT_EQ(b.elbow, Elbow::cw);
    EXPECT_GT(b.line, a.line);
  }
}

TEST(PlanTargets, FileErrorsNameTheLine) {
  struct Case {
    const char* csv;
    const char* says;
  };
  const Case cases[] = {
      {"robot,alpha,beta\n1,10\n", ":2: 2 cells"},
      {"robot,alpha,beta,x,y\n1,10,20,5,5\n", ":2: give either"},
      {"robot,alpha,beta\n1,10,\n", ":2: alpha and beta go together"},
      {"robot,alpha,gamma\n", ":1: unknown column 'gamma'"},
      {"alpha,beta\n", ":1: the header needs a 'robot' column"},
      {"robot,alpha,beta\n\n# c\n1,ten,5\n", ":4: 'ten' is not a number"},
      {"robot,x,y,elbow\n1,10,5,up\n", ":2: elbow 'up'"},
      {"robot,x,y\n0,10,5\n", ":2: robot id 0 out of range"},
      {"# nothing\n", "no header"},
  };
  for (const auto& c : cases) {
    auto r = parse_targets_csv(c.csv, "t.csv");
    ASSERT_FALSE(r) << c.csv;
    EXPECT_EQ(r.error(), PlanErrc::bad_target_file);
    EXPECT_NE(r.error().detail.find(c.says), std::string::npos) << r.error().detail;
  }
  auto y = parse_targets_yaml("targets:\n  - {robot: 1, alpha: 1, beta: 2}\n  - {robot: 2, alfa: 3}\n", "t.yaml");
  ASSERT_FALSE(y);
  EXPECT_EQ(y.error(), PlanErrc::bad_target_file);
  EXPECT_NE(y.error().detail.find("t.yaml:3"), std::string::npos) << y.error().detail;
  EXPECT_FALSE(parse_targets_yaml("targets: [ {robot: 1, x: 3} ]\n"));
  EXPECT_FALSE(parse_targets_yaml("- {robot: 1, alpha: 1, beta: 1}\n"));
  EXPECT_EQ(load_targets("/nonexistent/t.yaml").error(), PlanErrc::bad_target_file);
}

TEST(PlanTargets, GoodSetResolvesPosesAndParksTheRest) {
  const auto m = plane();
  // Robot 3's boss fibre to (190, 5), 11.18 mm from its centre, away from the fiducial.
  const std::vector<Target> t{pose(1, 0, 0), at(3, {190, 5})};
  const auto v = validate_targets(m, t);
  EXPECT_TRUE(v.ok()) << v.summary();
  EXPECT_EQ(v.robots[0].status, Status::ok);
  EXPECT_EQ(v.robots[1].status, Status::untargeted);
  EXPECT_EQ(v.robots[1].pose, (Pose{10, 170}));
  EXPECT_EQ(v.robots[2].status, Status::ok);
  const Vec2 f = m.robot(2).fibre(v.robots[2].pose, kBossFibre);
  EXPECT_NEAR(f.x, 190, 1e-9);
  EXPECT_NEAR(f.y, 5, 1e-9);
  EXPECT_LE(v.robots[2].pose.beta_deg, 180);
  EXPECT_EQ(v.poses().size(), 3u);
}

TEST(PlanTargets, RejectPolicyReportsEveryBadRobot) {
  const auto m = plane();
  // 1 and 2 head-on; 3 onto the fiducial.
  const std::vector<Target> t{pose(1, 0, 0), pose(2, 180, 0), pose(3, 0, 0)};
  const auto v = validate_targets(m, t);
  EXPECT_FALSE(v.ok());
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(v.robots[i].status, Status::rejected) << i;
    ASSERT_TRUE(v.robots[i].issue) << i;
  }
  EXPECT_EQ(*v.robots[0].issue, PlanErrc::robot_collision);
  EXPECT_NE(v.robots[0].issue->detail.find("robot 2"), std::string::npos);
  EXPECT_NE(v.robots[1].issue->detail.find("robot 1"), std::string::npos);
  EXPECT_EQ(*v.robots[2].issue, PlanErrc::obstacle_collision);
  EXPECT_NE(v.robots[2].issue->detail.find("fiducial 9"), std::string::npos);
  EXPECT_NE(v.summary().find("robot 3: rejected"), std::string::npos);
}

TEST(PlanTargets, ParkPolicyFoldsTheLaterRobot) {
  const auto m = plane();
  const std::vector<Target> t{pose(1, 0, 0), pose(2, 180, 0), pose(3, 0, 0)};
  ValidationOptions o;
  o.policy = TargetPolicy::park;
  const auto v = validate_targets(m, t, o);
  EXPECT_TRUE(v.ok()) << v.summary();
  EXPECT_EQ(v.robots[0].status, Status::ok);
  EXPECT_EQ(v.robots[0].pose, (Pose{0, 0}));
  EXPECT_EQ(v.robots[1].status, Status::parked);
  EXPECT_EQ(*v.robots[1].issue, PlanErrc::robot_collision);
  EXPECT_EQ(v.robots[1].pose, o.park);
  EXPECT_EQ(v.robots[2].status, Status::parked);
  EXPECT_EQ(*v.robots[2].issue, PlanErrc::obstacle_collision);
  // Listed the other way round, robot 1 gives way.
  const std::vector<Target> swapped{pose(2, 180, 0), pose(1, 0, 0)};
  const auto w = validate_targets(m, swapped, o);
  EXPECT_EQ(w.robots[0].status, Status::parked);
  EXPECT_EQ(w.robots[1].status, Status::ok);
}

TEST(PlanTargets, UnreachableUnknownAndDuplicate) {
  const auto m = plane();
  const std::vector<Target> t{at(3, {230, 0}),  at(1, {1, 0}),  pose(2, 400, 0), pose(99, 0, 0),
                              pose(3, 10, 170), at(1, {5, 5}, "laser")};
  for (auto policy : {TargetPolicy::reject, TargetPolicy::park}) {
    ValidationOptions o;
    o.policy = policy;
    const auto v = validate_targets(m, t, o);
    EXPECT_FALSE(v.ok());  // unknown and duplicate targets fail under either policy
    const Status bad = policy == TargetPolicy::park ? Status::parked : Status::rejected;
    EXPECT_EQ(v.robots[2].status, bad);
    EXPECT_EQ(*v.robots[2].issue, PlanErrc::too_far);
    EXPECT_EQ(*v.robots[0].issue, PlanErrc::too_close);
    EXPECT_EQ(*v.robots[1].issue, PlanErrc::outside_hard_stops);
    ASSERT_EQ(v.errors.size(), 3u);
    EXPECT_EQ(v.errors[0], PlanErrc::unknown_robot);
    EXPECT_EQ(v.errors[1], PlanErrc::duplicate_target);
    EXPECT_EQ(v.errors[2], PlanErrc::duplicate_target);
  }
  const auto f = validate_targets(m, std::vector{at(1, {5, 5}, "laser")});
  EXPECT_EQ(*f.robots[0].issue, PlanErrc::unknown_fibre);
}

TEST(PlanTargets, RobotThatCollidesEvenWhenParkedIsRejected) {
  // Parked (10, 170), robot 4's segment runs from (307.29, 1.285) back to (292.59, 1.285); a
  // fiducial at (300, 4) is 2.715 mm from it, inside 2 + 3.
  std::vector<RobotSpec> r{{4, {300, 0}, {}, {}, 2.0}};
  std::vector<FiducialSpec> f{{5, {300, 4}, 3.0}};
  const auto m = CollisionModel::build(r, ArmDesign{}, f).value();
  for (auto policy : {TargetPolicy::reject, TargetPolicy::park}) {
    ValidationOptions o;
    o.policy = policy;
    const auto v = validate_targets(m, std::vector<Target>{}, o);
    EXPECT_FALSE(v.ok());
    EXPECT_EQ(v.robots[0].status, Status::rejected);
    EXPECT_NE(v.robots[0].issue->detail.find("at the park pose"), std::string::npos);
  }
}

}  // namespace
}  // namespace axon::fps::plan
