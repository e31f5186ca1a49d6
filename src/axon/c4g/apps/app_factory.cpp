#include "axon/c4g/apps/app_factory.hpp"

#include "axon/c4g/apps/contribute.hpp"
#include "axon/c4g/apps/correct.hpp"
#include "axon/c4g/apps/echo.hpp"
#include "axon/c4g/apps/handover.hpp"
#include "axon/c4g/apps/monitor.hpp"
#include "axon/c4g/apps/pid.hpp"
#include "axon/c4g/apps/sensor_feed.hpp"
#include "axon/c4g/apps/stream.hpp"
#include "axon/c4g/apps/trajectory.hpp"
#include "axon/net/endpoint.hpp"

#include <fmt/format.h>

#include <numbers>
#include <optional>

namespace axon::c4g::apps {

namespace {

Exception bad(std::string text) { return Exception(Error(CoreErrc::invalid_argument, std::move(text))); }

std::vector<double> deg_to_rad(const std::vector<double>& v) {
  std::vector<double> out;
  for (double d : v) out.push_back(d * std::numbers::pi / 180.0);
  return out;
}

std::optional<AngleUnit> unit_of(const AppConfig& c) {
  if (c.units.empty()) return std::nullopt;
  auto unit = parse_angle_unit(c.units);
  if (!unit) throw bad("--units must be rad or deg");
  return unit;
}

// "MOTION_TYPE=FILE.csv" with a motion type 1..255.
StreamSegment parse_segment(const std::string& spec, std::optional<AngleUnit> unit) {
  const auto eq = spec.find('=');
  int type = 0;
  try {
    type = eq == std::string::npos ? 0 : std::stoi(spec.substr(0, eq));
  } catch (const std::exception&) {
    type = 0;
  }
  if (eq == std::string::npos || type < 1 || type > 255 || eq + 1 >= spec.size())
    throw bad(fmt::format("--segment '{}': expected MOTION_TYPE=FILE.csv with a motion type 1..255", spec));
  return {static_cast<std::uint8_t>(type), std::make_shared<Trajectory>(Trajectory::load(spec.substr(eq + 1), unit).value())};
}

bool has_segments(const AppConfig& c) { return !c.segments.empty() || !c.segment_tables.empty(); }
bool has_trajectory(const AppConfig& c) { return !c.file.empty() || c.trajectory || has_segments(c); }

// The segments from files and from tables, each motion type once, each with a trajectory.
std::vector<StreamSegment> segments_of(const AppConfig& c, std::optional<AngleUnit> unit) {
  std::vector<StreamSegment> all;
  for (const auto& spec : c.segments) all.push_back(parse_segment(spec, unit));
  for (const auto& t : c.segment_tables) {
    if (t.motion_type < 1 || !t.trajectory) throw bad("a segment needs a motion type 1..255 and a trajectory");
    all.push_back(t);
  }
  for (std::size_t i = 0; i < all.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (all[i].motion_type == all[j].motion_type)
        throw bad(fmt::format("two segments for motion type {}", unsigned{all[i].motion_type}));
  return all;
}

StreamOptions stream_options(const AppConfig& c, const std::string& file) {
  const auto unit = unit_of(c);
  StreamOptions s;
  if (!file.empty() && has_segments(c)) throw bad("give --file or --segment, not both");
  if (c.trajectory && (!file.empty() || has_segments(c))) throw bad("give a trajectory or --file/--segment, not both");
  if (!file.empty()) s.trajectory = std::make_shared<Trajectory>(Trajectory::load(file, unit).value());
  if (c.trajectory) s.trajectory = c.trajectory;
  s.per_cycle = c.per_cycle;
  s.segments = segments_of(c, unit);
  s.mode = c.mode;
  s.arm = c.arm;
  s.relative = c.relative;
  s.start_tolerance_rad = c.start_tolerance_deg * std::numbers::pi / 180.0;
  s.max_motor_speed = c.max_motor_speed;
  s.stop_ramp_s = std::min(c.ramp_s, 0.5);
  return s;
}

CorrectOptions correct_options(const AppConfig& c, const std::string& file, const std::function<void(const std::string&)>& say) {
  const auto unit = unit_of(c);
  CorrectOptions o;
  o.arm = c.arm;
  if (!file.empty()) o.values = std::make_shared<Trajectory>(Trajectory::load(file, unit).value());
  if (!c.feed.empty()) {
    SensorFeedOptions f;
    f.listen = net::parse_endpoint(c.feed, 0).value();
    if (!c.feed_from.empty()) f.source = net::parse_endpoint(c.feed_from, 0).value();
    f.axes = c.feed_axes;
    f.degrees = c.units == "deg";
    o.feed = SensorFeed::open(f).value();
    o.feed_timeout_s = c.feed_timeout_ms * 1e-3;
    if (say)
      say(fmt::format("correct: feed listening on {}:{} ({} values per datagram, {})", f.listen.host, o.feed->port(), f.axes,
                      f.degrees ? "deg" : "rad"));
  }
  o.limits.max_abs_rad = deg_to_rad(c.max_correction_deg);
  o.limits.max_step_rad = deg_to_rad(c.max_correction_step_deg);
  o.amplitude_rad = deg_to_rad(c.amplitude);
  o.frequency_hz = c.frequency_hz;
  o.open_time_s = c.open_time_s;
  o.ramp_s = c.ramp_s;
  o.max_motor_speed = c.max_motor_speed;
  return o;
}

PidOptions pid_options(const AppConfig& c) {
  PidOptions p;
  p.arm = c.arm;
  p.amplitude_rad = deg_to_rad(c.amplitude);
  p.frequency_hz = c.frequency_hz;
  p.open_time_s = c.open_time_s;
  p.ramp_s = c.ramp_s;
  p.dynamic_model_feedforward = !c.no_dynamic_model;
  p.reduce_in_pc = c.reduce_in_pc;
  p.limits.max_abs_rad = deg_to_rad(c.max_correction_deg);
  p.limits.max_step_rad = deg_to_rad(c.max_correction_step_deg);
  const std::size_t n = std::max({c.kp.size(), c.kv.size(), c.ki.size()});
  auto pick = [](const std::vector<double>& v, std::size_t i, double def) { return v.empty() ? def : v[std::min(i, v.size() - 1)]; };
  for (std::size_t i = 0; i < n; ++i) {
    const PidGains d;
    p.gains.push_back({pick(c.kp, i, d.kp), pick(c.kv, i, d.kv), pick(c.ki, i, d.ki)});
  }
  return p;
}

std::unique_ptr<App> make_handover(const AppConfig& c, const std::function<void(const std::string&)>& say) {
  HandoverOptions h;
  h.arm = c.arm;
  h.hold_s = c.open_time_s > 0 ? c.open_time_s : 0.5;
  if (has_trajectory(c)) h.stream = stream_options(c, c.file);
  if (!c.correct_file.empty() || !c.feed.empty() || !c.amplitude.empty()) {
    h.correct = correct_options(c, c.correct_file, say);
    if (h.correct->open_time_s <= 0 && !h.correct->values) h.correct->open_time_s = h.hold_s;
  }
  return std::make_unique<HandoverApp>(std::move(h));
}

}  // namespace

std::unique_ptr<App> make_app(const AppConfig& c, const std::function<void(const std::string&)>& say) {
  unit_of(c);  // a bad unit is refused whatever the app
  if (c.app == "monitor") return std::make_unique<MonitorApp>();
  if (c.app == "echo") return std::make_unique<EchoApp>();
  if (c.app == "stream") {
    if (!has_trajectory(c))
      throw bad("--app stream needs --file TRAJECTORY.csv or --segment N=FILE.csv");
    if (c.mode != 4 && c.mode != 5) throw bad("--app stream: --mode must be 4 or 5");
    auto s = stream_options(c, c.file);
    s.rearm = c.rearm;
    return std::make_unique<StreamApp>(std::move(s));
  }
  if (c.app == "correct") {
    auto o = correct_options(c, c.file, say);
    o.rearm = c.rearm;
    return std::make_unique<CorrectApp>(std::move(o));
  }
  if (c.app == "handover") return make_handover(c, say);
  if (c.app == "pid") return std::make_unique<PidApp>(pid_options(c));
  if (c.app == "contribute") {
    if (c.mode != 8 && c.mode != 9) throw bad("--app contribute: --mode must be 8 (velocity) or 9 (current)");
    ContributeOptions o;
    o.arm = c.arm;
    o.mode = c.mode;
    o.amplitude = c.amplitude;  // motor side for this app: turns/s (8) or A (9)
    o.max_motor_speed = c.max_motor_speed;
    o.frequency_hz = c.frequency_hz;
    o.open_time_s = c.open_time_s;
    o.ramp_s = c.ramp_s;
    return std::make_unique<ContributeApp>(std::move(o));
  }
  throw bad(fmt::format("unknown --app '{}' (monitor, echo, stream, correct, pid, handover, contribute)", c.app));
}

}  // namespace axon::c4g::apps
