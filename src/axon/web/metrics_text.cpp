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
                 type == MetricType::counter ? "counter" : "gauge");
  return *this;
}

void MetricsText::begin_sample(std::initializer_list<MetricLabel> labels) {
  out_ += name_;
  if (labels.size() == 0) return;
  out_ += '{';
  bool first = true;
  for (const auto& l : labels) {
    fmt::format_to(std::back_inserter(out_), "{}{}=\"{}\"", first ? "" : ",", l.name, escape_label_value(l.value));
    first = false;
  }
  out_ += '}';
}

MetricsText& MetricsText::sample(double value, std::initializer_list<MetricLabel> labels) {
  begin_sample(labels);
  if (std::isnan(value)) out_ += " NaN\n";
  else if (std::isinf(value)) out_ += value > 0 ? " +Inf\n" : " -Inf\n";
  else fmt::format_to(std::back_inserter(out_), " {}\n", value);
  return *this;
}

MetricsText& MetricsText::sample(std::uint64_t value, std::initializer_list<MetricLabel> labels) {
  begin_sample(labels);
  fmt::format_to(std::back_inserter(out_), " {}\n", value);
  return *this;
}

}  // namespace axon::web
