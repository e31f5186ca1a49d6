#include "axon/web/c4g_view.hpp"

#include "axon/c4g/apps/handover.hpp"
#include "axon/c4g/apps/open_mode.hpp"
#include "axon/c4g/protocol/axis_map.hpp"
#include "axon/c4g/protocol/mode.hpp"
#include "axon/web/json_text.hpp"
#include "axon/web/metrics_text.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <deque>
#include <iterator>
#include <optional>
#include <vector>

namespace axon::web {

// Named, not anonymous: the web library is a unity build, and the other views have helpers of
// their own in anonymous namespaces.
namespace c4g_page {

namespace apps = c4g::apps;
namespace host = c4g::host;
namespace protocol = c4g::protocol;

// The processing-time histogram's upper bounds in /metrics [us]: around the manual's 500-600 us
// answer window. The inter-packet period's [ms]: around both periods a controller may have (1 and
// 2 ms), so that one set of bounds serves either.
constexpr std::array<double, 15> kCycleBoundsUs{10, 20, 50, 100, 150, 200, 300, 400, 500, 600, 800, 1000, 2000, 5000, 10000};
constexpr std::array<double, 20> kPeriodBoundsMs{0.25, 0.5, 0.9, 0.95, 0.99, 1.01, 1.05, 1.1, 1.5, 1.9,
                                                 1.95, 1.99, 2.01, 2.05, 2.1, 2.5, 3, 5, 10, 20};
// The page's histograms: this many equal bins (plus one above), receive-to-send up to twice the
// deadline, the period up to twice the nominal one.
constexpr std::size_t kPageBins = 50;

constexpr std::array<host::ControllerError, 8> kControllerErrors{
    host::ControllerError::communication,   host::ControllerError::configuration_ax, host::ControllerError::forced_mode0,
    host::ControllerError::drive_off_server, host::ControllerError::follow_error,    host::ControllerError::controller_stop,
    host::ControllerError::position_jump,   host::ControllerError::override_scaled};

double wall_now_ns() {
  return static_cast<double>(
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count());
}

// Counts of a histogram's samples per interval of ascending upper bounds [ns]: counts[i] in
// (bounds[i-1], bounds[i]], the last element above every bound. Exact when the bounds are
// multiples of the histogram's bucket width (the edges here are whole microseconds).
std::vector<std::uint64_t> bin_counts(const core::LatencyHistogram& h, const std::vector<std::int64_t>& bounds) {
  std::vector<std::uint64_t> counts(bounds.size() + 1, 0);
  const auto width = h.bucket_width_ns();
  for (std::size_t i = 0; i < h.buckets(); ++i) {
    const auto n = h.bucket_count(i);
    if (n == 0) continue;
    const auto edge = static_cast<std::int64_t>(i) * width;  // the largest value bucket i holds
    const auto at = std::lower_bound(bounds.begin(), bounds.end(), edge);
    counts[static_cast<std::size_t>(at - bounds.begin())] += n;
  }
  counts.back() += h.overflow();
  return counts;
}

// kPageBins bins of `width` ns from 0, as bounds for bin_counts.
std::vector<std::int64_t> page_bounds(std::int64_t width) {
  std::vector<std::int64_t> b(kPageBins);
  for (std::size_t k = 0; k < kPageBins; ++k) b[k] = static_cast<std::int64_t>(k + 1) * width;
  return b;
}

// A width of whole microseconds (at least 1) that spreads `range` ns over kPageBins bins.
std::int64_t page_width(std::int64_t range) {
  const auto us = std::max<std::int64_t>(1, (range / static_cast<std::int64_t>(kPageBins) + 500) / 1000);
  return us * 1000;
}

std::string hist_json(const core::LatencyHistogram& h, std::int64_t width) {
  const auto counts = bin_counts(h, page_bounds(width));
  return fmt::format("{{\"width_us\":{},\"counts\":[{}],\"n\":{},\"max_us\":{:.1f}}}", static_cast<double>(width) / 1e3,
                     fmt::join(counts, ","), h.count(), static_cast<double>(h.max()) / 1e3);
}

// A float as JSON: null when it is not finite (a NaN in the controller's packet).
std::string json_number(float v) { return std::isfinite(v) ? fmt::format("{:.6g}", v) : "null"; }

struct AxisTrack {
  std::int32_t mode = 0;
  double since_wall_ns = 0;  // when the mode appeared (the packet's arrival), 0: unknown
};

struct ArmTrack {
  std::optional<bool> drives;  // unknown until an event tells
  bool exit_sent = false;      // the PC asked the arm to leave the open mode, and it has not yet
  std::uint64_t drives_off = 0;
  std::uint64_t exits = 0;
};

struct LoggedEvent {
  std::uint64_t cycle = 0;
  std::string text;
};

std::string_view kind_text(protocol::ModeKind k) {
  switch (k) {
    case protocol::ModeKind::standard: return "standard";
    case protocol::ModeKind::standby: return "standby";
    case protocol::ModeKind::sensor: return "sensor";
    case protocol::ModeKind::cartesian: return "cartesian";
    case protocol::ModeKind::special: return "special";
  }
  return "?";
}

// Where an axis's mode stands in START / CRUISE / END (header comment); "" without an open phase.
std::string_view open_phase(std::int32_t mode, double in_mode_s, bool exit_sent, const protocol::SwitchTimes& t) {
  if (protocol::base_of_standby(mode)) return "end";
  const auto* info = protocol::find_mode(mode);
  if (info == nullptr || mode == protocol::code(protocol::Mode::mode0) ||
      mode == protocol::code(protocol::Mode::mode0_prime) || info->kind == protocol::ModeKind::special)
    return "";
  if (exit_sent) return "end";
  if (protocol::phases(mode).has_cruise) return in_mode_s < t.total_s() ? "start" : "cruise";
  return "running";
}


// What the view keeps between events, and builds the state from.
class Model {
 public:
  Model(const apps::App& a, const host::Server& s, C4gViewOptions o) : app(a), server(s), options(std::move(o)) {}

