// run_control / run_pd / run_homing (the workflow under `axon blmc current|pd|home` and MotorBoard)
// against the board simulator on the in-process virtual bus, and validate()'s refusals.
#include "axon/blmc/host/control_run.hpp"
#include "axon/blmc/host/error.hpp"
#include "axon/blmc/host/motor_session.hpp"
#include "axon/blmc/host/session_log.hpp"
#include "sim_rig.hpp"

#include <gtest/gtest.h>

#include <sstream>

namespace axon::blmc::host {
namespace {

using namespace testing;

// With slack for a loaded machine (see test_limits()), here also for the board's receive timeout.
ControlOptions options(core::Duration duration) {
  ControlOptions o;
  o.limits = test_limits();
  o.limits.stale_after = 500ms;
  o.loop = loop_options();
  o.duration = duration;
  o.refresh = 20ms;
  return o;
}

BoardOptions slack() {
  BoardOptions o;
  o.recv_timeout_ms = 500;
  return o;
}

TEST(BlmcControlRun, ValidateRefusesAPeriodTheReceiveTimeoutWouldTrip) {
  auto o = options(1s);
  EXPECT_TRUE(validate(o, 50));
  o.loop.period = 100ms;
  const auto slow = validate(o, 50);
  ASSERT_FALSE(slow);
  EXPECT_TRUE(slow.error().code == std::errc::invalid_argument);
  EXPECT_NE(slow.error().detail.find("receive timeout of 50 ms"), std::string::npos) << slow.error().detail;
  EXPECT_TRUE(validate(o, 0)) << "no receive timeout: any period";
  o.loop.period = 50us;  // 20 kHz
  EXPECT_FALSE(validate(o, 50));
  o.loop.period = 0ms;
  EXPECT_FALSE(validate(o, 50));
  o = options(1s);
  o.limits.max_current_a = -1;
  EXPECT_FALSE(validate(o, 50));
}

TEST(BlmcControlRun, PdHoldsBothMotorsAndHandsTheBoardBackOutOfCyclicMode) {
  SimRig rig;
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host, slack());
    std::uint64_t records = 0;
    int refreshes = 0;
    ControlHooks hooks;
    hooks.record = [&](const CycleRecord&) { ++records; };
    hooks.refresh = [&](double t, const CycleRecord*) {
      EXPECT_GE(t, 0.0);
      ++refreshes;
      return true;
    };
    const std::function<asio::awaitable<Result<PdRun>>()> body = [&]() -> asio::awaitable<Result<PdRun>> {
      auto r = co_await run_pd(board, {10, 0.1}, {PdTarget{true, 0.3, 1, 0}, PdTarget{true, 0, 0, 0.2}}, options(1500ms),
                               hooks, 300ms);
      co_return r;
    };
    auto run = co_await with_motors_enabled<Result<PdRun>>(board, body);
    CO_ASSERT(run.enable && run.value && *run.value);
    const auto& pd = run.value->value();
    EXPECT_FALSE(pd.control.fault) << pd.control.fault->fault.describe();
    EXPECT_FALSE(pd.control.stopped);
    EXPECT_GT(pd.control.stats.cycles, 800u);
    EXPECT_EQ(records + pd.control.records_dropped, pd.control.stats.cycles);
    EXPECT_GT(refreshes, 10);
    for (int k = 0; k < 2; ++k) {
      EXPECT_GT(pd.tracking[static_cast<std::size_t>(k)].samples, 0u);
      EXPECT_LT(pd.tracking[static_cast<std::size_t>(k)].max_abs_error_rev, 0.1) << "motor " << k + 1;
    }
    EXPECT_TRUE(run.disable);
  });
}

TEST(BlmcControlRun, AnInterruptEndsTheRunAsAStop) {
  SimRig rig;
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host, slack());
    const std::function<asio::awaitable<Result<ControlOutcome>>()> body =
        [&]() -> asio::awaitable<Result<ControlOutcome>> {
      FunctionController ctl([](const ControlInput&, std::span<MotorPair>) {});
      ControlHooks hooks;
      hooks.refresh = [&](double t, const CycleRecord*) {
        if (t > 0.3) board.interrupt();
        return true;
      };
      auto r = co_await run_control(board, ctl, options(0s), hooks);
      co_return r;
    };
    auto run = co_await with_motors_enabled<Result<ControlOutcome>>(board, body);
    CO_ASSERT(run.value && *run.value);
    EXPECT_TRUE(run.value->value().stopped);
    EXPECT_FALSE(run.value->value().fault);
    EXPECT_TRUE(run.disable);
  });
}

TEST(BlmcControlRun, HomingReportsTheIndexOfEachMotor) {
  auto cfg = SimRig::config();
  cfg.motors[0].index_offset_rev = 0.4;
  cfg.motors[1].index_offset_rev = 0.1;
  SimRig rig(cfg);
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host, slack());
    HomingOptions h;
    h.speed_rev_s = -1;  // downwards: from 0 the marks come at -0.6 and -0.9 rev
    const std::function<asio::awaitable<Result<HomingRun>>()> body = [&]() -> asio::awaitable<Result<HomingRun>> {
      auto r = co_await run_homing(board, h, options(10s));
      co_return r;
    };
    auto run = co_await with_motors_enabled<Result<HomingRun>>(board, body);
    CO_ASSERT(run.value && *run.value);
    const auto& home = run.value->value();
    EXPECT_TRUE(home.all_found);
    EXPECT_NEAR(home.motors[0].index_rev, -0.6, 2e-4);
    EXPECT_NEAR(home.motors[1].index_rev, -0.9, 2e-4);
  });
}

TEST(BlmcSessionLog, CandumpTapWritesEveryFrameWithAStamp) {
  std::ostringstream out;
  can::CandumpWriter w(out);
  std::uint64_t n = 0;
  auto tap = candump_tap(w, "can0", &n);
  tap(can::Frame::parse("005#0000000000000000").value(), true);
  tap(can::Frame::parse("010#07").value(), false);
  EXPECT_EQ(n, 2u);
  EXPECT_NE(out.str().find(") can0 005#0000000000000000\n"), std::string::npos) << out.str();
  EXPECT_EQ(out.str().rfind("(", 0), 0u) << "no time stamp: " << out.str();
}

}  // namespace
}  // namespace axon::blmc::host
