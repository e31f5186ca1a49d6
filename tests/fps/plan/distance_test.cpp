// Exact segment distances against cases worked out by hand.
#include "axon/fps/plan/distance.hpp"

#include <gtest/gtest.h>

#include <random>

namespace axon::fps::plan {
namespace {

double d(Segment s, Segment t) { return segment_distance(s, t); }

TEST(PlanDistance, CrossingSegmentsAreAtZero) {
  // The diagonals of the square (0,0)-(2,2) meet at (1,1).
  EXPECT_EQ(d({{0, 0}, {2, 2}}, {{0, 2}, {2, 0}}), 0.0);
  EXPECT_TRUE(segments_cross_properly({{0, 0}, {2, 2}}, {{0, 2}, {2, 0}}));
}

TEST(PlanDistance, ParallelSegments) {
  // Both horizontal, overlapping in x over [1, 4]: the gap is the 3 mm between y = 0 and y = 3.
  EXPECT_DOUBLE_EQ(d({{0, 0}, {4, 0}}, {{1, 3}, {5, 3}}), 3.0);
  // Parallel without overlap: closest pair (1,0)-(4,4), sqrt(3^2 + 4^2) = 5.
  EXPECT_DOUBLE_EQ(d({{0, 0}, {1, 0}}, {{4, 4}, {6, 4}}), 5.0);
}

TEST(PlanDistance, CollinearSegments) {
  // On the x axis: [0,1] and [3,5] leave a gap of 2; [0,3] and [2,5] overlap.
  EXPECT_DOUBLE_EQ(d({{0, 0}, {1, 0}}, {{3, 0}, {5, 0}}), 2.0);
  EXPECT_EQ(d({{0, 0}, {3, 0}}, {{2, 0}, {5, 0}}), 0.0);
  EXPECT_FALSE(segments_cross_properly({{0, 0}, {3, 0}}, {{2, 0}, {5, 0}}));
}

TEST(PlanDistance, TeeAndTouchingEndpoints) {
  // A vertical stub ending 1 mm above the middle of a horizontal bar.
  EXPECT_DOUBLE_EQ(d({{0, 0}, {4, 0}}, {{2, 1}, {2, 5}}), 1.0);
  // The stub's end on the bar: touching counts as distance 0 though it is no proper crossing.
  EXPECT_EQ(d({{0, 0}, {4, 0}}, {{2, 0}, {2, 5}}), 0.0);
  EXPECT_FALSE(segments_cross_properly({{0, 0}, {4, 0}}, {{2, 0}, {2, 5}}));
  // Sharing an endpoint.
  EXPECT_EQ(d({{0, 0}, {4, 0}}, {{4, 0}, {6, 3}}), 0.0);
}

TEST(PlanDistance, DegenerateSegmentsArePoints) {
  // Point (2,3) over the bar [0,4] on the x axis: 3. Point (7,4) beyond its end (4,0): 3-4-5.
  EXPECT_DOUBLE_EQ(d({{2, 3}, {2, 3}}, {{0, 0}, {4, 0}}), 3.0);
  EXPECT_DOUBLE_EQ(d({{7, 4}, {7, 4}}, {{0, 0}, {4, 0}}), 5.0);
  // Two points (1,1) and (4,5): 3-4-5 again.
  EXPECT_DOUBLE_EQ(d({{1, 1}, {1, 1}}, {{4, 5}, {4, 5}}), 5.0);
  // A point on a zero-length segment at the same place.
  EXPECT_EQ(d({{1, 1}, {1, 1}}, {{1, 1}, {1, 1}}), 0.0);
  EXPECT_DOUBLE_EQ(point_segment_distance({2, 3}, {{0, 0}, {4, 0}}), 3.0);
}

TEST(PlanDistance, NearlyParallelLongSegmentsStayAccurate) {
  // Two 20 mm arms 4 mm apart, one tilted by 1e-9 rad: the gap is 4 mm to within 1e-7.
  const Segment s{{0, 0}, {20, 0}};
  const Segment t{{0, 4}, {20, 4 + 20e-9}};
  EXPECT_NEAR(d(s, t), 4.0, 1e-7);
}

TEST(PlanDistance, AgreesWithDenseSamplingAndIsSymmetric) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-10, 10);
  for (int k = 0; k < 200; ++k) {
    const Segment s{{u(rng), u(rng)}, {u(rng), u(rng)}};
    const Segment t{{u(rng), u(rng)}, {u(rng), u(rng)}};
    const double exact = d(s, t);
    EXPECT_NEAR(exact, d(t, s), 1e-12);
    EXPECT_NEAR(exact, d({s.b, s.a}, {t.b, t.a}), 1e-12);
    // Sampling can only find pairs at least as far apart as the exact minimum, and with 400 points
    // per segment (steps below 0.08 mm) it comes within that step of it.
    double sampled = 1e300;
    for (int i = 0; i <= 400; ++i) {
      const Vec2 p = s.a + (i / 400.0) * (s.b - s.a);
      sampled = std::min(sampled, point_segment_distance(p, t));
    }
    EXPECT_GE(sampled, exact - 1e-12);
    EXPECT_LE(sampled, exact + 0.08);
  }
}

}  // namespace
}  // namespace axon::fps::plan
