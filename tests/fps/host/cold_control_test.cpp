// The cold policy applied to the simulated plane over TCP: the PLC emulator's temperature crosses
// 0 degC and -10 degC, the host reads it, decides and sets every robot's speed and holding current.
#include "plane_rig.hpp"

#include "axon/fps/host/cold_control.hpp"

#include <boost/asio/detached.hpp>
#include <gtest/gtest.h>

#include <algorithm>

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::host;
using namespace axon::fps::host::testing;

TEST(ColdControl, FollowsThePlcTemperatureAcrossBothThresholds) {
  PlaneRig rig;
  rig.runner.run([&]() -> asio::awaitable<void> {
    co_await rig.connect();
    if (!rig.fpa) co_return;
    auto* plc = rig.sim->plc();
    ColdControl cold(*rig.fpa);

    // 15 degC (the emulator's start): normal speed, no heating, sent to all 12 at the first step.
    auto r = co_await cold.step();
    EXPECT_TRUE(r.has_value());
    if (!r) co_return;
    EXPECT_TRUE(r.value().changed);
    EXPECT_EQ(r.value().applied.size(), 12u) << r.value().to_text();
    EXPECT_TRUE(robots_at(*rig.sim, 5000, 0, 30));

    // Same temperature: nothing sent.
    r = co_await cold.step();
    EXPECT_TRUE(r.has_value() && !r.value().sent);

    // -2 degC on the plate: speed limited, no heating yet.
    EXPECT_TRUE(plc->set_sensor("fps_plate_edge", -2.0).has_value());
    r = co_await cold.step();
    EXPECT_TRUE(r.has_value() && r.value().changed && r.value().failed.empty());
    EXPECT_TRUE(robots_at(*rig.sim, 3000, 0, 30));

    // -12 degC: heating too.
    EXPECT_TRUE(plc->set_sensor("fps_plate_edge", -12.0).has_value());
    r = co_await cold.step();
    EXPECT_TRUE(r.has_value() && r.value().changed);
    EXPECT_TRUE(robots_at(*rig.sim, 3000, 45, 30));
    if (r) {
      EXPECT_NE(r.value().to_text().find("heating"), std::string::npos) << r.value().to_text();
    }

    // Back to exactly 0 degC: normal operation again ("below" is strict).
    EXPECT_TRUE(plc->set_sensor("fps_plate_edge", 0.0).has_value());
    r = co_await cold.step();
    EXPECT_TRUE(r.has_value() && r.value().changed);
    EXPECT_TRUE(robots_at(*rig.sim, 5000, 0, 30));
  });
}

TEST(ColdControl, WatchFollowsAScriptAndRetriesARobotThatMissedIt) {
  auto so = plane_sim_options();
  // Robot 4 does not answer its first SET_SPEED: it gets the settings at the next round.
  so.simulator.reply_faults.rules.push_back(drop_rule(replies_of(4, protocol::CommandId::set_speed), 0, 1));
  // The plate cools from +5 to -15 degC over 2 s of script time.
  so.plc_options.script = plc::SensorScript({{0, "fps_plate_centre", 5.0}, {2, "fps_plate_centre", -15.0}});
  PlaneRig rig(so);
  rig.runner.run([&]() -> asio::awaitable<void> {
    co_await rig.connect();
    if (!rig.fpa) co_return;
    ColdControl cold(*rig.fpa);
    bool stop = false;
    std::vector<ColdApplyReport> reports;
    asio::co_spawn(
        rig.runner.io,
        cold.watch(50ms, &stop,
                   [&](const Result<ColdApplyReport>& r) {
                     if (r && r.value().sent) reports.push_back(r.value());
                   }),
        asio::detached);
    // The robots end limited and heated once the script is below -10 degC.
    EXPECT_TRUE(co_await eventually([&] { return robots_at(*rig.sim, 3000, 45, 30); }, 20000));
    stop = true;
    co_await core::sleep_for(100ms);
    // Robot 4 failed once and was sent the settings again.
    bool failed4 = false, resent4 = false;
    for (const auto& rp : reports) {
      if (rp.failed.contains(4)) failed4 = true;
      if (failed4 && std::find(rp.applied.begin(), rp.applied.end(), 4) != rp.applied.end()) resent4 = true;
    }
    EXPECT_TRUE(failed4);
    EXPECT_TRUE(resent4);
    EXPECT_TRUE(cold.applied().has_value() && cold.applied()->heating);
  });
}

// The loop under `fps plane cold --watch --for S`: it ends by itself at its time limit, having sent
// the settings once (forced at the first step) and then only read the unchanged temperature.
TEST(ColdControl, WatchEndsAtItsTimeLimitAndSendsOnlyWhatChanged) {
  PlaneRig rig;
  rig.runner.run([&]() -> asio::awaitable<void> {
    co_await rig.connect();
    if (!rig.fpa) co_return;
    ColdControl cold(*rig.fpa);
    std::vector<ColdApplyReport> reports;
    auto watching = cold.watch(50ms, nullptr,
                               [&](const Result<ColdApplyReport>& r) {
                                 EXPECT_TRUE(r.has_value());
                                 if (r) reports.push_back(r.value());
                               },
                               400ms);
    co_await std::move(watching);  // returns: no stop flag, only the limit ends it
    if (reports.size() < 2u) {
      ADD_FAILURE() << "only " << reports.size() << " steps before the limit";
      co_return;
    }
    EXPECT_TRUE(reports.front().sent);
    EXPECT_EQ(reports.front().applied.size(), 12u);
    EXPECT_TRUE(std::none_of(reports.begin() + 1, reports.end(), [](const ColdApplyReport& r) { return r.sent; }));
  });
}

// A stop set while the loop waits for its next period ends it before that period is over.
TEST(ColdControl, WatchStopsBetweenStepsWithoutWaitingOutThePeriod) {
  PlaneRig rig;
  rig.runner.run([&]() -> asio::awaitable<void> {
    co_await rig.connect();
    if (!rig.fpa) co_return;
    ColdControl cold(*rig.fpa);
    bool stop = false;
    int steps = 0;
    bool ended = false;
    asio::co_spawn(
        rig.runner.io,
        [&]() -> asio::awaitable<void> {
          auto watching = cold.watch(std::chrono::hours(1), &stop, [&](const Result<ColdApplyReport>&) { ++steps; });
          co_await std::move(watching);
          ended = true;
        },
        asio::detached);
    EXPECT_TRUE(co_await eventually([&] { return steps == 1; }, 20000));
    stop = true;
    EXPECT_TRUE(co_await eventually([&] { return ended; }, 20000)) << "the hour-long wait was not cut short";
    EXPECT_EQ(steps, 1);
  });
}
