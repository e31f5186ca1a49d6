#include "c4g/host/timing_stats.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

using namespace axon::c4g::host;

TEST(LatencyHistogram, PercentilesByNearestRankOnBucketEdges) {
  LatencyHistogram h(10, 11);  // (0, 100] in 10 ns buckets
  for (std::int64_t v : {5, 15, 15, 25, 95, 250}) h.add(v);
  EXPECT_EQ(h.count(), 6u);
  EXPECT_EQ(h.overflow(), 1u);
  EXPECT_EQ(h.bucket_count(2), 2u);  // (10, 20]
  EXPECT_EQ(h.min(), 5);
  EXPECT_EQ(h.max(), 250);
  EXPECT_DOUBLE_EQ(h.mean(), 405.0 / 6.0);
  EXPECT_EQ(h.percentile(10), 10);   // rank 1: the 5 in (0,10]
  EXPECT_EQ(h.percentile(50), 20);   // rank 3: the second 15 in (10,20]
  EXPECT_EQ(h.percentile(66.7), 100);  // rank 5: the 95 in (90,100]
  EXPECT_EQ(h.percentile(99), 250);  // rank 6: in the overflow bucket -> the exact max
  EXPECT_EQ(h.percentile(100), 250);
}

TEST(LatencyHistogram, UniformSamplesGiveExactPercentilesAtUnitWidth) {
  LatencyHistogram h(1, 2000);
  for (std::int64_t v = 1; v <= 1000; ++v) h.add(v);
  EXPECT_EQ(h.percentile(50), 500);
  EXPECT_EQ(h.percentile(99), 990);
  EXPECT_EQ(h.percentile(99.9), 999);
  EXPECT_EQ(h.percentile(100), 1000);
}

TEST(LatencyHistogram, ValuesOnAnEdgeBelongToTheLowerBucket) {
  LatencyHistogram h(10, 11);
  h.add(20);
  h.add(100);
  h.add(101);
  EXPECT_EQ(h.bucket_count(2), 1u);
  EXPECT_EQ(h.bucket_count(10), 1u);
  EXPECT_EQ(h.overflow(), 1u);
}

TEST(LatencyHistogram, PercentileNeverExceedsTheMaximum) {
  LatencyHistogram h(1000, 10);
  h.add(3);
  EXPECT_EQ(h.percentile(50), 3);
}

TEST(LatencyHistogram, NegativeSamplesCountInTheFirstBucketAndResetEmpties) {
  LatencyHistogram h(10, 10);
  h.add(-3);
  EXPECT_EQ(h.bucket_count(0), 1u);
  EXPECT_EQ(h.min(), -3);
  h.reset();
  EXPECT_EQ(h.count(), 0u);
  EXPECT_EQ(h.percentile(50), 0);
  EXPECT_EQ(h.max(), 0);
  EXPECT_EQ(h.bucket_count(0), 0u);
}

TEST(LatencyHistogram, RejectsEmptyGeometry) {
  EXPECT_THROW(LatencyHistogram(0, 10), std::invalid_argument);
  EXPECT_THROW(LatencyHistogram(10, 0), std::invalid_argument);
}

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
