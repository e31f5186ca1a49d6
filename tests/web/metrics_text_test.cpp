#include "axon/web/metrics_text.hpp"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace axon::web
