#include "axon/web/metrics_text.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>

namespace axon::web {
namespace {

TEST(MetricsText, FamilyHasHelpAndTypeBeforeItsSamples) {
  MetricsText m;
  m.family("axon_test_requests_total", MetricType::counter, "Requests answered")
      .sample(std::uint64_t{3}, {{"robot", "17"}, {"bus", "gw1/2"}})
      .sample(std::uint64_t{0}, {{"robot", "18"}, {"bus", "gw1/2"}});
  m.family("axon_test_time_seconds", MetricType::gauge, "Time").sample(1.5);
  EXPECT_EQ(m.text(),
            "# HELP axon_test_requests_total Requests answered\n"
            "# TYPE axon_test_requests_total counter\n"
            "axon_test_requests_total{robot=\"17\",bus=\"gw1/2\"} 3\n"
            "axon_test_requests_total{robot=\"18\",bus=\"gw1/2\"} 0\n"
            "# HELP axon_test_time_seconds Time\n"
            "# TYPE axon_test_time_seconds gauge\n"
            "axon_test_time_seconds 1.5\n");
}

TEST(MetricsText, EscapesHelpAndLabelValues) {
  MetricsText m;
  m.family("x", MetricType::gauge, "a \\ b\nc \"quoted\"").sample(1.0, {{"name", "say \"hi\"\\\n"}});
  EXPECT_EQ(m.text(),
            "# HELP x a \\\\ b\\nc \"quoted\"\n# TYPE x gauge\n"
            "x{name=\"say \\\"hi\\\"\\\\\\n\"} 1\n");
}

TEST(MetricsText, WritesNonFiniteValuesAsPrometheusSpellsThem) {
  MetricsText m;
  m.family("x", MetricType::gauge, "h")
      .sample(std::numeric_limits<double>::quiet_NaN())
      .sample(std::numeric_limits<double>::infinity())
      .sample(-std::numeric_limits<double>::infinity());
  EXPECT_NE(m.text().find("x NaN\nx +Inf\nx -Inf\n"), std::string::npos) << m.text();
}

TEST(MetricsText, HistogramBucketsAreCumulativeAndEndAtInf) {
  const std::array<double, 2> bounds{1e-05, 0.0001};
  const std::array<std::uint64_t, 3> counts{4, 2, 1};
  MetricsText m;
  m.family("axon_test_jitter_seconds", MetricType::histogram, "Jitter").histogram(bounds, counts, 0.25, {{"board", "can0"}});
  EXPECT_EQ(m.text(),
            "# HELP axon_test_jitter_seconds Jitter\n"
            "# TYPE axon_test_jitter_seconds histogram\n"
            "axon_test_jitter_seconds_bucket{board=\"can0\",le=\"1e-05\"} 4\n"
            "axon_test_jitter_seconds_bucket{board=\"can0\",le=\"0.0001\"} 6\n"
            "axon_test_jitter_seconds_bucket{board=\"can0\",le=\"+Inf\"} 7\n"
            "axon_test_jitter_seconds_sum{board=\"can0\"} 0.25\n"
            "axon_test_jitter_seconds_count{board=\"can0\"} 7\n");
}

}  // namespace
}  // namespace axon::web
