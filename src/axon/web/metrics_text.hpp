// The Prometheus text exposition format (version 0.0.4), as /metrics serves it.
//
// A metric family is announced once with its # HELP and # TYPE lines, then its samples follow,
// one per label set. Names carry their unit as a suffix (_seconds, _bytes, _degrees) and counters
// end in _total, as Prometheus's naming rules ask (`promtool check metrics` checks them). Help
// text and label values are escaped here; names are the caller's constants and are not checked.
// A histogram's samples are its cumulative buckets (name_bucket{le="..."}, the last le="+Inf"),
// name_sum and name_count.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <span>
#include <string>
#include <string_view>

namespace axon::web {

enum class MetricType { counter, gauge, histogram };

struct MetricLabel {
  std::string_view name;
  std::string_view value;
};

class MetricsText {
 public:
  // Starts a family: its HELP and TYPE lines. Samples written after it belong to it.
  MetricsText& family(std::string_view name, MetricType type, std::string_view help);
  // One sample of the current family, e.g. sample(requests, {{"robot", "17"}, {"bus", "gw1/2"}}).
  MetricsText& sample(double value, std::initializer_list<MetricLabel> labels = {});
  MetricsText& sample(std::uint64_t value, std::initializer_list<MetricLabel> labels = {});
  // One histogram of the current family (a MetricType::histogram): counts[i] observations fell in
  // (upper_bounds[i-1], upper_bounds[i]], counts[upper_bounds.size()] above the last bound (so
  // counts has one element more than upper_bounds, which ascend); `sum` of every observation.
  MetricsText& histogram(std::span<const double> upper_bounds, std::span<const std::uint64_t> counts, double sum,
                         std::initializer_list<MetricLabel> labels = {});

  [[nodiscard]] const std::string& text() const noexcept { return out_; }
  [[nodiscard]] std::string take() noexcept { return std::move(out_); }

 private:
  void begin_sample(std::initializer_list<MetricLabel> labels, std::string_view suffix = {}, const MetricLabel* le = nullptr);
  void write_value(double v);

  std::string out_;
  std::string name_;  // of the current family
};

// A HELP text with backslashes and newlines escaped; a label value with double quotes escaped too.
[[nodiscard]] std::string escape_help(std::string_view text);
[[nodiscard]] std::string escape_label_value(std::string_view text);

}  // namespace axon::web
