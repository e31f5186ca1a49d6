#include "axon/c4g/host/safety.hpp"

#include "axon/c4g/protocol/axis_map.hpp"
#include "axon/c4g/protocol/mode.hpp"
#include "c4g/protocol/example_init.hpp"

#include <gtest/gtest.h>

#include <limits>

using namespace axon::c4g;
using namespace axon::c4g::host;
using protocol::code;
using protocol::Mode;

namespace {
protocol::Packet packet(std::int32_t mode, std::size_t axes = 2) {
  protocol::Packet p;
  p.count = axes;
  p.infpar = protocol::kDrivesOn;
  for (std::size_t i = 0; i < axes; ++i) p.axes[i].mode = mode;
  return p;
}
}  // namespace

TEST(Safety, OverridesApplyWithoutAnInitializationPacket) {
  SafetyConfig c;
  c.current_limit_override[0] = 2.0f;
  c.following_error_override[1] = 0.1f;
  Safety s(c);
  auto req = packet(code(Mode::mode9));
  auto rep = req;
  rep.axes[0].d5 = -7.0f;
  EXPECT_EQ(s.apply(req, rep), FaultReason::none);
  EXPECT_FLOAT_EQ(rep.axes[0].d5, -2.0f);  // mode 9 current contribution clamped

  req = packet(code(Mode::mode2));
  req.axes[1].d1 = 0.0f;
  req.axes[1].d3 = 0.2f;
  rep = req;
  EXPECT_EQ(s.apply(req, rep), FaultReason::following_error);
  EXPECT_EQ(rep.axes[1].mode, code(Mode::following_error));
  EXPECT_EQ(rep.axes[0].mode, code(Mode::mode2));
}

TEST(Safety, FollowingErrorIsCheckedWhereThePcGeneratesTheTrajectoryNotWhereItOnlyCorrects) {
  SafetyConfig c;
  c.following_error_override[0] = 0.1f;
  for (const auto m : {Mode::mode4, Mode::mode5}) {
    Safety s(c);
    auto req = packet(code(m));
    req.axes[0].d1 = 0.0f;
    req.axes[0].d3 = 5.0f;
    auto rep = req;
    rep.axes[0].d1 = m == Mode::mode4 ? 0.0f : 0.01f;
    EXPECT_EQ(s.apply(req, rep), FaultReason::following_error) << code(m);
    EXPECT_EQ(rep.axes[0].mode, code(Mode::following_error));  // 508 on the axis
  }
  Safety s(c);
  auto req = packet(code(Mode::mode7));
  req.axes[0].d1 = 0.0f;
  req.axes[0].d3 = 5.0f;
  auto rep = req;
  rep.axes[0].d1 = 0.0f;
  EXPECT_EQ(s.apply(req, rep), FaultReason::none);
}

TEST(Safety, KeepsEachAxisFollowingErrorAndItsPeakInTheModeForOtherThreads) {
  Safety s;  // no thresholds: nothing is checked, the figures are kept all the same
  auto req = packet(code(Mode::mode4));
  const auto cycle = [&](float d1, float d3, std::int32_t mode) {
    req.axes[1].mode = mode;
    req.axes[1].d1 = d1;
    req.axes[1].d3 = d3;
    auto rep = req;
    s.apply(req, rep);
  };
  EXPECT_EQ(s.following_error(1), 0.0f);  // before any packet
  cycle(1.0f, 0.75f, code(Mode::mode4));
  EXPECT_FLOAT_EQ(s.following_error(1), 0.25f);
  EXPECT_FLOAT_EQ(s.following_error_peak(1), 0.25f);
  cycle(1.0f, 1.1f, code(Mode::mode4));  // the other side of the target: the size counts
  EXPECT_FLOAT_EQ(s.following_error(1), 0.1f);
  EXPECT_FLOAT_EQ(s.following_error_peak(1), 0.25f);  // the peak stays while the mode does
  cycle(1.0f, 0.95f, code(Mode::mode0));
  EXPECT_FLOAT_EQ(s.following_error(1), 0.05f);
  EXPECT_FLOAT_EQ(s.following_error_peak(1), 0.05f);  // a new mode: a new peak
  EXPECT_EQ(s.following_error(0), 0.0f);
  EXPECT_EQ(s.following_error(protocol::kMaxAxes), 0.0f);  // out of range reads 0
  EXPECT_TRUE(Safety::checks_following_error(code(Mode::mode4)));
  EXPECT_TRUE(Safety::checks_following_error(code(Mode::mode1)));
  EXPECT_FALSE(Safety::checks_following_error(code(Mode::mode7)));
  EXPECT_FALSE(Safety::checks_following_error(code(Mode::mode0)));
}

TEST(Safety, StrokeEndsAndContinuityAreOnByDefault) {
  const SafetyConfig c;
  EXPECT_TRUE(c.check_stroke_ends);
  EXPECT_TRUE(c.check_continuity);
  EXPECT_TRUE(c.check_following_error);
  EXPECT_DOUBLE_EQ(c.joints[0][0].min_deg, -180.0);
  EXPECT_DOUBLE_EQ(c.joints[3][9].max_deg, 180.0);
}

