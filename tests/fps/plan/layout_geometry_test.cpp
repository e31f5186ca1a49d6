// The layout's geometry in the planning model: per-robot orientation, arm lengths and measured
// fibres, the plane's collision segment, guide cameras as obstacles; and why it matters: a plan
// made on the old fixed geometry touches when checked on the true one, the plan made on the true
// geometry does not.
#include "axon/fps/layout/calibration_tables.hpp"
#include "axon/fps/plan/checker.hpp"
#include "axon/fps/plan/layout_model.hpp"
#include "axon/fps/plan/planner.hpp"
#include "axon/fps/plan/problems.hpp"
#include "axon/fps/plan/targets.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace axon::fps::plan {
namespace {

// tests/fps/data/calibration: robots 101..106 (model indices 0..5) below guide camera 2, whose
// edge runs along y = 276.26 for |x| <= 56.54; fiducials 17 and 23 between the lower robots.
FocalPlane true_plane() {
  auto p = load_calibration_dir(std::string(AXON_TESTS_DIR) + "/fps/data/calibration");
  EXPECT_TRUE(p.has_value()) << p.error().message();
  return std::move(p).value();
}

// The same robot centres, fiducials and zero offsets as a layout file had to give them before:
// orientation 0, arms 7.4 / 16.2 / 14.7 mm, the design's fibres, no guide cameras.
FocalPlane old_plane(const FocalPlane& truth) {
  auto spec = truth.spec();
  spec.arms = ArmLengths{};
  spec.guide_cameras.clear();
  for (auto& r : spec.robots) {
    r.orientation_deg = 0;
    r.alpha_length_mm.reset();
    r.beta_length_mm.reset();
    r.fibre_offsets.clear();
  }
  return FocalPlane::build(std::move(spec)).value();
}

std::size_t camera_index(const CollisionModel& m, const std::string& name) {
  for (std::size_t k = 0; k < m.obstacles().size(); ++k)
    if (m.obstacles()[k].name == name) return k;
  ADD_FAILURE() << "no obstacle " << name;
  return 0;
}

TEST(LayoutGeometry, ModelCarriesEveryRobotsGeometryAndTheGuideCameras) {
  const FocalPlane plane = true_plane();
  const auto model = model_from_layout(plane).value();
  EXPECT_EQ(model.design().beta_collision_mm, 14.7276);
  const Positioner& r102 = model.robot(1);
  EXPECT_EQ(r102.id(), 102);
  EXPECT_DOUBLE_EQ(r102.alpha_length_mm(), 7.4215);
  EXPECT_DOUBLE_EQ(r102.collision_length_mm(), 14.7276);
  // Orientation -90 and alpha offset -0.31: alpha 90.31, beta -0.22 points the arm along +x.
  const Segment s = r102.collision_segment({90.31, -0.22});
  EXPECT_NEAR(s.a.x, r102.centre().x + 7.4215, 1e-9);
  EXPECT_NEAR(s.b.x, r102.centre().x + 7.4215 + 14.7276, 1e-9);
  EXPECT_NEAR(s.b.y, r102.centre().y, 1e-9);
  // The measured boss fibre (14.9871, -0.3702) replaces the design's.
  const Vec2 boss = r102.fibre({90.31, -0.22}, kBossFibre);
  EXPECT_NEAR(boss.x, r102.centre().x + 7.4215 + 14.9871, 1e-9);
  EXPECT_NEAR(boss.y, r102.centre().y - 0.3702, 1e-9);
  // Both guide cameras are obstacles with their buffer; robot 101 is paired with camera 2.
  const std::size_t cam = camera_index(model, "guide camera 2");
  EXPECT_EQ(model.obstacles()[cam].buffer_mm, 3.0);
  EXPECT_EQ(model.obstacles()[cam].kind, Obstacle::Kind::other);
  bool paired = false;
  for (const std::uint32_t k : model.obstacle_pairs_of(0)) {
    const ObstaclePair& p = model.obstacle_pairs()[k];
    if (p.obstacle == cam) {
      paired = true;
      EXPECT_DOUBLE_EQ(p.limit_mm, 2.0 + 3.0);
    }
  }
  EXPECT_TRUE(paired);
}

struct GeometryProblem {
  FocalPlane truth = true_plane();
  CollisionModel true_model = model_from_layout(truth).value();
  CollisionModel old_model = model_from_layout(old_plane(truth)).value();
  std::vector<Pose> start = folded_poses(true_model);

