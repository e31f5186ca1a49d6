// Forward and inverse kinematics of the positioner: hand-worked poses and round trips.
#include "axon/fps/plan/kinematics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace axon::fps::plan {
namespace {

constexpr double kEps = 1e-9;

void expect_near(Vec2 a, Vec2 b, double eps = kEps) {
  EXPECT_NEAR(a.x, b.x, eps);
  EXPECT_NEAR(a.y, b.y, eps);
}

// The science fibre's x on the beta arm: 22.4 mm at full extension with a 0.375 mm side offset.
const double kScienceX = std::sqrt(22.4 * 22.4 - 0.375 * 0.375) - 7.4;  // 14.99686
const double kMetrologyX = kScienceX - std::sqrt(0.75 * 0.75 - 0.375 * 0.375);  // 14.34734

Positioner nominal(Vec2 centre = {}, RobotCalibration cal = {}, AngleLimits lim = {}) {
  return Positioner(RobotSpec{1, centre, cal, lim, 2.0}, ArmDesign{});
}

TEST(PlanKinematics, DefaultFibresAndFigures) {
  const ArmDesign d;
  ASSERT_EQ(d.fibres.size(), 3u);
  EXPECT_EQ(d.fibre_index("metrology"), kMetrologyFibre);
  EXPECT_EQ(d.fibre_index("APOGEE"), kApogeeFibre);
  EXPECT_EQ(d.fibre_index("boss"), kBossFibre);
  EXPECT_FALSE(d.fibre_index("nope"));
  EXPECT_NEAR(d.fibres[kMetrologyFibre].offset.x, 14.3473, 1e-4);
  EXPECT_NEAR(d.fibres[kApogeeFibre].offset.x, 14.9969, 1e-4);
  EXPECT_DOUBLE_EQ(d.fibres[kApogeeFibre].offset.y, 0.375);
  EXPECT_DOUBLE_EQ(d.fibres[kBossFibre].offset.y, -0.375);
  const Positioner p = nominal();
  // The brief's reachable annulus for the metrology fibre: 14.3473 -+ 7.4.
  EXPECT_NEAR(p.min_reach_mm(kMetrologyFibre), 6.9473, 1e-4);
  EXPECT_NEAR(p.max_reach_mm(kMetrologyFibre), 21.7473, 1e-4);
  // A science fibre at alpha 0, beta 0 lies exactly one hex pitch from the centre; turning beta
  // by its 1.43 deg side angle lines it up radially: 7.4 + hypot(14.9969, 0.375) = 22.4015.
  EXPECT_NEAR(norm(p.fibre({0, 0}, kBossFibre)), 22.4, 1e-12);
  EXPECT_NEAR(p.max_reach_mm(kBossFibre), 7.4 + std::hypot(kScienceX, 0.375), 1e-12);
  EXPECT_DOUBLE_EQ(p.reach_mm(), 7.4 + 14.7);
}

TEST(PlanKinematics, ForwardStretchedOut) {
  const Positioner p = nominal({100, 50});
  // alpha 0, beta 0: everything on the +x line through the centre.
  expect_near(p.beta_axis({0, 0}), {107.4, 50});
  expect_near(p.tip({0, 0}), {107.4 + 16.2, 50});
  const Segment s = p.collision_segment({0, 0});
  expect_near(s.a, {107.4, 50});
  expect_near(s.b, {107.4 + 14.7, 50});
  expect_near(p.fibre({0, 0}, kMetrologyFibre), {107.4 + kMetrologyX, 50});
  expect_near(p.fibre({0, 0}, kApogeeFibre), {107.4 + kScienceX, 50.375});
}

TEST(PlanKinematics, ForwardBentPose) {
  const Positioner p = nominal();
  // alpha 90: beta axis at (0, 7.4). beta 90 turns the beta arm to 180 deg: pointing along -x.
  expect_near(p.beta_axis({90, 90}), {0, 7.4});
  expect_near(p.tip({90, 90}), {-16.2, 7.4});
  // The apogee offset (x, +0.375) turned by 180 deg is (-x, -0.375).
  expect_near(p.fibre({90, 90}, kApogeeFibre), {-kScienceX, 7.4 - 0.375});
  // Folded (beta 180) the metrology fibre sits 14.3473 - 7.4 = 6.9473 mm behind the centre.
  expect_near(p.fibre({0, 180}, kMetrologyFibre), {7.4 - kMetrologyX, 0});
}

TEST(PlanKinematics, CalibrationShiftsAnglesAndLengths) {
  RobotCalibration cal;
  cal.orientation_deg = 30;
  cal.alpha_offset_deg = 5;
  cal.beta_offset_deg = -3;
  cal.alpha_length_delta_mm = 0.1;
  cal.beta_length_delta_mm = -0.05;
  const Positioner p = nominal({}, cal);
  // alpha 10 becomes 10 + 30 + 5 = 45 deg on the plane; beta 20 adds 20 - 3 = 17.
  const double a = 45 * std::numbers::pi / 180, b = 62 * std::numbers::pi / 180;
  expect_near(p.beta_axis({10, 20}), {7.5 * std::cos(a), 7.5 * std::sin(a)});
  const double mx = kMetrologyX - 0.05;
  expect_near(p.fibre({10, 20}, kMetrologyFibre), {7.5 * std::cos(a) + mx * std::cos(b), 7.5 * std::sin(a) + mx * std::sin(b)});
  EXPECT_DOUBLE_EQ(p.collision_length_mm(), 14.65);
}

TEST(PlanKinematics, InverseHandWorked) {
  const Positioner p = nominal();
  // Beta axis at (7.4, 0) with alpha 0; beta 90 puts the metrology fibre straight above it.
  const IkSolutions s = p.inverse({7.4, kMetrologyX}, kMetrologyFibre);
  ASSERT_TRUE(s.ok[0]);
  ASSERT_TRUE(s.ok[1]);
  EXPECT_NEAR(s.pose[0].alpha_deg, 0, kEps);
  EXPECT_NEAR(s.pose[0].beta_deg, 90, kEps);
  // The other elbow mirrors the arms about the line to the target, turning beta to 270.
  EXPECT_NEAR(s.pose[1].beta_deg, 270, kEps);
  expect_near(p.fibre(s.pose[1], kMetrologyFibre), {7.4, kMetrologyX});
}

TEST(PlanKinematics, InverseRoundTripsBothElbowsEveryFibre) {
  std::mt19937 rng(11);
  RobotCalibration cal;
  cal.orientation_deg = -12;
  cal.alpha_offset_deg = 1.5;
  cal.beta_offset_deg = -0.7;
  cal.alpha_length_delta_mm = 0.08;
  cal.beta_length_delta_mm = -0.1;
  const Positioner p = nominal({-30, 20}, cal);
  std::uniform_real_distribution<double> ang(0, 2 * std::numbers::pi);
  for (std::size_t f = 0; f < p.fibre_count(); ++f) {
    std::uniform_real_distribution<double> rad(p.min_reach_mm(f) + 1e-6, p.max_reach_mm(f) - 1e-6);
    for (int k = 0; k < 300; ++k) {
      const double r = rad(rng), th = ang(rng);
      const Vec2 target = p.centre() + Vec2{r * std::cos(th), r * std::sin(th)};
      const IkSolutions s = p.inverse(target, f);
      ASSERT_TRUE(s.ok[0] && s.ok[1]) << "fibre " << f << " r " << r;
      for (int e = 0; e < 2; ++e) {
        expect_near(p.fibre(s.pose[e], f), target, 1e-9);
        EXPECT_TRUE(p.within_limits(s.pose[e]));
      }
      // Distinct elbows away from the annulus edges.
      EXPECT_GT(std::abs(s.pose[0].beta_deg - s.pose[1].beta_deg), 1e-6);
      // And back: FK of a random pose, IK, the same pose on one of the elbows.
      const Pose q{std::uniform_real_distribution<double>(0, 360)(rng), std::uniform_real_distribution<double>(5, 175)(rng)};
      const IkSolutions back = p.inverse(p.fibre(q, f), f);
      const bool match0 = std::abs(back.pose[0].alpha_deg - q.alpha_deg) < 1e-7 && std::abs(back.pose[0].beta_deg - q.beta_deg) < 1e-7;
      const bool match1 = std::abs(back.pose[1].alpha_deg - q.alpha_deg) < 1e-7 && std::abs(back.pose[1].beta_deg - q.beta_deg) < 1e-7;
      EXPECT_TRUE(match0 || match1) << "alpha " << q.alpha_deg << " beta " << q.beta_deg;
    }
  }
}

TEST(PlanKinematics, UnreachableTargetsSayWhy) {
  const Positioner p = nominal();
  EXPECT_EQ(p.inverse({30, 0}, kMetrologyFibre).reason, PlanErrc::too_far);
  EXPECT_FALSE(p.inverse({30, 0}, kMetrologyFibre).any());
  EXPECT_EQ(p.inverse({1, 1}, kMetrologyFibre).reason, PlanErrc::too_close);
  // Just inside both edges of the annulus: reachable (the two elbows coincide there).
  EXPECT_TRUE(p.inverse({21.7473, 0}, kMetrologyFibre).any());
  EXPECT_TRUE(p.inverse({6.9474, 0}, kMetrologyFibre).any());
  auto r = p.inverse({30, 0}, kMetrologyFibre, Elbow::ccw);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error(), PlanErrc::too_far);
  EXPECT_NE(r.error().detail.find("robot 1"), std::string::npos);
}

