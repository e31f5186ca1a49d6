#include "axon/c4g/host/safety.hpp"

#include "axon/c4g/protocol/mode.hpp"

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

TEST(Safety, FollowingErrorIsNotCheckedOutsideThePcLoopModes) {
  SafetyConfig c;
  c.following_error_override[0] = 0.1f;
  Safety s(c);
  auto req = packet(code(Mode::mode4));
  req.axes[0].d1 = 0.0f;
  req.axes[0].d3 = 5.0f;
  auto rep = req;
  EXPECT_EQ(s.apply(req, rep), FaultReason::none);
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
