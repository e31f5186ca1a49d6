#include "axon/blmc/host/loop_timing.hpp"

#include <gtest/gtest.h>

namespace axon::blmc::host {
namespace {

using namespace std::chrono_literals;
core::TimePoint at_us(int us) { return core::TimePoint(std::chrono::microseconds(us)); }

TEST(BlmcLoopTiming, PeriodJitterAndLateness) {
  LoopTiming t(1ms);
  t.cycle_started(at_us(1000), at_us(1000));
  t.cycle_finished(at_us(1100), at_us(2000));
  t.cycle_started(at_us(2000), at_us(2050));  // 1050 us period, 50 us late
  t.cycle_finished(at_us(2100), at_us(3000));
  t.cycle_started(at_us(3000), at_us(3000));  // 950 us period
  t.cycle_finished(at_us(3300), at_us(4000));
  const auto s = t.stats();
  EXPECT_EQ(s.cycles, 3u);
  EXPECT_EQ(s.overruns, 0u);
  EXPECT_EQ(s.period_min, 950us);
  EXPECT_EQ(s.period_max, 1050us);
  EXPECT_EQ(s.period_mean, 1000us);
  EXPECT_EQ(s.jitter_max, 50us);
  EXPECT_EQ(s.jitter_p50, 50us);
  EXPECT_EQ(s.late_max, 50us);
  EXPECT_EQ(s.compute_max, 300us);
  EXPECT_EQ(s.compute_mean, (100us + 50us + 300us) / 3);
}

TEST(BlmcLoopTiming, OverrunWhenACycleEndsAfterTheNextDeadline) {
  LoopTiming t(1ms);
  t.cycle_started(at_us(0), at_us(0));
  t.cycle_finished(at_us(1200), at_us(1000));
  t.skipped(1);
  t.cycle_started(at_us(2000), at_us(2000));
  t.cycle_finished(at_us(2100), at_us(3000));
  const auto s = t.stats();
  EXPECT_EQ(s.overruns, 1u);
  EXPECT_EQ(s.missed, 1u);
  EXPECT_EQ(s.jitter_max, 1000us);  // 2 ms period
}

TEST(BlmcLoopTiming, PercentilesFromTheHistogram) {
  LoopTiming t(1ms);
  int now = 0;
  t.cycle_started(at_us(now), at_us(now));
  for (int i = 0; i < 100; ++i) {
    now += i == 99 ? 1400 : 1000;  // one 400 us outlier
    t.cycle_started(at_us(now), at_us(now));
  }
  const auto s = t.stats();
  EXPECT_EQ(s.jitter_p50, 0us);
  EXPECT_EQ(s.jitter_max, 400us);
  EXPECT_EQ(s.jitter_p99, 0us);  // 99 of 100 periods were exact
}

TEST(BlmcLoopTiming, JitterBeyondTheHistogramReadsAsTheExactMaximum) {
  LoopTiming t(1ms);
  t.cycle_started(at_us(0), at_us(0));
  t.cycle_started(at_us(20000), at_us(20000));
  const auto s = t.stats();
  EXPECT_EQ(s.jitter_max, 19ms);
  EXPECT_EQ(s.jitter_p99, 19ms);
}

}  // namespace
}  // namespace axon::blmc::host
