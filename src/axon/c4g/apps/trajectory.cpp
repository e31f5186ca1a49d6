#include "axon/c4g/apps/trajectory.hpp"

#include "axon/core/text.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

namespace axon::c4g::apps {

namespace {

Error parse_error(std::string_view source, std::size_t line, std::string_view what) {
  return Error(CoreErrc::invalid_argument, fmt::format("{}:{}: {}", source, line, what));
}

}  // namespace

std::optional<AngleUnit> parse_angle_unit(std::string_view text) noexcept {
  if (text == "rad" || text == "radians") return AngleUnit::rad;
  if (text == "deg" || text == "degrees") return AngleUnit::deg;
  return std::nullopt;
}

Result<Trajectory> Trajectory::parse(std::string_view text, std::string_view source, std::optional<AngleUnit> unit) {
  Trajectory t;
  t.unit_ = unit.value_or(AngleUnit::rad);
  bool have_header = false;
  std::size_t line_no = 0;
  while (!text.empty()) {
    const auto nl = text.find('\n');
    const std::string_view raw = text.substr(0, nl);
    text.remove_prefix(nl == std::string_view::npos ? text.size() : nl + 1);
    ++line_no;
    const std::string_view line = core::trim(raw);
    if (line.empty()) continue;
    if (line.front() == '#') {
      std::string_view body = core::trim(line.substr(1));
      if (body.starts_with("units:") || body.starts_with("unit:")) {
        const auto u = parse_angle_unit(core::trim(body.substr(body.find(':') + 1)));
        if (!u) return parse_error(source, line_no, "units must be rad or deg");
        if (have_header) return parse_error(source, line_no, "the units directive must come before the header");
        if (unit && *u != *unit)
          return parse_error(source, line_no,
                             fmt::format("the file says units {} but {} was asked for", *u == AngleUnit::deg ? "deg" : "rad",
                                         *unit == AngleUnit::deg ? "deg" : "rad"));
        t.unit_ = *u;
      }
      continue;
    }
    const auto fields = core::split_fields(line);
    if (!have_header) {
      if (fields.size() < 2) return parse_error(source, line_no, "header needs a time column and at least one axis");
      if (core::parse_number<double>(fields[0]))
        return parse_error(source, line_no, "expected a header line (e.g. t,j1,j2,...) before the data");
      for (const auto& f : fields)
        if (f.empty()) return parse_error(source, line_no, "empty column name in the header");
      t.axes_ = fields.size() - 1;
      have_header = true;
      continue;
    }
    if (fields.size() != t.axes_ + 1)
      return parse_error(source, line_no, fmt::format("expected {} fields (time and {} axes), got {}", t.axes_ + 1, t.axes_,
                                                      fields.size()));
    const auto time = core::parse_number<double>(fields[0]);
    if (!time || !std::isfinite(*time)) return parse_error(source, line_no, fmt::format("bad time '{}'", fields[0]));
    if (*time < 0) return parse_error(source, line_no, "time must not be negative");
    if (!t.times_.empty() && !(*time > t.times_.back()))
      return parse_error(source, line_no,
                         fmt::format("time {} does not increase (previous row {})", *time, t.times_.back()));
    const double scale = t.unit_ == AngleUnit::deg ? std::numbers::pi / 180.0 : 1.0;
    for (std::size_t i = 1; i < fields.size(); ++i) {
      const auto v = core::parse_number<double>(fields[i]);
      if (!v || !std::isfinite(*v))
        return parse_error(source, line_no, fmt::format("bad value '{}' in column {}", fields[i], i + 1));
      t.values_.push_back(*v * scale);
    }
    t.times_.push_back(*time);
  }
  if (!have_header) return parse_error(source, line_no, "no header line (e.g. t,j1,j2,...)");
  if (t.times_.empty()) return parse_error(source, line_no, "no data rows");
  return t;
}

Result<Trajectory> Trajectory::load(const std::string& path, std::optional<AngleUnit> unit) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error(CoreErrc::invalid_argument, fmt::format("cannot open trajectory file {}", path));
  std::ostringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  return parse(text, path, unit);
}

Result<Trajectory> Trajectory::from_rows(std::vector<double> times, std::vector<std::vector<double>> rows_rad) {
  if (times.empty() || times.size() != rows_rad.size() || rows_rad.front().empty())
    return Error(CoreErrc::invalid_argument, "trajectory: need as many rows as times, at least one, with one axis or more");
  Trajectory t;
  t.axes_ = rows_rad.front().size();
  for (std::size_t r = 0; r < times.size(); ++r) {
    if (rows_rad[r].size() != t.axes_ || !std::isfinite(times[r]) || (r > 0 && !(times[r] > times[r - 1])))
      return Error(CoreErrc::invalid_argument, fmt::format("trajectory: bad row {}", r));
    for (double v : rows_rad[r]) {
      if (!std::isfinite(v)) return Error(CoreErrc::invalid_argument, fmt::format("trajectory: bad value in row {}", r));
      t.values_.push_back(v);
    }
  }
  t.times_ = std::move(times);
  return t;
}

Result<Trajectory> Trajectory::from_table(std::span<const double> values, std::size_t axes, double row_step, AngleUnit unit) {
  if (axes == 0 || values.empty() || values.size() % axes != 0)
    return Error(CoreErrc::invalid_argument,
                 fmt::format("trajectory: {} values do not make whole rows of {} axes (at least one row and one axis)",
                             values.size(), axes));
  if (!std::isfinite(row_step) || row_step <= 0)
    return Error(CoreErrc::invalid_argument, fmt::format("trajectory: the step between rows must be > 0, got {}", row_step));
  Trajectory t;
  t.axes_ = axes;
  t.unit_ = unit;
  const double scale = unit == AngleUnit::deg ? std::numbers::pi / 180.0 : 1.0;
  const std::size_t rows = values.size() / axes;
  t.values_.reserve(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i]))
      return Error(CoreErrc::invalid_argument, fmt::format("trajectory: row {} axis {} is not a finite number", i / axes, i % axes + 1));
    t.values_.push_back(values[i] * scale);
  }
  t.times_.reserve(rows);
  for (std::size_t r = 0; r < rows; ++r) t.times_.push_back(static_cast<double>(r) * row_step);
  return t;
}

void Trajectory::sample(double t, std::span<double> position, std::span<double> velocity) const noexcept {
  const std::size_t n = std::min({axes_, position.size(), velocity.size()});
  if (t <= times_.front() || times_.size() == 1) {
    for (std::size_t i = 0; i < n; ++i) {
      position[i] = values_[i];
      velocity[i] = 0;
    }
    return;
  }
  if (t >= times_.back()) {
    const std::size_t last = (times_.size() - 1) * axes_;
    for (std::size_t i = 0; i < n; ++i) {
      position[i] = values_[last + i];
      velocity[i] = 0;
    }
    return;
  }
  // First row with time > t; the segment is [k - 1, k].
  const auto it = std::upper_bound(times_.begin(), times_.end(), t);
  const std::size_t k = static_cast<std::size_t>(it - times_.begin());
  const double t0 = times_[k - 1], t1 = times_[k];
  const double a = (t - t0) / (t1 - t0);
  for (std::size_t i = 0; i < n; ++i) {
    const double p0 = values_[(k - 1) * axes_ + i], p1 = values_[k * axes_ + i];
    position[i] = p0 + a * (p1 - p0);
    velocity[i] = (p1 - p0) / (t1 - t0);
  }
}

}  // namespace axon::c4g::apps
