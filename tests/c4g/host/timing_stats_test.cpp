#include "axon/c4g/host/timing_stats.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

using namespace axon::c4g::host;

namespace {
// t1 = 0, 1.0, 2.1, 2.95 ms; cycle times 100, 600, 50, 200 us.
void feed(TimingStats& t) {
  t.record(0, 100'000);
  t.record(1'000'000, 1'600'000);
  t.record(2'100'000, 2'150'000);
  t.record(2'950'000, 3'150'000);
}
}  // namespace

TEST(TimingStats, ManualDefinitionsOnAHandComputedSequence) {
  TimingStats t(TimingConfig{1'000'000, 500'000, 1'000, 20'000});
  feed(t);
  EXPECT_EQ(t.cycles(), 4u);
  EXPECT_EQ(t.last_cycle_time_ns(), 200'000);
  EXPECT_EQ(t.worst_cycle_time_ns(), 600'000);
  EXPECT_EQ(t.inter_steps(), 3u);  // 1.0, 1.1, 0.85 ms
  EXPECT_EQ(t.last_inter_step_ns(), 850'000);
  EXPECT_EQ(t.min_inter_step_ns(), 850'000);
  EXPECT_EQ(t.max_inter_step_ns(), 1'100'000);
  EXPECT_EQ(t.min_jitter_ns(), -150'000);
  EXPECT_EQ(t.max_jitter_ns(), 100'000);
  EXPECT_DOUBLE_EQ(t.min_percent_jitter(), -15.0);
  EXPECT_DOUBLE_EQ(t.max_percent_jitter(), 10.0);
  EXPECT_EQ(t.missed_deadlines(), 1u);  // only the 600 us cycle is above 500 us
  EXPECT_EQ(t.cycle_times().count(), 4u);
  EXPECT_EQ(t.cycle_times().percentile(50), 100'000);  // ranks: 50, 100, 200, 600 us
  EXPECT_EQ(t.cycle_times().max(), 600'000);
  EXPECT_EQ(t.inter_step_times().percentile(100), 1'100'000);
}

TEST(TimingStats, DeadlineIsConfigurableAndStrict) {
  TimingStats t(TimingConfig{1'000'000, 200'000, 1'000, 1'000});
  feed(t);
  EXPECT_EQ(t.missed_deadlines(), 1u);  // 200 us is on the deadline, not over it
  TimingStats u(TimingConfig{1'000'000, 99'999, 1'000, 1'000});
  feed(u);
  EXPECT_EQ(u.missed_deadlines(), 3u);
}

TEST(TimingStats, PercentJitterFollowsTheNominalPeriod) {
  TimingStats t(TimingConfig{2'000'000, 500'000, 1'000, 1'000});
  t.record(0, 1);
  t.record(2'100'000, 2'100'001);
  EXPECT_EQ(t.min_jitter_ns(), 100'000);
  EXPECT_DOUBLE_EQ(t.max_percent_jitter(), 5.0);
}

TEST(TimingStats, RestartInterStepSkipsThePause) {
  TimingStats t;
  t.record(0, 10);
  t.record(1'000'000, 1'000'010);
  t.restart_inter_step();
  t.record(900'000'000, 900'000'010);  // after a long planned pause
  t.record(901'000'000, 901'000'010);
  EXPECT_EQ(t.inter_steps(), 2u);
  EXPECT_EQ(t.max_inter_step_ns(), 1'000'000);
  EXPECT_EQ(t.cycles(), 4u);
}

TEST(TimingStats, SummaryPrintsTheManualsFigures) {
  TimingStats t(TimingConfig{1'000'000, 500'000, 1'000, 20'000});
  EXPECT_NE(t.summary().find("needs two cycles"), std::string::npos);
  feed(t);
  const std::string s = t.summary();
  EXPECT_NE(s.find("Nominal inter-packet period       = 0.001000000 s"), std::string::npos) << s;
  EXPECT_NE(s.find("Worst cycle time                  = 0.000600000 s"), std::string::npos) << s;
  EXPECT_NE(s.find("[+0.000850000; +0.001100000] s"), std::string::npos) << s;
  EXPECT_NE(s.find("[-0.000150000; +0.000100000] s"), std::string::npos) << s;
  EXPECT_NE(s.find("[-15.000000000; +10.000000000] %"), std::string::npos) << s;
  EXPECT_NE(s.find("= 1\n"), std::string::npos) << s;  // missed deadlines
}

TEST(TimingStats, ResetStartsOver) {
  TimingStats t;
  feed(t);
  t.reset();
  EXPECT_EQ(t.cycles(), 0u);
  EXPECT_EQ(t.inter_steps(), 0u);
  EXPECT_EQ(t.worst_cycle_time_ns(), 0);
  EXPECT_EQ(t.missed_deadlines(), 0u);
  t.record(5, 7);
  EXPECT_EQ(t.inter_steps(), 0u);  // no step across the reset
  EXPECT_EQ(t.worst_cycle_time_ns(), 2);
}

// A controller exactly on its period, at 1 and at 2 ms: no jitter once the nominal period is the
// controller's (before, a fixed 1 ms nominal showed +100 % at 2 ms).
TEST(TimingStats, ExactPeriodHasNoJitterAtOneAndTwoMilliseconds) {
  for (const std::int64_t period : {1'000'000, 2'000'000}) {
    SCOPED_TRACE(period);
    TimingStats t;  // the default configuration: the period is the session's
    EXPECT_FALSE(t.nominal_known());
    for (std::int64_t k = 0; k < 10; ++k) t.record(k * period, k * period + 100'000);
    EXPECT_EQ(t.min_jitter_ns(), 0);  // unknown period: no figure rather than a wrong one
    EXPECT_NE(t.summary().find("Nominal inter-packet period       = unknown"), std::string::npos) << t.summary();
    EXPECT_EQ(t.summary().find("Percentage jitter"), std::string::npos) << t.summary();
    t.set_nominal_period_ns(period);  // the initialization packet arrived
    EXPECT_EQ(t.nominal_period_ns(), period);
    EXPECT_EQ(t.min_jitter_ns(), 0);
    EXPECT_EQ(t.max_jitter_ns(), 0);
    EXPECT_DOUBLE_EQ(t.max_percent_jitter(), 0.0);
    t.record(10 * period + period / 10, 10 * period + period / 10 + 100'000);  // one packet 10 % late
    EXPECT_EQ(t.max_jitter_ns(), period / 10);
    EXPECT_NEAR(t.max_percent_jitter(), 10.0, 1e-9);
    EXPECT_NE(t.summary().find("[+0.000000000; +10.000000000] %"), std::string::npos) << t.summary();
  }
}