TEST(PlanKinematics, HardStopLimitsRejectElbows) {
  AngleLimits lim;
  lim.alpha_max_deg = 90;
  lim.beta_max_deg = 180;
  const Positioner p = nominal({}, {}, lim);
  // Straight behind the centre needs alpha near 180: outside 0..90 for both elbows.
  const IkSolutions s = p.inverse({-15, 0}, kMetrologyFibre);
  EXPECT_FALSE(s.any());
  EXPECT_EQ(s.reason, PlanErrc::outside_hard_stops);
  EXPECT_EQ(p.inverse({-15, 0}, kMetrologyFibre, Elbow::ccw).error(), PlanErrc::outside_hard_stops);
  // Above the beta axis at alpha 0: ccw (beta 90) fits, cw (beta 270) exceeds beta 180.
  const IkSolutions t = p.inverse({7.4, kMetrologyX}, kMetrologyFibre);
  EXPECT_TRUE(t.ok[0]);
  EXPECT_FALSE(t.ok[1]);
  EXPECT_EQ(p.inverse({7.4, kMetrologyX}, kMetrologyFibre, Elbow::cw).error(), PlanErrc::outside_hard_stops);
}

TEST(PlanKinematics, WrapIntoLimits) {
  EXPECT_DOUBLE_EQ(*wrap_into(-10, 0, 360), 350);
  EXPECT_DOUBLE_EQ(*wrap_into(370, 0, 360), 10);
  EXPECT_DOUBLE_EQ(*wrap_into(360, 0, 360), 0);
  EXPECT_DOUBLE_EQ(*wrap_into(-5, -8, 368), -5);
  EXPECT_FALSE(wrap_into(5, 10, 20));
  EXPECT_FALSE(wrap_into(NAN, 0, 360));
}

}  // namespace
}  // namespace axon::fps::plan