  // The same commands for both models, except robot 106: its boss fibre to 21 mm below its
  // centre, resolved by each model's inverse kinematics.
  std::vector<Pose> targets(const CollisionModel& m) const {
    std::vector<Pose> t = start;
    t[0] = {179.73, 0};  // 101: true geometry points it up into camera 2's buffer; old: along -x
    t[1] = {90, 0};      // 102: true geometry points it along +x into robot 103; old: up, clear
    t[3] = {90, 40};     // 104 (turned hole, orientation 0): 0.35 mm outside camera 2's buffer
    const Positioner& r106 = m.robot(5);
    t[5] = r106.inverse(r106.centre() + Vec2{0, -21}, kBossFibre, Elbow::ccw).value();
    return t;
  }
};

PlannerOptions one_thread() {
  PlannerOptions o;
  o.parallel = false;
  o.check.threads = 1;
  return o;
}

TEST(LayoutGeometry, OldGeometryPlanTouchesTheTrueGeometryTheNewPlanDoesNot) {
  const GeometryProblem p;
  // Planned on the old geometry: clean in its own model...
  PlanRequest old_req{p.start, p.targets(p.old_model), {}, {}};
  const Plan old_plan = plan_moves(p.old_model, old_req, one_thread()).value();
  ASSERT_TRUE(old_plan.verified);
  EXPECT_EQ(old_plan.not_reached, 0u) << old_plan.summary(p.old_model);

  // ...but the robots execute the same angles on their true geometry.
  TrajectoryChecker truth_checker(p.true_model);
  CheckReport r;
  ASSERT_TRUE(truth_checker.check(old_plan.trajectories, {}, r));
  EXPECT_FALSE(r.ok());
  const std::size_t cam = camera_index(p.true_model, "guide camera 2");
  bool camera_hit = false, robots_hit = false, fiducial_hit = false;
  for (std::size_t k = 0; k < r.obstacle_pairs.size(); ++k) {
    const ObstaclePair& pair = p.true_model.obstacle_pairs()[k];
    if (!r.obstacle_pairs[k].collided) continue;
    if (pair.robot == 0 && pair.obstacle == cam) camera_hit = true;
    if (pair.robot == 5 && p.true_model.obstacles()[pair.obstacle].name == "fiducial 23") fiducial_hit = true;
  }
  for (std::size_t k = 0; k < r.robot_pairs.size(); ++k) {
    const RobotPair& pair = p.true_model.robot_pairs()[k];
    if (r.robot_pairs[k].collided && pair.a == 1 && pair.b == 2) robots_hit = true;
  }
  EXPECT_TRUE(camera_hit) << "robot 101 into guide camera 2's buffer";
  EXPECT_TRUE(robots_hit) << "robot 102 into robot 103";
  EXPECT_TRUE(fiducial_hit) << "robot 106 into fiducial 23";

  // Planned on the true geometry: the impossible targets are parked, with the reason, and the
  // plan checks clean on the true geometry, by the planner and by an independent checker run.
  PlanRequest req{p.start, p.targets(p.true_model), {}, {}};
  const Plan plan = plan_moves(p.true_model, req, one_thread()).value();
  EXPECT_TRUE(plan.verified);
  EXPECT_EQ(plan.robots[0].status, RobotPlan::Status::parked);
  EXPECT_NE(plan.robots[0].reason.find("guide camera 2"), std::string::npos) << plan.robots[0].reason;
  EXPECT_TRUE(plan.robots[1].status != RobotPlan::Status::reached || plan.robots[2].status != RobotPlan::Status::reached)
      << plan.summary(p.true_model);
  EXPECT_EQ(plan.robots[3].status, RobotPlan::Status::reached) << plan.summary(p.true_model);
  EXPECT_EQ(plan.robots[5].status, RobotPlan::Status::reached) << plan.summary(p.true_model);
  CheckReport clean;
  ASSERT_TRUE(truth_checker.check(plan.trajectories, {}, clean));
  EXPECT_TRUE(clean.ok());
  EXPECT_GE(clean.min_clearance_mm, 0.0);
  // Robot 104 ends 0.35 mm outside camera 2's buffer: the checker measured that pair.
  for (std::size_t k = 0; k < clean.obstacle_pairs.size(); ++k) {
    const ObstaclePair& pair = p.true_model.obstacle_pairs()[k];
    if (pair.robot == 3 && pair.obstacle == cam) {
      EXPECT_GT(clean.obstacle_pairs[k].min_clearance_mm, 0.0);
      EXPECT_LT(clean.obstacle_pairs[k].min_clearance_mm, 0.5);
    }
  }

  // Robot 106's boss fibre: on its target with the true geometry's own plan, far off with the
  // old one (its hole is turned by -90 degrees).
  const Positioner& r106 = p.true_model.robot(5);
  const Vec2 goal = r106.centre() + Vec2{0, -21};
  EXPECT_LT(norm(r106.fibre(plan.robots[5].end, kBossFibre) - goal), 1e-6);
  EXPECT_GT(norm(r106.fibre(old_plan.robots[5].end, kBossFibre) - goal), 10.0);
}

}  // namespace
}  // namespace axon::fps::plan