  void add_event(const apps::Event& e, const std::string& text);
  void on_init();
  [[nodiscard]] std::string info_json() const;
  [[nodiscard]] std::string state_json() const;
  [[nodiscard]] std::string metrics() const;

  unsigned publishes = 0;

 private:
  void on_mode_change(const apps::Event& e);
  void on_arm_event(const apps::Event& e);
  [[nodiscard]] std::size_t arm_of(std::size_t open_index) const;
  [[nodiscard]] std::string app_json() const;
  [[nodiscard]] std::string server_json() const;
  [[nodiscard]] std::string axes_json() const;
  [[nodiscard]] std::string arms_json() const;
  [[nodiscard]] std::string counters_json() const;
  [[nodiscard]] std::string safety_json() const;
  [[nodiscard]] std::string timing_json() const;
  [[nodiscard]] std::string controller_errors_json() const;
  [[nodiscard]] std::string events_json() const;
  void write_counter_metrics(MetricsText& m) const;
  void write_timing_metrics(MetricsText& m) const;
  void write_state_metrics(MetricsText& m) const;
  void write_following_error_metrics(MetricsText& m) const;
  [[nodiscard]] std::int64_t nominal_ns() const;
  [[nodiscard]] std::vector<std::size_t> arms_present() const;

  const apps::App& app;
  const host::Server& server;
  C4gViewOptions options;
  std::chrono::steady_clock::time_point t0 = std::chrono::steady_clock::now();
  std::size_t axis_count = 0;  // open axes: the initialization packet's, else the highest seen
  std::optional<protocol::AxisMap> map;
  std::array<float, protocol::kMaxAxes> fe_threshold{}, current_limit{};
  std::array<AxisTrack, protocol::kMaxAxes> axes{};
  std::array<ArmTrack, protocol::kMaxArms> arms{};
  std::deque<LoggedEvent> log;
  std::uint64_t events = 0, mode_changes = 0, silences = 0, inits = 0;
};

// A new initialization packet: the axis map, the thresholds and the start-up modes.
void Model::on_init() {
  const auto init = server.init();
  if (!init) return;
  axis_count = static_cast<std::size_t>(std::clamp<std::int32_t>(init->open_axes, 0, protocol::kMaxAxes));
  auto m = protocol::AxisMap::from_init(*init);
  if (!m) {
    map.reset();
    return;
  }
  map = m.value();
  fe_threshold = map->per_open_axis(init->following_error);
  current_limit = map->per_open_axis(init->current_limit);
  for (std::size_t i = 0; i < map->count(); ++i) {
    const auto startup = map->startup_mode(i);
    axes[i] = {protocol::is_known_mode(startup) ? startup : 0, wall_now_ns()};
  }
  for (auto& a : arms) a.exit_sent = false;
}

std::size_t Model::arm_of(std::size_t open_index) const {
  if (!map || open_index >= map->count()) return 0;
  return map->logical(open_index).arm;
}

void Model::on_mode_change(const apps::Event& e) {
  if (e.axis < 0 || static_cast<std::size_t>(e.axis) >= protocol::kMaxAxes) return;
  const auto i = static_cast<std::size_t>(e.axis);
  axes[i] = {e.aux, static_cast<double>(e.wall_ns)};
  axis_count = std::max(axis_count, i + 1);
  ++mode_changes;
  // The arm's exit request is over once every one of its axes is back in mode 0.
  const auto arm = arm_of(i);
  if (arm == 0) return;
  const auto first = map->arm_first(arm);
  bool all0 = true;
  for (std::size_t k = first; k < first + map->arm_count(arm); ++k) all0 = all0 && axes[k].mode == 0;
  if (all0) arms[arm - 1].exit_sent = false;
}

void Model::on_arm_event(const apps::Event& e) {
  if (e.axis < 1 || e.axis > static_cast<int>(protocol::kMaxArms)) return;
  auto& a = arms[static_cast<std::size_t>(e.axis - 1)];
  if (e.kind == apps::EventKind::exit_sent) {
    a.exit_sent = true;
    ++a.exits;
    return;
  }
  if (e.value == 0 && a.drives.value_or(false)) ++a.drives_off;
  a.drives = e.value != 0;
}

void Model::add_event(const apps::Event& e, const std::string& text) {
  ++events;
  switch (e.kind) {
    case apps::EventKind::init:
      ++inits;
      on_init();
      break;
    case apps::EventKind::mode_change: on_mode_change(e); break;
    case apps::EventKind::drives:
    case apps::EventKind::exit_sent: on_arm_event(e); break;
    case apps::EventKind::silence:
      // The next packets' modes are not evented until they change: start over from mode 0.
      ++silences;
      for (auto& a : axes) a = {};
      break;
    case apps::EventKind::note: break;
  }
  log.push_back({e.cycle, text});
  while (log.size() > options.event_log) log.pop_front();
}

std::int64_t Model::nominal_ns() const {
  const auto n = server.cycle().timing().nominal_period_ns();
  return n > 0 ? n : 2'000'000;  // unknown yet: the six-axis robot's 2 ms
}

// The arms with open axes (the axis map), else those the drives events named.
std::vector<std::size_t> Model::arms_present() const {
  std::vector<std::size_t> out;
  for (std::size_t arm = 1; arm <= protocol::kMaxArms; ++arm)
    if (map ? map->arm_count(arm) > 0 : arms[arm - 1].drives.has_value()) out.push_back(arm);
  return out;
}

std::string Model::info_json() const {
  std::string out;
  auto it = std::back_inserter(out);
  const auto& t = options.soft_switch;
  fmt::format_to(it, "{{\"family\":\"c4g\",\"command\":{},\"app\":{},\"soft_switch_ms\":[{},{},{}],\"modes\":",
                 json_quote(options.command), json_quote(app.name()), t.t1_s * 1e3, t.t2_s * 1e3, t.t3_s * 1e3);
  out += c4g_modes_json();
  out += ",\"controller_errors\":[";
  bool first = true;
  for (const auto e : kControllerErrors) {
    fmt::format_to(it, "{}{{\"name\":{},\"meaning\":{}}}", first ? "" : ",", json_quote(host::manual_name(e)),
                   json_quote(host::meaning(e)));
    first = false;
  }
  fmt::format_to(it, "],\"cycle_time_bounds_us\":[{}],\"period_bounds_ms\":[{}]}}", fmt::join(kCycleBoundsUs, ","),
                 fmt::join(kPeriodBoundsMs, ","));
  return out;
}

std::string Model::app_json() const {
  const auto phase = c4g_app_phase(app);
  return fmt::format("{{\"name\":{},\"status\":{},\"phase\":{},\"finished\":{},\"error\":{},\"cycles\":{},\"quiescent\":{},"
                     "\"events_dropped\":{}}}",
                     json_quote(app.name()), json_quote(app.status()), phase.empty() ? "null" : json_quote(phase),
                     app.finished(), json_quote(app.error_text()), app.cycles(), app.quiescent(), app.events_dropped());
}

std::string Model::server_json() const {
  const auto peer = server.peer();
  const auto& t = server.cycle().timing();
  return fmt::format("{{\"state\":\"{}\",\"controller\":{},\"local\":{},\"period_ms\":{},\"freeze\":\"{}\",\"sessions\":{}}}",
                     host::to_string(server.state()), peer ? json_quote(peer->to_string()) : "null",
                     json_quote(server.local_address().to_string()),
                     t.nominal_known() ? fmt::format("{}", static_cast<double>(t.nominal_period_ns()) / 1e6) : "null",
                     host::to_string(server.freeze_state()), server.counters().sessions.load());
}

std::string Model::axes_json() const {
  std::string out = "[";
  auto it = std::back_inserter(out);
  const double now = wall_now_ns();
  for (std::size_t i = 0; i < axis_count; ++i) {
    const auto& a = axes[i];
    const auto* info = protocol::find_mode(a.mode);
    const auto arm = arm_of(i);
    const auto axis = map && i < map->count() ? map->logical(i).axis : 0;
    const double in_mode = a.since_wall_ns > 0 ? std::max(0.0, (now - a.since_wall_ns) * 1e-9) : 0.0;
    const bool exit_sent = arm > 0 && arms[arm - 1].exit_sent;
    const auto& safety = server.safety();
    fmt::format_to(it, "{}{{\"i\":{},\"arm\":{},\"axis\":{},\"mode\":{},\"name\":{},\"label\":{},\"phase\":\"{}\","
                       "\"in_mode_s\":{:.3f},\"fe_threshold\":{},\"current_limit\":{},\"following_error\":{},"
                       "\"following_error_peak\":{},\"fe_checked\":{}}}",
                   i ? "," : "", i + 1, arm, static_cast<unsigned>(axis), a.mode,
                   json_quote(info ? info->name : "unknown"), json_quote(info ? info->label : std::to_string(a.mode)),
                   open_phase(a.mode, in_mode, exit_sent, options.soft_switch), in_mode, fe_threshold[i], current_limit[i],
                   json_number(safety.following_error(i)), json_number(safety.following_error_peak(i)),
                   host::Safety::checks_following_error(a.mode));
  }
  return out + "]";
}

std::string Model::arms_json() const {
  std::string out = "[";
  bool first = true;
  for (const auto arm : arms_present()) {
    const auto& a = arms[arm - 1];
    fmt::format_to(std::back_inserter(out), "{}{{\"arm\":{},\"axes\":{},\"drives\":{},\"exit_sent\":{},\"drives_off\":{},"
                                            "\"exits\":{}}}",
                   first ? "" : ",", arm, map ? map->arm_count(arm) : 0,
                   a.drives ? (*a.drives ? "\"on\"" : "\"off\"") : "null", a.exit_sent, a.drives_off, a.exits);
    first = false;
  }
  return out + "]";
}

std::string Model::counters_json() const {
  const auto& c = server.counters();
  const auto& cc = server.cycle().counters();
  return fmt::format("{{\"packets\":{},\"cyclic\":{},\"init\":{},\"replies\":{},\"late_replies\":{},\"unanswered\":{},"
                     "\"send_errors\":{},\"protocol_errors\":{},\"safe_replies\":{},\"app_late\":{},\"app_exceptions\":{},"
                     "\"refused_mode_changes\":{},\"foreign\":{},\"freezes\":{},\"init_requests\":{},\"controller_restarts\":{}}}",
                     c.packets.load(), c.cyclic_packets.load(), c.init_packets.load(), cc.replies.load(),
                     server.cycle().timing().missed_deadlines(), c.unanswered.load(), cc.send_errors.load(),
                     c.protocol_errors.load(), c.safe_replies.load(), c.controller_late.load(),
                     c.controller_exceptions.load(), c.refused_mode_changes.load(), c.foreign.load(), c.freezes.load(),
                     c.init_requests.load(), c.controller_restarts.load());
}

std::string Model::safety_json() const {
  const auto& s = server.safety();
  const auto& c = s.counters();
  const auto reason = s.reason();
  return fmt::format("{{\"fault\":\"{}\",\"fault_axis\":{},\"obeyed\":{},\"faults\":{},\"drive_off_replies\":{},"
                     "\"following_error_replies\":{},\"currents_clamped\":{}}}",
                     host::to_string(reason), reason == host::FaultReason::none ? -1 : s.fault_axis(), s.obeyed(),
                     c.faults.load(), c.drive_off_replies.load(), c.following_error_replies.load(), c.currents_clamped.load());
}

std::string Model::timing_json() const {
  const auto& t = server.cycle().timing();
  const auto& ct = t.cycle_times();
  const auto& it = t.inter_step_times();
  const auto deadline = t.config().deadline_ns;
  const auto us = [](std::int64_t ns) { return static_cast<double>(ns) / 1e3; };
  return fmt::format("{{\"cycles\":{},\"nominal_known\":{},\"nominal_period_us\":{},\"deadline_us\":{},\"last_cycle_us\":{:.1f},"
                     "\"worst_cycle_us\":{:.1f},\"p50_us\":{:.1f},\"p99_us\":{:.1f},\"p999_us\":{:.1f},\"period_min_us\":{:.1f},"
                     "\"period_max_us\":{:.1f},\"period_p50_us\":{:.1f},\"jitter_min_us\":{:.1f},\"jitter_max_us\":{:.1f},"
                     "\"late\":{},\"cycle_hist\":{},\"period_hist\":{}}}",
                     t.cycles(), t.nominal_known(), us(nominal_ns()), us(deadline), us(t.last_cycle_time_ns()),
                     us(t.worst_cycle_time_ns()), us(ct.percentile(50)), us(ct.percentile(99)), us(ct.percentile(99.9)),
                     us(t.min_inter_step_ns()), us(t.max_inter_step_ns()), us(it.percentile(50)), us(t.min_jitter_ns()),
                     us(t.max_jitter_ns()), t.missed_deadlines(), hist_json(ct, page_width(2 * deadline)),
                     hist_json(it, page_width(2 * nominal_ns())));
}

std::string Model::controller_errors_json() const {
  const auto& w = server.controller_errors();
  std::string out = "{\"counts\":{";
  bool first = true;
  for (const auto e : kControllerErrors) {
    if (w.count(e) == 0) continue;
    fmt::format_to(std::back_inserter(out), "{}{}:{}", first ? "" : ",", json_quote(host::manual_name(e)), w.count(e));
    first = false;
  }
  const auto last = w.last();
  fmt::format_to(std::back_inserter(out), "}},\"last\":{},\"last_arm\":{},\"last_axis\":{}}}",
                 last == host::ControllerError::none ? "null" : json_quote(host::manual_name(last)), w.last_arm(), w.last_axis());
  return out;
}

std::string Model::events_json() const {
  std::string out = "[";
  bool first = true;
  for (const auto& e : log) {
    fmt::format_to(std::back_inserter(out), "{}{{\"cycle\":{},\"text\":{}}}", first ? "" : ",", e.cycle, json_quote(e.text));
    first = false;
  }
  return out + "]";
}

std::string Model::state_json() const {
  const auto t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return fmt::format("{{\"t_s\":{:.3f},\"wall_s\":{:.3f},\"command\":{},\"app\":{},\"server\":{},\"axes\":{},\"arms\":{},"
                     "\"counters\":{},\"safety\":{},\"timing\":{},\"controller_errors\":{},\"events_seen\":{},\"events\":{}}}",
                     t, wall_now_ns() * 1e-9, json_quote(options.command), app_json(), server_json(), axes_json(), arms_json(),
                     counters_json(), safety_json(), timing_json(), controller_errors_json(), events, events_json());
}

void Model::write_counter_metrics(MetricsText& m) const {
  struct Counter {
    std::string_view name, help;
    std::uint64_t value;
  };
  const auto& c = server.counters();
  const auto& s = server.safety().counters();
  const std::array<Counter, 14> counters{{
      {"axon_c4g_packets_total", "Datagrams received from the session's controller", c.packets.load()},
      {"axon_c4g_cycles_total", "Cyclic packets the server handled (one per controller cycle)", c.cyclic_packets.load()},
      {"axon_c4g_init_packets_total", "Initialization packets received", c.init_packets.load()},
      {"axon_c4g_late_replies_total", "Replies sent later than the answer deadline after their packet arrived",
       server.cycle().timing().missed_deadlines()},
      {"axon_c4g_unanswered_packets_total", "Datagrams the server could not answer (of no known size)", c.unanswered.load()},
      {"axon_c4g_send_errors_total", "Replies the socket failed to send", server.cycle().counters().send_errors.load()},
      {"axon_c4g_protocol_errors_total", "Datagrams that did not decode", c.protocol_errors.load()},
      {"axon_c4g_safe_replies_total", "Cycles answered with the server's safe reply instead of the application's",
       c.safe_replies.load()},
      {"axon_c4g_app_late_total", "Application calls that took longer than their budget", c.controller_late.load()},
      {"axon_c4g_refused_mode_changes_total", "Mode changes the application asked for that the rules forbid",
       c.refused_mode_changes.load()},
      {"axon_c4g_foreign_datagrams_total", "Datagrams from a source other than the session's controller (ignored)",
       c.foreign.load()},
      {"axon_c4g_safety_faults_total", "Faults the PC-side safety layer latched", s.faults.load()},
      {"axon_c4g_drive_off_replies_total", "Replies that asked the controller for drive off (505)", s.drive_off_replies.load()},
      {"axon_c4g_following_error_replies_total", "Replies that asked for a following-error stop (508)",
       s.following_error_replies.load()},
  }};
  for (const auto& k : counters) m.family(k.name, MetricType::counter, k.help).sample(k.value);
  m.family("axon_c4g_currents_clamped_total", MetricType::counter, "Reply currents the safety layer clamped to the limit")
      .sample(s.currents_clamped.load());
  m.family("axon_c4g_controller_errors_total", MetricType::counter,
           "The controller's errors as its packets showed them, by the manual's name");
  const auto& w = server.controller_errors();
  for (const auto e : kControllerErrors) m.sample(std::uint64_t{w.count(e)}, {{"error", host::manual_name(e)}});
  m.family("axon_c4g_app_events_dropped_total", MetricType::counter, "Application events lost to a full queue")
      .sample(app.events_dropped());
}

void Model::write_timing_metrics(MetricsText& m) const {
  const auto& t = server.cycle().timing();
  const auto seconds_of = [](std::int64_t ns) { return static_cast<double>(ns) * 1e-9; };
  m.family("axon_c4g_reply_deadline_seconds", MetricType::gauge, "The answer deadline a reply counts late after, in seconds")
      .sample(seconds_of(t.config().deadline_ns));
  m.family("axon_c4g_nominal_period_seconds", MetricType::gauge,
           "The controller's period from its initialization packet, in seconds (0 while unknown)")
      .sample(seconds_of(t.nominal_period_ns()));
  m.family("axon_c4g_worst_cycle_time_seconds", MetricType::gauge, "The longest receive-to-send time so far, in seconds")
      .sample(seconds_of(t.worst_cycle_time_ns()));
  const auto histogram = [&](std::string_view name, std::string_view help, const core::LatencyHistogram& h,
                             std::span<const double> bounds_s) {
    std::vector<std::int64_t> bounds_ns;
    for (const double b : bounds_s) bounds_ns.push_back(static_cast<std::int64_t>(b * 1e9 + 0.5));
    const auto counts = bin_counts(h, bounds_ns);
    m.family(name, MetricType::histogram, help).histogram(bounds_s, counts, h.mean() * 1e-9 * static_cast<double>(h.count()));
  };
  std::array<double, kCycleBoundsUs.size()> cycle_s{};
  std::transform(kCycleBoundsUs.begin(), kCycleBoundsUs.end(), cycle_s.begin(), [](double us) { return us * 1e-6; });
  std::array<double, kPeriodBoundsMs.size()> period_s{};
  std::transform(kPeriodBoundsMs.begin(), kPeriodBoundsMs.end(), period_s.begin(), [](double ms) { return ms * 1e-3; });
  histogram("axon_c4g_cycle_time_seconds",
            "Processing time of each cycle: from the controller's packet received to the reply sent, in seconds",
            t.cycle_times(), cycle_s);
  histogram("axon_c4g_inter_packet_period_seconds",
            "Time between two consecutive packets of the controller (its period as the PC sees it), in seconds",
            t.inter_step_times(), period_s);
}

void Model::write_state_metrics(MetricsText& m) const {
  m.family("axon_c4g_axis_mode", MetricType::gauge, "The mode code (SM) of each open axis in the controller's latest packets");
  for (std::size_t i = 0; i < axis_count; ++i) {
    const auto axis = std::to_string(i + 1);
    const auto arm = std::to_string(arm_of(i));
    m.sample(static_cast<double>(axes[i].mode), {{"axis", axis}, {"arm", arm}});
  }
  m.family("axon_c4g_drives_on", MetricType::gauge, "1 while the arm's drives are on, else 0");
  for (const auto arm : arms_present()) m.sample(std::uint64_t{arms[arm - 1].drives.value_or(false)}, {{"arm", std::to_string(arm)}});
  m.family("axon_c4g_drives_off_total", MetricType::counter, "Times the arm's drives went off");
  for (const auto arm : arms_present()) m.sample(arms[arm - 1].drives_off, {{"arm", std::to_string(arm)}});
  m.family("axon_c4g_safety_faulted", MetricType::gauge, "1 while the PC-side safety layer has a fault latched, else 0")
      .sample(std::uint64_t{server.safety().faulted()});
  write_following_error_metrics(m);
  m.family("axon_c4g_following_error_threshold_revolutions", MetricType::gauge,
           "The initialization packet's following-error threshold of each open axis, in motor revolutions");
  if (map)
    for (std::size_t i = 0; i < map->count(); ++i)
      m.sample(static_cast<double>(fe_threshold[i]), {{"axis", std::to_string(i + 1)}});
  const auto phase = c4g_app_phase(app);
  if (phase.empty()) return;
  m.family("axon_c4g_app_phase", MetricType::gauge, "1 for the application's phase now, 0 for the others");
  for (const auto p : {apps::Phase::waiting, apps::Phase::running, apps::Phase::fading, apps::Phase::holding, apps::Phase::idle,
                       apps::Phase::exiting, apps::Phase::done, apps::Phase::refused})
    m.sample(std::uint64_t{apps::to_string(p) == phase}, {{"phase", apps::to_string(p)}});
}

// The cycle's latest |D1 - D3| per open axis and its peak in the mode (Safety's atomics). A NaN
// (a packet that carried one) is left out: Prometheus would take it, but a graph would not.
void Model::write_following_error_metrics(MetricsText& m) const {
  const auto& safety = server.safety();
  const auto each = [&](auto value) {
    for (std::size_t i = 0; i < axis_count; ++i)
      if (const float v = value(i); std::isfinite(v)) m.sample(static_cast<double>(v), {{"axis", std::to_string(i + 1)}});
  };
  m.family("axon_c4g_following_error_revolutions", MetricType::gauge,
           "Each open axis's following error |target - actual| (D1 - D3) in the latest packet, in motor revolutions");
  each([&](std::size_t i) { return safety.following_error(i); });
  m.family("axon_c4g_following_error_peak_revolutions", MetricType::gauge,
           "Each open axis's largest following error since it entered its present mode, in motor revolutions");
  each([&](std::size_t i) { return safety.following_error_peak(i); });
}

std::string Model::metrics() const {
  MetricsText m;
  write_counter_metrics(m);
  write_timing_metrics(m);
  write_state_metrics(m);
  return m.take();
}

}  // namespace c4g_page

struct C4gView::Impl : c4g_page::Model {
  using Model::Model;
};

C4gView::C4gView(const c4g::apps::App& app, const c4g::host::Server& server, C4gViewOptions options)
    : impl_(std::make_unique<Impl>(app, server, std::move(options))) {
  impl_->on_init();  // a session already past its initialization packet
}
C4gView::~C4gView() = default;

void C4gView::add_event(const c4g::apps::Event& event, const std::string& text) { impl_->add_event(event, text); }
std::string C4gView::info_json() const { return impl_->info_json(); }
std::string C4gView::state_json() const { return impl_->state_json(); }
std::string C4gView::metrics() const { return impl_->metrics(); }

void C4gView::publish(Source& source, unsigned metrics_every) {
  source.publish(state_json());
  if (metrics_every == 0 || impl_->publishes++ % metrics_every == 0) source.publish_metrics(metrics());
}

std::string c4g_modes_json() {
  namespace protocol = c4g::protocol;
  std::string out = "[";
  for (const auto& m : protocol::all_modes())
    fmt::format_to(std::back_inserter(out), "{}{{\"code\":{},\"name\":{},\"label\":{},\"kind\":\"{}\",\"description\":{}}}",
                   out.size() > 1 ? "," : "", protocol::code(m.mode), json_quote(m.name), json_quote(m.label),
                   c4g_page::kind_text(m.kind), json_quote(m.description));
  return out + "]";
}

std::string c4g_app_phase(const c4g::apps::App& app) {
  namespace apps = c4g::apps;
  if (const auto* o = dynamic_cast<const apps::OpenModeApp*>(&app)) return std::string(apps::to_string(o->phase()));
  const auto* h = dynamic_cast<const apps::HandoverApp*>(&app);
  if (h == nullptr) return {};
  // The part serving an open mode now: the one whose phase is neither waiting nor done.
  const std::array<const apps::OpenModeApp*, 3> parts{h->stream(4), h->stream(5), &h->correct()};
  for (const auto* p : parts) {
    if (p == nullptr) continue;
    const auto ph = p->phase();
    if (ph != apps::Phase::waiting && ph != apps::Phase::done) return std::string(apps::to_string(ph));
  }
  return "waiting";
}

}  // namespace axon::web
