// watch_status / monitor / record (the loops under `axon blmc status|monitor|record`) against the
// board simulator on the in-process virtual bus.
#include "axon/blmc/host/observe.hpp"

#include "axon/blmc/host/board.hpp"
#include "sim_rig.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <sstream>
#include <vector>

namespace axon::blmc::host {
namespace {

using namespace testing;

BoardOptions watching_board() {
  BoardOptions o;
  o.recv_timeout_ms = 500;
  return o;
}

TEST(BlmcObserve, WatchStatusWithNoDurationHandsOverTheFirstStatusOnly) {
  SimRig rig;
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host, watching_board());
    std::vector<protocol::Status> seen;
    auto r = co_await watch_status(board, 0s, [&](const protocol::Status& s) {
      seen.push_back(s);
      return true;
    });
    CO_ASSERT(r);
    EXPECT_EQ(r.value(), 1u);
    CO_ASSERT(seen.size() == 1u);
    EXPECT_FALSE(seen[0].system_enabled);
  });
}

TEST(BlmcObserve, WatchStatusStopsWhenTheCallbackRefuses) {
  SimRig rig;
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host, watching_board());
    int calls = 0;
    auto r = co_await watch_status(board, 30s, [&](const protocol::Status&) { return ++calls < 2; });
    CO_ASSERT(r);
    EXPECT_EQ(r.value(), 2u);
    EXPECT_EQ(calls, 2);
  });
}

TEST(BlmcObserve, AnInterruptedWatchEndsWithoutAnError) {
  SimRig rig;
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host, watching_board());
    board.interrupt();
    int calls = 0;
    auto r = co_await watch_status(board, 30s, [&](const protocol::Status&) { return ++calls > 0; });
    CO_ASSERT(r);
    EXPECT_EQ(r.value(), 0u);
    const bool sampled = co_await monitor(board, 10ms, 30s, [&](double, const Measurements&) { return ++calls > 0; });
    EXPECT_TRUE(sampled);
    EXPECT_EQ(calls, 0);
  });
}

TEST(BlmcObserve, MonitorSamplesTheMeasurementsOfAnEnabledBoardForItsDuration) {
  SimRig rig;
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host, watching_board());
    auto enabled = co_await board.enable();
    CO_ASSERT(enabled);
    std::vector<double> times;
    std::vector<std::uint64_t> frames;
    const bool ok = co_await monitor(board, 20ms, 200ms, [&](double t, const Measurements& m) {
      times.push_back(t);
      frames.push_back(m.frames);
      return true;
    });
    EXPECT_TRUE(ok);
    CO_ASSERT(times.size() >= 2u);
    EXPECT_TRUE(std::is_sorted(times.begin(), times.end()));
    EXPECT_GE(times.back(), 0.2);
    EXPECT_GT(frames.back(), frames.front()) << "the board's data frames should keep arriving";
    auto disabled = co_await board.disable();
    EXPECT_TRUE(disabled);
  });
}

TEST(BlmcObserve, MonitorStopsWhenTheCallbackRefuses) {
  SimRig rig;
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host, watching_board());
    int calls = 0;
    const bool ok = co_await monitor(board, 10ms, 30s, [&](double, const Measurements&) {
      ++calls;
      return false;
    });
    EXPECT_FALSE(ok);
    EXPECT_EQ(calls, 1);
  });
}

TEST(BlmcObserve, RecordWritesEveryFrameForItsDurationAndRemovesItsTap) {
  SimRig rig;
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host, watching_board());
    auto enabled = co_await board.enable();
    CO_ASSERT(enabled);
    std::ostringstream out;
    can::CandumpWriter log(out);
    const auto n = co_await record(board, log, "can0", 200ms);
    EXPECT_GT(n, 0u);
    const std::string text = out.str();
    EXPECT_EQ(static_cast<std::uint64_t>(std::count(text.begin(), text.end(), '\n')), n);
    EXPECT_NE(text.find(" can0 "), std::string::npos) << text.substr(0, 200);
    auto disabled = co_await board.disable();  // after the recording: not in the log
    EXPECT_TRUE(disabled);
    co_await core::sleep_for(50ms);
    EXPECT_EQ(out.str(), text);
  });
}

}  // namespace
}  // namespace axon::blmc::host
