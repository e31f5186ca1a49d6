#include "axon/c4g/apps/trajectory.hpp"

#include <gtest/gtest.h>

#include <array>
#include <limits>
#include <numbers>

using namespace axon::c4g::apps;

namespace {
std::string error_of(std::string_view text, std::optional<AngleUnit> unit = std::nullopt) {
  auto r = Trajectory::parse(text, "traj.csv", unit);
  return r ? std::string("parsed") : r.error().detail;
}
}  // namespace

TEST(Trajectory, ParsesHeaderCommentsUnitsAndRows) {
  const auto t = Trajectory::parse("# a test\n# units: deg\n\nt, j1, j2\n0, 0, 90\n0.5, 10, 90\r\n1.0,20,-90\n", "x").value();
  EXPECT_EQ(t.axes(), 2u);
  EXPECT_EQ(t.rows(), 3u);
  EXPECT_EQ(t.file_unit(), AngleUnit::deg);
  EXPECT_DOUBLE_EQ(t.duration(), 1.0);
  EXPECT_NEAR(t.value(1, 0), 10 * std::numbers::pi / 180, 1e-12);
  EXPECT_NEAR(t.value(2, 1), -std::numbers::pi / 2, 1e-12);
}

TEST(Trajectory, RadiansByDefaultAndDegreesOnRequest) {
  EXPECT_DOUBLE_EQ(Trajectory::parse("t,a\n0,1.5\n", "x").value().value(0, 0), 1.5);
  EXPECT_NEAR(Trajectory::parse("t,a\n0,180\n", "x", AngleUnit::deg).value().value(0, 0), std::numbers::pi, 1e-12);
}

TEST(Trajectory, SamplesByLinearInterpolationAndHoldsTheEnds) {
  const auto t = Trajectory::parse("t,a,b\n1,0,10\n2,1,10\n4,5,0\n", "x").value();
  std::array<double, 2> p{}, v{};
  t.sample(1.5, p, v);
  EXPECT_DOUBLE_EQ(p[0], 0.5);
  EXPECT_DOUBLE_EQ(v[0], 1.0);
  EXPECT_DOUBLE_EQ(p[1], 10);
  t.sample(3, p, v);
  EXPECT_DOUBLE_EQ(p[0], 3.0);
  EXPECT_DOUBLE_EQ(v[0], 2.0);
  EXPECT_DOUBLE_EQ(p[1], 5.0);
  EXPECT_DOUBLE_EQ(v[1], -5.0);
  t.sample(0, p, v);
  EXPECT_DOUBLE_EQ(p[0], 0);
  EXPECT_DOUBLE_EQ(v[0], 0);
  t.sample(9, p, v);
  EXPECT_DOUBLE_EQ(p[0], 5);
  EXPECT_DOUBLE_EQ(v[0], 0);
}

TEST(Trajectory, ErrorsNameTheLine) {
  EXPECT_EQ(error_of("t,a,b\n0,1,2\n1,2\n"), "traj.csv:3: expected 3 fields (time and 2 axes), got 2");
  EXPECT_EQ(error_of("t,a\n0,1\n0,2\n"), "traj.csv:3: time 0 does not increase (previous row 0)");
  EXPECT_EQ(error_of("t,a\n\n0,x1\n"), "traj.csv:3: bad value 'x1' in column 2");
  EXPECT_EQ(error_of("# c\n0,1\n"), "traj.csv:2: expected a header line (e.g. t,j1,j2,...) before the data");
  EXPECT_EQ(error_of("t,a\n-1,0\n"), "traj.csv:2: time must not be negative");
  EXPECT_EQ(error_of("t,a\n0,nan\n"), "traj.csv:2: bad value 'nan' in column 2");
  EXPECT_EQ(error_of("t,a\n"), "traj.csv:1: no data rows");
  EXPECT_EQ(error_of("# units: grad\nt,a\n0,0\n"), "traj.csv:1: units must be rad or deg");
  EXPECT_EQ(error_of("# units: deg\nt,a\n0,0\n", AngleUnit::rad), "traj.csv:1: the file says units deg but rad was asked for");
}

TEST(Trajectory, LoadReportsAMissingFile) {
  auto r = Trajectory::load("/nonexistent/traj.csv");
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().detail.find("/nonexistent/traj.csv"), std::string::npos);
}

TEST(Trajectory, FromATableOfRowsAStepApart) {
  const std::array<double, 6> values{0, 90, 10, 90, 20, -90};  // 3 rows x 2 axes, degrees
  const auto t = Trajectory::from_table(values, 2, 0.5, AngleUnit::deg).value();
  EXPECT_EQ(t.axes(), 2u);
  EXPECT_EQ(t.rows(), 3u);
  EXPECT_DOUBLE_EQ(t.time(2), 1.0);
  EXPECT_NEAR(t.value(1, 0), 10 * std::numbers::pi / 180, 1e-12);
  EXPECT_NEAR(t.value(2, 1), -std::numbers::pi / 2, 1e-12);
  EXPECT_DOUBLE_EQ(Trajectory::from_table(values, 3, 1.0).value().value(1, 2), -90);  // radians as given
}

TEST(Trajectory, FromATableRefusesPartialRowsBadStepsAndNonFiniteValues) {
  const std::array<double, 5> five{0, 1, 2, 3, 4};
  auto detail = [](const axon::Result<Trajectory>& r) { return r ? std::string("made") : r.error().detail; };
  EXPECT_EQ(detail(Trajectory::from_table(five, 2, 1.0)),
            "trajectory: 5 values do not make whole rows of 2 axes (at least one row and one axis)");
  EXPECT_EQ(detail(Trajectory::from_table({}, 2, 1.0)),
            "trajectory: 0 values do not make whole rows of 2 axes (at least one row and one axis)");
  EXPECT_EQ(detail(Trajectory::from_table(five, 0, 1.0)),
            "trajectory: 5 values do not make whole rows of 0 axes (at least one row and one axis)");
  EXPECT_EQ(detail(Trajectory::from_table(five, 5, 0.0)), "trajectory: the step between rows must be > 0, got 0");
  const std::array<double, 4> nan{0, 1, std::numeric_limits<double>::quiet_NaN(), 3};
  EXPECT_EQ(detail(Trajectory::from_table(nan, 2, 1.0)), "trajectory: row 1 axis 1 is not a finite number");
  EXPECT_EQ(Trajectory::from_table(nan, 2, 1.0).error().code, axon::CoreErrc::invalid_argument);
}
