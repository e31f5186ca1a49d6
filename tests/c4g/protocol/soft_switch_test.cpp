// The linear soft-switching model (manual, chapter 12) against values computed by hand for
// T1 = 50 ms, T2 = 100 ms, T3 = 50 ms, and the variable-threshold limiter.
#include "axon/c4g/protocol/soft_switch.hpp"

#include <gtest/gtest.h>

#include <limits>

namespace axon::c4g::protocol {
namespace {

const SwitchTimes kTimes{0.05, 0.10, 0.05};

TEST(C4gSoftSwitch, IntervalsAndTheLinearRampEnteringThePc) {
  struct Row {
    double t;
    SwitchInterval interval;
    double chi;
  };
  // chi = (t - T1) / T2 inside T2: 0.075 -> 0.25, 0.1 -> 0.5, 0.125 -> 0.75.
  const Row rows[] = {{0.0, SwitchInterval::pre, 0.0},         {0.049, SwitchInterval::pre, 0.0},
                      {0.05, SwitchInterval::switching, 0.0},  {0.075, SwitchInterval::switching, 0.25},
                      {0.10, SwitchInterval::switching, 0.5},  {0.125, SwitchInterval::switching, 0.75},
                      {0.151, SwitchInterval::post, 1.0},      {0.199, SwitchInterval::post, 1.0},
                      {0.201, SwitchInterval::done, 1.0},      {5.0, SwitchInterval::done, 1.0},
                      {-1.0, SwitchInterval::pre, 0.0}};
  for (const auto& r : rows) {
    const auto s = linear_switch(kTimes, SwitchDirection::to_pc, r.t);
    EXPECT_EQ(s.interval, r.interval) << "t = " << r.t;
    EXPECT_NEAR(s.chi, r.chi, 1e-12) << "t = " << r.t;
    EXPECT_NEAR(s.eta, r.chi, 1e-12) << "t = " << r.t;        // eta = chi
    EXPECT_NEAR(s.rho, 1.0 - r.chi, 1e-12) << "t = " << r.t;  // rho = 1 - chi
    EXPECT_NEAR(s.pc_gain(), s.eta, 1e-12);                    // entering: the PC's current by eta
    EXPECT_NEAR(s.drive_gain(), s.rho, 1e-12);                 // the drive's limiter by rho
    EXPECT_EQ(s.robot_must_be_still(), r.interval != SwitchInterval::done);
  }
}

TEST(C4gSoftSwitch, LeavingThePcSwapsTheFactors) {
  const auto s = linear_switch(kTimes, SwitchDirection::to_drive, 0.075);
  EXPECT_NEAR(s.chi, 0.25, 1e-12);
  EXPECT_NEAR(s.pc_gain(), 0.75, 1e-12);     // the PC's current by rho
  EXPECT_NEAR(s.drive_gain(), 0.25, 1e-12);  // the drive's limiter at eta (Imax - Imin)
  const auto end = linear_switch(kTimes, SwitchDirection::to_drive, 0.16);
  EXPECT_EQ(end.interval, SwitchInterval::post);
  EXPECT_EQ(end.pc_gain(), 0.0);
  EXPECT_EQ(end.drive_gain(), 1.0);
}

TEST(C4gSoftSwitch, NoSwitchAndZeroLengthIntervals) {
  const SwitchSample none;
  EXPECT_EQ(none.pc_gain(), 0.0);
  EXPECT_EQ(none.drive_gain(), 1.0);
  EXPECT_FALSE(none.robot_must_be_still());
  // T2 = 0: chi jumps from 0 to 1 at T1.
  const SwitchTimes step{0.01, 0.0, 0.01};
  EXPECT_EQ(linear_switch(step, SwitchDirection::to_pc, 0.0099).chi, 0.0);
  EXPECT_EQ(linear_switch(step, SwitchDirection::to_pc, 0.01).chi, 1.0);
  EXPECT_EQ(linear_switch(step, SwitchDirection::to_pc, 0.01).interval, SwitchInterval::post);
  // All zero: done at once.
  EXPECT_EQ(linear_switch(SwitchTimes{0, 0, 0}, SwitchDirection::to_pc, 0.0).interval, SwitchInterval::done);
}

TEST(C4gSoftSwitch, ValidateRejectsNegativeAndNonFiniteTimes) {
  EXPECT_TRUE(validate(kTimes));
  EXPECT_TRUE(validate(SwitchTimes{0, 0, 0}));
  EXPECT_FALSE(validate(SwitchTimes{-0.01, 0.1, 0.05}));
  EXPECT_FALSE(validate(SwitchTimes{0.05, std::numeric_limits<double>::quiet_NaN(), 0.05}));
  EXPECT_FALSE(validate(SwitchTimes{0.05, 0.1, std::numeric_limits<double>::infinity()}));
}

TEST(C4gSoftSwitch, VariableThresholdLimiter) {
  // Imax 24.5 A (axes 1-3 of the manual's robot), factor 0.25: threshold 6.125 A.
  EXPECT_DOUBLE_EQ(limit_current(5.0, 0.25, 24.5), 5.0);
  EXPECT_DOUBLE_EQ(limit_current(10.0, 0.25, 24.5), 6.125);
  EXPECT_DOUBLE_EQ(limit_current(-10.0, 0.25, 24.5), -6.125);  // the sign is kept
  EXPECT_DOUBLE_EQ(limit_current(3.0, 0.0, 24.5), 0.0);
  EXPECT_DOUBLE_EQ(limit_current(30.0, 1.0, 24.5), 24.5);
  EXPECT_DOUBLE_EQ(limit_current(30.0, 0.5, 24.5, 4.5), 10.0);  // (Imax - Imin) = 20 A
}

}  // namespace
}  // namespace axon::c4g::protocol
