#include "axon/web/c4g_sim_view.hpp"

#include "axon/c4g/protocol/mode.hpp"
#include "axon/web/c4g_view.hpp"
#include "axon/web/json_text.hpp"
#include "axon/web/metrics_text.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <array>
#include <chrono>
#include <deque>
#include <iterator>
#include <span>

namespace axon::web {

// Named, not anonymous: the web library is a unity build.
namespace c4g_sim_page {

namespace sim = c4g::sim;
namespace protocol = c4g::protocol;

struct LoggedEvent {
  double time_s = 0;
  std::uint64_t cycle = 0;
  sim::EventLevel level = sim::EventLevel::info;
  std::string name, text;
};

// The manual's label of a mode code ("4", "1'", "501"), its code when the interface has none.
std::string label_of(std::int32_t code) {
  const auto* info = protocol::find_mode(code);
  return info ? std::string(info->label) : std::to_string(code);
}

std::string name_of(std::int32_t code) {
  const auto* info = protocol::find_mode(code);
  return info ? std::string(info->name) : "unknown";
}

std::string degrees_json(std::span<const double> v) { return fmt::format("[{:.4f}]", fmt::join(v, ",")); }

class Model {
 public:
  explicit Model(C4gSimViewOptions o) : options(std::move(o)) {}

  void add_event(const sim::LiveEvent& e);
  [[nodiscard]] std::string info_json() const;
  [[nodiscard]] std::string state_json() const;
  [[nodiscard]] std::string metrics() const;

  sim::LiveState live{};
  std::uint64_t dropped = 0;
  unsigned publishes = 0;

 private:
  [[nodiscard]] std::string scenario_json() const;
  [[nodiscard]] std::string arms_json() const;
  [[nodiscard]] std::string axes_json() const;
  [[nodiscard]] std::string counters_json() const;
  [[nodiscard]] std::string events_json() const;
  void write_counter_metrics(MetricsText& m) const;
  void write_state_metrics(MetricsText& m) const;
  void write_arm_metrics(MetricsText& m) const;