TEST(Safety, AJumpInAnAbsoluteTargetDrivesOff505) {
  Safety s;  // 100 motor turns/s at 2 ms: 0.2 turns per cycle
  auto req = packet(code(Mode::mode4));
  auto rep = req;
  rep.axes[0].d1 = 0.15f;  // entering: from the controller's target 0
  EXPECT_EQ(s.apply(req, rep), FaultReason::none);
  req.axes[0].d1 = 0.15f;
  rep = req;
  rep.axes[0].d1 = 0.5f;
  EXPECT_EQ(s.apply(req, rep), FaultReason::discontinuity);
  EXPECT_EQ(s.fault_axis(), 0);
  EXPECT_EQ(rep.axes[0].mode, code(Mode::drive_off));
  EXPECT_EQ(rep.axes[1].mode, code(Mode::drive_off));
}

TEST(Safety, AnIncrementLargerThanTheStepDrivesOff) {
  SafetyConfig c;
  c.axes[1].max_step = 0.01f;
  Safety s(c);
  auto req = packet(code(Mode::mode5));
  auto rep = req;
  rep.axes[1].d1 = 0.02f;
  EXPECT_EQ(s.apply(req, rep), FaultReason::discontinuity);
  EXPECT_EQ(s.fault_axis(), 1);
}

TEST(Safety, MotorTurnStrokeEndsApplyWithoutAnInitializationPacket) {
  SafetyConfig c;
  c.axes[0].min_position = -1.0f;
  c.axes[0].max_position = 1.0f;
  Safety s(c);
  auto req = packet(code(Mode::mode8));  // a contribution mode: the actual position is held to them
  req.axes[0].d3 = 1.5f;
  auto rep = req;
  EXPECT_EQ(s.apply(req, rep), FaultReason::stroke_end);
  EXPECT_EQ(rep.axes[0].mode, code(Mode::drive_off));
}

TEST(Safety, JointStrokeEndsAtTheLinkGoThroughTheArmsTransmission) {
  // The manual's arm: axis 1 has a ratio of -181.587 motor turns per link turn and q0 0.142965.
  const auto init = protocol::test::manual_example_init();
  const auto map = protocol::AxisMap::from_init(init).value();
  SafetyConfig c;
  ASSERT_TRUE(parse_stroke_end("1.1=-10:20", 1, c));
  Safety s(c);
  s.configure(init, map);
  auto req = packet(code(Mode::mode4), 6);
  for (std::size_t i = 0; i < 6; ++i) req.axes[i].d1 = init.calibration[0][i];  // every joint at 0
  auto at = [&](double deg) { return static_cast<float>(init.calibration[0][0] - 181.587296 * deg / 360.0); };
  req.axes[0].d1 = at(19.95);
  for (std::size_t i = 0; i < 6; ++i) req.axes[i].d3 = req.axes[i].d1;  // following well
  auto rep = req;
  rep.axes[0].d1 = at(19.99);  // inside: 20 deg is the positive stroke end
  EXPECT_EQ(s.apply(req, rep), FaultReason::none);
  req.axes[0].d1 = req.axes[0].d3 = rep.axes[0].d1;
  rep = req;
  rep.axes[0].d1 = at(20.03);
  EXPECT_EQ(s.apply(req, rep), FaultReason::stroke_end);
  EXPECT_EQ(s.fault_axis(), 0);
  EXPECT_EQ(rep.axes[0].mode, code(Mode::drive_off));
}

TEST(Safety, StrokeEndSpecsAreParsedOrRefusedWithTheReason) {
  SafetyConfig c;
  ASSERT_TRUE(parse_stroke_end("3=-120:150.5", 2, c));
  EXPECT_DOUBLE_EQ(c.joints[1][2].min_deg, -120.0);
  EXPECT_DOUBLE_EQ(c.joints[1][2].max_deg, 150.5);
  for (const char* bad : {"3", "3=10", "0=-1:1", "11=-1:1", "5.1=-1:1", "3=5:-5", "x=1:2"}) {
    const auto r = parse_stroke_end(bad, 1, c);
    ASSERT_FALSE(r) << bad;
    EXPECT_NE(r.error().detail.find("stroke end"), std::string::npos) << r.error().detail;
  }
}

TEST(Safety, NonFiniteReplyDrivesOff) {
  Safety s;
  auto req = packet(code(Mode::mode7));
  auto rep = req;
  rep.axes[1].d2 = std::numeric_limits<float>::infinity();
  EXPECT_EQ(s.apply(req, rep), FaultReason::not_finite);
  for (const auto& a : rep.open_axes()) {
    EXPECT_EQ(a.mode, code(Mode::drive_off));
    EXPECT_EQ(a.d2, 0.0f);
  }
}

TEST(Safety, TripFromOutsideLatchesTheFirstReasonOnly) {
  Safety s;
  s.trip(FaultReason::user_request);
  s.trip(FaultReason::controller_late);
  EXPECT_EQ(s.reason(), FaultReason::user_request);
  EXPECT_EQ(s.counters().faults.load(), 1u);
  auto req = packet(0);
  auto rep = req;
  s.apply(req, rep);  // drives still on: ask for drive off
  EXPECT_EQ(rep.axes[0].mode, code(Mode::drive_off));
  req.infpar = 0;
  rep = req;
  s.apply(req, rep);  // drives off, mode 0: the reply goes through
  EXPECT_EQ(rep.axes[0].mode, 0);
  EXPECT_TRUE(s.faulted());
  s.reset();
  s.begin_cycle();
  EXPECT_FALSE(s.faulted());
}
