#include "axon/core/latency_histogram.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <utility>

using axon::core::LatencyHistogram;

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

TEST(LatencyHistogram, CountAboveIsExactOnBucketEdges) {
  LatencyHistogram h(1000, 100);  // 1 us buckets to 99 us
  for (std::int64_t v : {0, 999, 1000, 1001, 2000, 250'000}) h.add(v);
  EXPECT_EQ(h.count_above(0), 5u);
  EXPECT_EQ(h.count_above(1000), 3u);   // 1001, 2000 and the overflow sample
  EXPECT_EQ(h.count_above(2000), 1u);
  EXPECT_EQ(h.count_above(-1), 6u);
  EXPECT_EQ(h.count_above(98'000), 1u);
}

TEST(LatencyHistogram, MovedHistogramKeepsItsSamples) {
  LatencyHistogram a(1000, 100);
  a.add(10'000);
  a.add(20'000);
  LatencyHistogram b(std::move(a));
  EXPECT_EQ(b.count(), 2u);
  EXPECT_EQ(b.max(), 20'000);
  EXPECT_EQ(b.percentile(50), 10'000);
}