  C4gSimViewOptions options;
  std::chrono::steady_clock::time_point t0 = std::chrono::steady_clock::now();
  std::deque<LoggedEvent> log;
  std::uint64_t events = 0;
  std::array<std::uint64_t, 3> events_by_level{};  // info, warning, error
};

void Model::add_event(const sim::LiveEvent& e) {
  ++events;
  ++events_by_level.at(static_cast<std::size_t>(e.level));
  log.push_back({e.time_s, e.cycle, e.level, std::string(e.name_view()), std::string(e.text_view())});
  while (log.size() > options.event_log) log.pop_front();
}

std::string Model::info_json() const {
  return fmt::format("{{\"family\":\"c4g\",\"view\":\"simulator\",\"command\":{},\"robot\":{},\"program\":{},\"server\":{},"
                     "\"period_ms\":{},\"steps\":[{}],\"modes\":{}}}",
                     json_quote(options.command), json_quote(options.robot), json_quote(options.program),
                     json_quote(options.server), options.period_ms, [&] {
                       std::string s;
                       for (const auto& step : options.steps) s += (s.empty() ? "" : ",") + json_quote(step);
                       return s;
                     }(),
                     c4g_modes_json());
}

std::string Model::scenario_json() const {
  const bool under_way = live.step < live.steps && live.step < options.steps.size();
  return fmt::format("{{\"step\":{},\"steps\":{},\"kind\":{},\"text\":{},\"done\":{},\"failed\":{}}}", live.step + 1,
                     live.steps, under_way ? json_quote(sim::to_string(live.step_kind)) : "null",
                     under_way ? json_quote(options.steps[live.step]) : "null", live.scenario_done, live.scenario_failed);
}

std::string Model::arms_json() const {
  std::string out = "[";
  for (std::size_t arm = 1; arm < live.arms.size(); ++arm) {
    const auto& a = live.arms[arm];
    if (!a.present) continue;
    const auto joints = std::span<const double>(a.joint_deg).first(a.joints);
    const auto targets = std::span<const double>(a.target_deg).first(a.joints);
    fmt::format_to(std::back_inserter(out), "{}{{\"arm\":{},\"drives\":\"{}\",\"program_mode\":{},\"program_label\":{},"
                                            "\"joints_deg\":{},\"targets_deg\":{}}}",
                   out.size() > 1 ? "," : "", arm, a.drives_on ? "on" : "off", a.program_mode,
                   a.program_mode ? json_quote(label_of(a.program_mode)) : "null", degrees_json(joints), degrees_json(targets));
  }
  return out + "]";
}

std::string Model::axes_json() const {
  std::string out = "[";
  for (std::size_t i = 0; i < live.axis_count; ++i) {
    const auto& a = live.axes[i];
    fmt::format_to(std::back_inserter(out), "{}{{\"i\":{},\"arm\":{},\"axis\":{},\"mode\":{},\"label\":{},\"name\":{},"
                                            "\"pc_request\":{},\"pc_label\":{},\"position\":{:.6f},\"target\":{:.6f},"
                                            "\"error\":{:.6f},\"current\":{:.4f}}}",
                   i ? "," : "", i + 1, a.arm, a.axis, a.mode, json_quote(label_of(a.mode)), json_quote(name_of(a.mode)),
                   a.pc_request, json_quote(label_of(a.pc_request)), a.position, a.target, a.target - a.position, a.current);
  }
  return out + "]";
}

std::string Model::counters_json() const {
  const auto& s = live.stats;
  return fmt::format("{{\"ticks\":{},\"packets_sent\":{},\"sync_sent\":{},\"init_sent\":{},\"cyclic_sent\":{},\"replies_ok\":{},"
                     "\"misses\":{},\"consecutive_misses\":{},\"max_consecutive_misses\":{},\"late_replies\":{},"
                     "\"wrong_number\":{},\"wrong_size\":{},\"malformed\":{},\"duplicate_replies\":{},\"frozen_cycles\":{},"
                     "\"refused_requests\":{},\"saturated_cycles\":{},\"overruns\":{}}}",
                     s.ticks, s.packets_sent, s.sync_sent, s.init_sent, s.cyclic_sent, s.replies_ok, s.misses,
                     live.consecutive_misses, s.max_consecutive_misses, s.late_replies, s.wrong_number, s.wrong_size,
                     s.malformed, s.duplicate_replies, s.frozen_cycles, s.refused_requests, s.saturated_cycles, live.overruns);
}

std::string Model::events_json() const {
  std::string out = "[";
  for (const auto& e : log)
    fmt::format_to(std::back_inserter(out), "{}{{\"t\":{:.3f},\"cycle\":{},\"level\":\"{}\",\"name\":{},\"text\":{}}}",
                   out.size() > 1 ? "," : "", e.time_s, e.cycle, sim::to_string(e.level), json_quote(e.name),
                   json_quote(e.text));
  return out + "]";
}

std::string Model::state_json() const {
  const auto t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return fmt::format("{{\"t_s\":{:.3f},\"sequence\":{},\"time_s\":{:.3f},\"phase\":\"{}\",\"ended\":{},"
                     "\"communication_error\":{},\"scenario\":{},\"arms\":{},\"axes\":{},\"counters\":{},"
                     "\"rtt\":{{\"count\":{},\"mean_us\":{:.1f},\"max_us\":{:.1f}}},\"events_seen\":{},\"dropped\":{},"
                     "\"events\":{}}}",
                     t, live.sequence, live.time_s, sim::to_string(live.phase), live.ended, live.communication_error,
                     scenario_json(), arms_json(), axes_json(), counters_json(), live.rtt_count, live.rtt_mean_us,
                     live.rtt_max_us, events, dropped, events_json());
}

void Model::write_counter_metrics(MetricsText& m) const {
  const auto& s = live.stats;
  m.family("axon_c4g_sim_cycles_total", MetricType::counter, "Controller periods the simulator ticked").sample(s.ticks);
  m.family("axon_c4g_sim_packets_sent_total", MetricType::counter, "Datagrams the simulated controller sent, by kind");
  m.sample(s.sync_sent, {{"kind", "sync"}}).sample(s.init_sent, {{"kind", "init"}}).sample(s.cyclic_sent, {{"kind", "cyclic"}});
  m.family("axon_c4g_sim_replies_ok_total", MetricType::counter, "The PC's replies accepted: in time, with the right number")
      .sample(s.replies_ok);
  m.family("axon_c4g_sim_missed_replies_total", MetricType::counter,
           "Cyclic packets without a good reply from the PC in the reply window (ten in a row: communication error)")
      .sample(s.misses);
  m.family("axon_c4g_sim_late_replies_total", MetricType::counter, "Replies from the PC that came after their window")
      .sample(s.late_replies);
  m.family("axon_c4g_sim_bad_replies_total", MetricType::counter, "Replies from the PC refused, by reason");
  m.sample(s.wrong_number, {{"reason", "wrong_number"}})
      .sample(s.wrong_size, {{"reason", "wrong_size"}})
      .sample(s.malformed, {{"reason", "malformed"}})
      .sample(s.duplicate_replies, {{"reason", "duplicate"}});
  m.family("axon_c4g_sim_refused_requests_total", MetricType::counter, "Mode codes from the PC that the rules do not allow")
      .sample(s.refused_requests);
  m.family("axon_c4g_sim_frozen_cycles_total", MetricType::counter, "Cycles not checked while freezing").sample(s.frozen_cycles);
  m.family("axon_c4g_sim_saturated_cycles_total", MetricType::counter, "Axis-cycles whose reference current hit its limit")
      .sample(s.saturated_cycles);
  m.family("axon_c4g_sim_schedule_overruns_total", MetricType::counter, "Ticks the simulator started more than a period late")
      .sample(live.overruns);
  m.family("axon_c4g_sim_events_total", MetricType::counter, "The controller's events, by level");
  for (const auto level : {sim::EventLevel::info, sim::EventLevel::warning, sim::EventLevel::error})
    m.sample(events_by_level.at(static_cast<std::size_t>(level)), {{"level", sim::to_string(level)}});
  m.family("axon_c4g_sim_live_dropped_total", MetricType::counter,
           "Snapshots and events the controller's thread could not hand to the page (the page's thread too slow)")
      .sample(dropped);
}

void Model::write_state_metrics(MetricsText& m) const {
  m.family("axon_c4g_sim_communication_error", MetricType::gauge, "1 once the controller raised ERR_C4GOPEN_UDP, else 0")
      .sample(std::uint64_t{live.communication_error});
  m.family("axon_c4g_sim_consecutive_misses", MetricType::gauge, "Cyclic packets in a row without a good reply, now")
      .sample(static_cast<double>(live.consecutive_misses));
  m.family("axon_c4g_sim_program_step", MetricType::gauge, "The robot program's step under way, from 1 (steps + 1: ended)")
      .sample(static_cast<double>(live.step + 1));
  m.family("axon_c4g_sim_round_trip_max_seconds", MetricType::gauge, "The longest round trip of an accepted reply, in seconds")
      .sample(live.rtt_max_us * 1e-6);
  m.family("axon_c4g_sim_round_trip_mean_seconds", MetricType::gauge, "The mean round trip of the accepted replies, in seconds")
      .sample(live.rtt_mean_us * 1e-6);
  m.family("axon_c4g_sim_axis_mode", MetricType::gauge, "The mode code each open axis is in");
  for (std::size_t i = 0; i < live.axis_count; ++i)
    m.sample(static_cast<double>(live.axes[i].mode), {{"axis", std::to_string(i + 1)}, {"arm", std::to_string(live.axes[i].arm)}});
  m.family("axon_c4g_sim_axis_requested_mode", MetricType::gauge, "The mode code the PC's last good reply asked for, per open axis");
  for (std::size_t i = 0; i < live.axis_count; ++i)
    m.sample(static_cast<double>(live.axes[i].pc_request),
             {{"axis", std::to_string(i + 1)}, {"arm", std::to_string(live.axes[i].arm)}});
  m.family("axon_c4g_sim_axis_position_revolutions", MetricType::gauge, "Each open axis's motor position, in motor revolutions");
  for (std::size_t i = 0; i < live.axis_count; ++i) m.sample(live.axes[i].position, {{"axis", std::to_string(i + 1)}});
  m.family("axon_c4g_sim_axis_current_amperes", MetricType::gauge, "Each open axis's reference current, in amperes");
  for (std::size_t i = 0; i < live.axis_count; ++i) m.sample(live.axes[i].current, {{"axis", std::to_string(i + 1)}});
}

void Model::write_arm_metrics(MetricsText& m) const {
  const auto each_arm = [&](auto&& write) {
    for (std::size_t arm = 1; arm < live.arms.size(); ++arm)
      if (live.arms[arm].present) write(arm, live.arms[arm]);
  };
  m.family("axon_c4g_sim_drives_on", MetricType::gauge, "1 while the arm's drives are on, else 0");
  each_arm([&](std::size_t arm, const sim::LiveArm& a) { m.sample(std::uint64_t{a.drives_on}, {{"arm", std::to_string(arm)}}); });
  m.family("axon_c4g_sim_program_mode", MetricType::gauge, "The open mode the robot program's GO OPEN asked for (0: none)");
  each_arm([&](std::size_t arm, const sim::LiveArm& a) {
    m.sample(static_cast<double>(a.program_mode), {{"arm", std::to_string(arm)}});
  });
  const auto joints = [&](std::string_view name, std::string_view help, bool target) {
    m.family(name, MetricType::gauge, help);
    each_arm([&](std::size_t arm, const sim::LiveArm& a) {
      for (std::size_t k = 0; k < a.joints; ++k)
        m.sample(target ? a.target_deg[k] : a.joint_deg[k], {{"arm", std::to_string(arm)}, {"joint", std::to_string(k + 1)}});
    });
  };
  joints("axon_c4g_sim_joint_position_degrees", "Each joint's position at the link, in degrees", false);
  joints("axon_c4g_sim_joint_target_degrees", "Each joint's target at the link (the packets' D1), in degrees", true);
}

std::string Model::metrics() const {
  MetricsText m;
  write_counter_metrics(m);
  write_state_metrics(m);
  write_arm_metrics(m);
  return m.take();
}

}  // namespace c4g_sim_page

struct C4gSimView::Impl : c4g_sim_page::Model {
  using Model::Model;
};

C4gSimView::C4gSimView(C4gSimViewOptions options) : impl_(std::make_unique<Impl>(std::move(options))) {}
C4gSimView::~C4gSimView() = default;

void C4gSimView::update(const c4g::sim::LiveState& state, std::uint64_t dropped) {
  impl_->live = state;
  impl_->dropped = dropped;
}
void C4gSimView::add_event(const c4g::sim::LiveEvent& event) { impl_->add_event(event); }
std::string C4gSimView::info_json() const { return impl_->info_json(); }
std::string C4gSimView::state_json() const { return impl_->state_json(); }
std::string C4gSimView::metrics() const { return impl_->metrics(); }

void C4gSimView::publish(Source& source, unsigned metrics_every) {
  source.publish(state_json());
  if (metrics_every == 0 || impl_->publishes++ % metrics_every == 0) source.publish_metrics(metrics());
}

}  // namespace axon::web
