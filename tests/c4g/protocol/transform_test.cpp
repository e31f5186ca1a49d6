#include "axon/c4g/protocol/transform.hpp"

#include "axon/c4g/protocol/error.hpp"
#include "c4g/protocol/example_init.hpp"

#include <gtest/gtest.h>

#include <numbers>

using namespace axon::c4g::protocol;
using axon::c4g::protocol::test::manual_example_init;

// Hand computation for the manual's wrist (axes 4..6 of the example):
//   kr4 = 72.585968, kr5 = 78.75, kr6 = -50; k54 = -0.02, k64 = 0.0204, k65 = 0.02
//   K_r rows 4..6 (columns 4..6):
//     [ kr4,                   0,          0   ]   [ 72.585968, 0,     0   ]
//     [ -kr5 k54,              kr5,        0   ] = [ 1.575,     78.75, 0   ]
//     [ kr6 (k65 k54 - k64),   -kr6 k65,   kr6 ]   [ 1.04,      1.0,   -50 ]
//   since -78.75 * -0.02 = 1.575, -50 * (0.02 * -0.02 - 0.0204) = -50 * -0.0208 = 1.04, 50 * 0.02 = 1.
//   Link q = (pi, 0, 0, pi/2, pi, -pi/4) rad is (0.5, 0, 0, 0.25, 0.5, -0.125) link turns, so
//     m1 = -181.587296 * 0.5 + 0.142965               = -90.650683
//     m2 = 0.170353, m3 = 0.222660                      (calibration only)
//     m4 = 72.585968 * 0.25 + 0.405883                = 18.552375
//     m5 = 1.575 * 0.25 + 78.75 * 0.5 + 0.039380       = 39.808130
//     m6 = 1.04 * 0.25 + 1.0 * 0.5 - 50 * -0.125 + 0.355824 = 7.365824
// The ratios travel as float32, so comparisons allow 1e-4.
namespace {
constexpr double pi = std::numbers::pi;
constexpr double tol = 1e-4;
}  // namespace

TEST(C4gTransform, TransmissionMatrixOfTheManualsWrist) {
  const auto t = ArmTransform::from_init(manual_example_init(), 1).value();
  ASSERT_EQ(t.axes(), 6u);
  const auto& kr = t.kr();
  EXPECT_NEAR(kr(0, 0), -181.587296, tol);
  EXPECT_NEAR(kr(3, 3), 72.585968, tol);
  EXPECT_NEAR(kr(4, 3), 1.575, tol);
  EXPECT_NEAR(kr(4, 4), 78.75, tol);
  EXPECT_NEAR(kr(5, 3), 1.04, tol);
  EXPECT_NEAR(kr(5, 4), 1.0, tol);
  EXPECT_NEAR(kr(5, 5), -50.0, tol);
  EXPECT_NEAR(kr(3, 4), 0.0, 1e-12);  // lower triangular
  EXPECT_NEAR(kr(3, 5), 0.0, 1e-12);
  EXPECT_NEAR(kr(4, 5), 0.0, 1e-12);
  EXPECT_NEAR(kr(1, 0), 0.0, 1e-12);  // no influence outside the wrist
  EXPECT_NEAR(t.k1()(3, 4), -0.02, 1e-7);
  EXPECT_NEAR(t.k1()(3, 5), 0.0204, 1e-7);
  EXPECT_NEAR(t.k1()(4, 5), 0.02, 1e-7);
  EXPECT_TRUE((t.kr() * t.kr_inverse()).isIdentity(1e-12));
}

TEST(C4gTransform, LinkRadiansToMotorTurnsWithCalibration) {
  const auto t = ArmTransform::from_init(manual_example_init(), 1).value();
  ArmTransform::Vector q(6);
  q << pi, 0, 0, pi / 2, pi, -pi / 4;
  const auto m = t.motor_position(q);
  EXPECT_NEAR(m(0), -90.650683, tol);
  EXPECT_NEAR(m(1), 0.170353, tol);
  EXPECT_NEAR(m(2), 0.222660, tol);
  EXPECT_NEAR(m(3), 18.552375, tol);
  EXPECT_NEAR(m(4), 39.808130, tol);
  EXPECT_NEAR(m(5), 7.365824, tol);
  const auto back = t.link_position(m);
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(back(i), q(i), 1e-9);
}

TEST(C4gTransform, VelocitiesIgnoreCalibration) {
  const auto t = ArmTransform::from_init(manual_example_init(), 1).value();
  ArmTransform::Vector dq(6);
  dq << 0, 0, 0, 2 * pi * 0.25, 2 * pi * 0.5, 2 * pi * -0.125;  // link turns/s 0.25, 0.5, -0.125
  const auto dm = t.motor_velocity(dq);
  EXPECT_NEAR(dm(0), 0.0, 1e-12);
  EXPECT_NEAR(dm(3), 72.585968 * 0.25, tol);
  EXPECT_NEAR(dm(4), 1.575 * 0.25 + 78.75 * 0.5, tol);
  EXPECT_NEAR(dm(5), 1.04 * 0.25 + 1.0 * 0.5 + 6.25, tol);
  const auto back = t.link_velocity(dm);
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(back(i), dq(i), 1e-9);
}

TEST(C4gTransform, MovingOnlyAxisFourTurnsMotorsFiveAndSix) {
  // The influence coefficient says: moving axis 4 moves axes 5 and 6 unless their motors compensate.
  const auto t = ArmTransform::from_init(manual_example_init(), 1).value();
  ArmTransform::Vector dq = ArmTransform::Vector::Zero(6);
  dq(3) = 2 * pi;  // one link turn of axis 4 only
  const auto dm = t.motor_velocity(dq);
  EXPECT_NEAR(dm(4), 1.575, tol);
  EXPECT_NEAR(dm(5), 1.04, tol);
}

TEST(C4gTransform, RejectsSingularOrMissingArms) {
  InitPacket p = manual_example_init();
  EXPECT_EQ(ArmTransform::from_init(p, 2).error(), ProtocolErrc::singular_transform);  // arm 2 has no axes
  EXPECT_EQ(ArmTransform::from_init(p, 0).error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(ArmTransform::from_init(p, 5).error(), ProtocolErrc::value_out_of_range);
  p.transmission_ratio[0][2] = 0.0f;  // a hole below the last axis
  EXPECT_EQ(ArmTransform::from_init(p, 1).error(), ProtocolErrc::singular_transform);
}

TEST(C4gTransform, ShortArmsUseOnlyTheCoefficientsTheyHave) {
  const double ratios[] = {10.0, -20.0, 30.0, 40.0, 50.0};
  const double influence[] = {0, 0, 0, 0.5, 0.25, 0.125};
  const double cal[] = {0, 0, 0, 0, 0};
  const auto t = ArmTransform::make(ratios, influence, cal).value();
  ASSERT_EQ(t.axes(), 5u);
  EXPECT_NEAR(t.kr()(4, 3), -50.0 * 0.5, 1e-12);  // only k54 exists
  EXPECT_TRUE((t.kr() * t.kr_inverse()).isIdentity(1e-12));
  const double bad_cal[] = {0, 0};
  EXPECT_EQ(ArmTransform::make(ratios, influence, bad_cal).error(), ProtocolErrc::value_out_of_range);
}
