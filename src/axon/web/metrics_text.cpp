#include "axon/web/metrics_text.hpp"

#include <fmt/format.h>

#include <cmath>

namespace axon::web {
namespace {

std::string escape(std::string_view text, bool quotes) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    if (c == '\\') out += "\\\\";
    else if (c == '\n') out += "\\n";
    else if (c == '"' && quotes) out += "\\\"";
    else out += c;
  }
  return out;
}

}  // namespace

std::string escape_help(std::string_view text) { return escape(text, false); }
std::string escape_label_value(std::string_view text) { return escape(text, true); }

MetricsText& MetricsText::family(std::string_view name, MetricType type, std::string_view help) {
  name_.assign(name);
  fmt::format_to(std::back_inserter(out_), "# HELP {} {}\n# TYPE {} {}\n", name, escape_help(help), name,
                 type == MetricType::counter ? "counter" : type == MetricType::gauge ? "gauge" : "histogram");
  return *this;
}

void MetricsText::begin_sample(std::initializer_list<MetricLabel> labels, std::string_view suffix, const MetricLabel* le) {
  out_ += name_;
  out_ += suffix;
  if (labels.size() == 0 && le == nullptr) return;
  out_ += '{';
  bool first = true;
  const auto add = [&](const MetricLabel& l) {
    fmt::format_to(std::back_inserter(out_), "{}{}=\"{}\"", first ? "" : ",", l.name, escape_label_value(l.value));
    first = false;
  };
  for (const auto& l : labels) add(l);
  if (le != nullptr) add(*le);
  out_ += '}';
}

void MetricsText::write_value(double v) {
  if (std::isnan(v)) out_ += " NaN\n";
  else if (std::isinf(v)) out_ += v > 0 ? " +Inf\n" : " -Inf\n";
  else fmt::format_to(std::back_inserter(out_), " {}\n", v);
}

MetricsText& MetricsText::sample(double v, std::initializer_list<MetricLabel> labels) {
  begin_sample(labels);
  write_value(v);
  return *this;
}

MetricsText& MetricsText::sample(std::uint64_t value, std::initializer_list<MetricLabel> labels) {
  begin_sample(labels);
  fmt::format_to(std::back_inserter(out_), " {}\n", value);
  return *this;
}

MetricsText& MetricsText::histogram(std::span<const double> upper_bounds, std::span<const std::uint64_t> counts, double sum,
                                    std::initializer_list<MetricLabel> labels) {
  std::uint64_t cumulative = 0;
  for (std::size_t i = 0; i <= upper_bounds.size(); ++i) {
    cumulative += i < counts.size() ? counts[i] : 0;
    const std::string bound = i < upper_bounds.size() ? fmt::format("{}", upper_bounds[i]) : "+Inf";
    const MetricLabel le{"le", bound};
    begin_sample(labels, "_bucket", &le);
    fmt::format_to(std::back_inserter(out_), " {}\n", cumulative);
  }
  begin_sample(labels, "_sum");
  write_value(sum);
  begin_sample(labels, "_count");
  fmt::format_to(std::back_inserter(out_), " {}\n", cumulative);
  return *this;
}

}  // namespace axon::web
