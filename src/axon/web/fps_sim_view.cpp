#include "axon/web/fps_sim_view.hpp"

#include "axon/fps/layout/focal_plane.hpp"
#include "axon/fps/protocol/status.hpp"
#include "axon/fps/sim/focal_plane_sim.hpp"
#include "axon/web/json_text.hpp"
#include "axon/web/metrics_text.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <iterator>

namespace axon::web {
namespace {

namespace sim = fps::sim;

constexpr std::array<std::string_view, 6> kStates{"ready", "moving", "not-initialised", "collided", "offline", "bootloader"};

std::string_view robot_state(const sim::PositionerModel& m) {
  if (m.run_state() == sim::RunState::bootloader) return "bootloader";
  if (m.run_state() != sim::RunState::application) return "offline";
  const auto st = m.status();
  if (st.collided()) return "collided";
  if (m.moving()) return "moving";
  if (!st.initialized() || !st.motors_calibrated()) return "not-initialised";
  return "ready";
}

// One robot as read by the last update().
struct Row {
  std::uint16_t id = 0;
  std::string bus;
  double alpha = 0;
  double beta = 0;
  std::string_view state;
  std::uint64_t status = 0;  // the application's status word (0 outside the application)
  std::string firmware;
  sim::ModelCounters counters;
  std::uint64_t overflows = 0;  // frames lost to its full receive buffer
};

}  // namespace

struct FpsSimView::Impl {
  Impl(const fps::FocalPlane& p, sim::FocalPlaneSimulator& s) : plane(p), simulator(s) {}

  void read_robots();
  void update_lock();
  void write_plane_metrics(MetricsText& m) const;
  void write_robot_metrics(MetricsText& m) const;
  void write_bus_metrics(MetricsText& m) const;

  const fps::FocalPlane& plane;
  sim::FocalPlaneSimulator& simulator;
  std::vector<Row> rows;
  FpsLock lock;
  std::map<std::string, std::uint64_t> locks_by_bus;
  double time_s = 0;
  unsigned publishes = 0;
};

FpsSimView::FpsSimView(const fps::FocalPlane& plane, sim::FocalPlaneSimulator& sim)
    : impl_(std::make_unique<Impl>(plane, sim)) {}
FpsSimView::~FpsSimView() = default;

const FpsLock& FpsSimView::lock() const noexcept { return impl_->lock; }

void FpsSimView::Impl::read_robots() {
  auto& s = simulator.simulator();
  time_s = sim::to_seconds(s.now());
  const auto models = s.robots();
  rows.resize(models.size());
  for (std::size_t i = 0; i < models.size(); ++i) {
    const auto& m = *models[i];
    Row& r = rows[i];
    if (r.id != m.id()) {
      r.id = m.id();
      const auto* site = plane.find(r.id);
      r.bus = site ? site->bus.to_string() : std::string{};
    }
    r.alpha = m.physical_deg(sim::Arm::alpha);
    r.beta = m.physical_deg(sim::Arm::beta);
    r.state = robot_state(m);
    r.status = m.run_state() == sim::RunState::application ? m.status().raw() : 0;
    r.firmware = m.running_version().to_string();
    r.counters = m.counters();
    const auto* endpoint = s.endpoint(r.id);
    r.overflows = endpoint ? endpoint->stats().rx_dropped : 0;
  }
}

void FpsSimView::Impl::update_lock() {
  std::vector<std::uint16_t> now;  // in id order
  for (const auto& r : rows)
    if (fps::protocol::PositionerStatus(r.status).collided()) now.push_back(r.id);
  std::sort(now.begin(), now.end());
  std::vector<std::uint16_t> next;  // those still collided in the order first seen, then the new ones
  for (auto id : lock.collided)
    if (std::binary_search(now.begin(), now.end(), id)) next.push_back(id);
  for (auto id : now)
    if (std::find(lock.collided.begin(), lock.collided.end(), id) == lock.collided.end()) next.push_back(id);
  const bool was_locked = lock.locked;
  lock.collided = std::move(next);
  lock.locked = !lock.collided.empty();
  if (!lock.locked) {
    lock.robot = 0;
    lock.bus.clear();
    lock.arm.clear();
    return;
  }
  lock.robot = lock.collided.front();
  const auto it = std::find_if(rows.begin(), rows.end(), [&](const Row& r) { return r.id == lock.robot; });
  lock.bus = it->bus;
  lock.arm = fps::protocol::PositionerStatus(it->status).has(fps::protocol::StatusBit::collision_alpha) ? "alpha" : "beta";
  if (!was_locked) {
    ++lock.count;
    ++locks_by_bus[lock.bus];
  }
}

void FpsSimView::update() {
  impl_->read_robots();
  impl_->update_lock();
}

std::string FpsSimView::info_json() const {
  std::string out;
  auto o = std::back_inserter(out);
  fmt::format_to(o, "{{\"family\":\"fps\",\"view\":\"simulator\",\"layout\":{},\"pitch_mm\":{},\"robots\":[", json_quote(impl_->plane.name()),
                 impl_->plane.pitch_mm());
  bool first = true;
  for (auto* m : impl_->simulator.simulator().robots()) {
    const auto& c = m->config();
    const auto* site = impl_->plane.find(c.id);
    fmt::format_to(o, "{}{{\"id\":{},\"x\":{},\"y\":{},\"orientation\":{},\"alpha_mm\":{},\"beta_mm\":{},\"bus\":{},\"sextant\":{}}}",
                   first ? "" : ",", c.id, c.x_mm, c.y_mm, c.orientation_deg, c.arms.alpha_length_mm, c.arms.beta_collision_mm,
                   json_quote(site ? site->bus.to_string() : ""), site ? site->sextant : 0);
    first = false;
  }
  out += "],\"fiducials\":[";
  first = true;
  for (const auto& f : impl_->plane.fiducials()) {
    fmt::format_to(o, "{}{{\"id\":{},\"x\":{},\"y\":{}}}", first ? "" : ",", f.id, f.x_mm, f.y_mm);
    first = false;
  }
  out += "],\"status_bits\":[";
  first = true;
  for (const auto& b : fps::protocol::kStatusBits) {
    fmt::format_to(o, "{}{{\"bit\":{},\"name\":{},\"meaning\":{}}}", first ? "" : ",", static_cast<unsigned>(b.bit),
                   json_quote(b.name), json_quote(b.meaning));
    first = false;
  }
  out += "],\"states\":[";
  for (std::size_t i = 0; i < kStates.size(); ++i) fmt::format_to(o, "{}\"{}\"", i ? "," : "", kStates[i]);
  out += "]}";
  return out;
}

std::string FpsSimView::state_json() const {
  const auto& im = *impl_;
  std::array<std::size_t, kStates.size()> counts{};
  for (const auto& r : im.rows)
    counts[static_cast<std::size_t>(std::find(kStates.begin(), kStates.end(), r.state) - kStates.begin())]++;
  std::string out;
  out.reserve(im.rows.size() * 130 + 512);
  auto o = std::back_inserter(out);
  const auto wall = std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  fmt::format_to(o, "{{\"time_s\":{:.3f},\"wall_s\":{:.3f},\"sync_line\":{},\"moving\":{},\"states\":{{", im.time_s, wall,
                 im.simulator.sync_line(), counts[1]);
  for (std::size_t i = 0; i < kStates.size(); ++i) fmt::format_to(o, "{}\"{}\":{}", i ? "," : "", kStates[i], counts[i]);
  const auto& l = im.lock;
  fmt::format_to(o, "}},\"lock\":{{\"locked\":{},\"robot\":{},\"bus\":{},\"arm\":{},\"count\":{},\"collided\":[{}]}},\"robots\":[",
                 l.locked, l.robot, json_quote(l.bus), json_quote(l.arm), l.count, fmt::join(l.collided, ","));
  bool first = true;
  for (const auto& r : im.rows) {
    fmt::format_to(o, "{}{{\"id\":{},\"a\":{:.3f},\"b\":{:.3f},\"s\":\"{}\",\"st\":\"{:016x}\",\"fw\":\"{}\",\"req\":{},"
                   "\"rej\":{},\"col\":{},\"ovf\":{}}}",
                   first ? "" : ",", r.id, r.alpha, r.beta, r.state, r.status, r.firmware, r.counters.requests,
                   r.counters.rejected, r.counters.collisions, r.overflows);
    first = false;
  }
  out += "]}";
  return out;
}

void FpsSimView::Impl::write_plane_metrics(MetricsText& m) const {
  const auto& st = simulator.simulator().stats();
  std::array<std::uint64_t, kStates.size()> counts{};
  for (const auto& r : rows) counts[static_cast<std::size_t>(std::find(kStates.begin(), kStates.end(), r.state) - kStates.begin())]++;
  m.family("axon_fps_sim_robots", MetricType::gauge, "Simulated robots by state");
  for (std::size_t i = 0; i < kStates.size(); ++i) m.sample(counts[i], {{"state", kStates[i]}});
  m.family("axon_fps_sim_locked", MetricType::gauge, "1 while a robot has a collision flag set (the collision lock), else 0")
      .sample(std::uint64_t{lock.locked});
  m.family("axon_fps_sim_locks_total", MetricType::counter, "Times the collision lock went on").sample(lock.count);
  m.family("axon_fps_sim_time_seconds", MetricType::gauge, "Simulated time since the simulator started, in seconds").sample(time_s);
  m.family("axon_fps_sim_frames_processed_total", MetricType::counter, "Frames the robots took from their receive buffers")
      .sample(st.frames_processed);
  m.family("axon_fps_sim_frames_sent_total", MetricType::counter, "Frames the robots sent (replies and unsolicited)")
      .sample(st.frames_sent);
  m.family("axon_fps_sim_unsolicited_frames_total", MetricType::counter, "Frames the robots sent on their own (collision reports)")
      .sample(st.unsolicited);
  m.family("axon_fps_sim_send_errors_total", MetricType::counter, "Frames a bus refused to take from a robot").sample(st.send_errors);
  m.family("axon_fps_sim_collisions_total", MetricType::counter, "Collisions the simulator detected, by what was hit")
      .sample(st.neighbour_collisions, {{"kind", "neighbour"}})
      .sample(st.obstacle_collisions, {{"kind", "obstacle"}});
  m.family("axon_fps_sim_receive_overflows_total", MetricType::counter, "Frames lost to full robot receive buffers, all robots")
      .sample(simulator.simulator().receive_overflows());
  const auto& c = simulator.counters();
  m.family("axon_fps_sim_sync_edges_total", MetricType::counter, "Rising edges of the sync line").sample(c.sync_edges);
  m.family("axon_fps_sim_power_changes_total", MetricType::counter, "PLC relay switches, by relay")
      .sample(c.sextant_power_changes, {{"relay", "positioners"}})
      .sample(c.gateway_power_changes, {{"relay", "gateways"}});
}

void FpsSimView::Impl::write_robot_metrics(MetricsText& m) const {
  struct Field {
    std::string_view name;
    std::string_view help;
    std::uint64_t (*get)(const Row&);
  };
  static constexpr std::array<Field, 4> kFields{{
      {"axon_fps_sim_robot_requests_total", "Requests a robot answered", [](const Row& r) { return r.counters.requests; }},
      {"axon_fps_sim_robot_rejected_total", "Requests a robot answered with a non-zero response code",
       [](const Row& r) { return r.counters.rejected; }},
      {"axon_fps_sim_robot_collision_reports_total", "Collision reports a robot sent",
       [](const Row& r) { return r.counters.collisions; }},
      {"axon_fps_sim_robot_receive_overflows_total", "Frames lost to a robot's full receive buffer",
       [](const Row& r) { return r.overflows; }},
  }};
  for (const auto& f : kFields) {
    m.family(f.name, MetricType::counter, f.help);
    for (const auto& r : rows) {
      const auto id = fmt::format("{}", r.id);
      m.sample(f.get(r), {{"robot", id}, {"bus", r.bus}});
    }
  }
}

void FpsSimView::Impl::write_bus_metrics(MetricsText& m) const {
  struct Bus {
    std::uint64_t requests = 0, collisions = 0, overflows = 0;
  };
  std::map<std::string, Bus> buses;
  for (const auto& r : rows) {
    auto& b = buses[r.bus];
    b.requests += r.counters.requests;
    b.collisions += r.counters.collisions;
    b.overflows += r.overflows;
  }
  m.family("axon_fps_sim_bus_requests_total", MetricType::counter, "Requests the robots of a bus answered");
  for (const auto& [name, b] : buses) m.sample(b.requests, {{"bus", name}});
  m.family("axon_fps_sim_bus_collision_reports_total", MetricType::counter, "Collision reports the robots of a bus sent");
  for (const auto& [name, b] : buses) m.sample(b.collisions, {{"bus", name}});
  m.family("axon_fps_sim_bus_receive_overflows_total", MetricType::counter, "Frames lost to full receive buffers on a bus");
  for (const auto& [name, b] : buses) m.sample(b.overflows, {{"bus", name}});
  m.family("axon_fps_sim_bus_locks_total", MetricType::counter, "Times a robot of a bus caused the collision lock");
  for (const auto& [name, b] : buses) {
    const auto it = locks_by_bus.find(name);
    m.sample(it == locks_by_bus.end() ? 0 : it->second, {{"bus", name}});
  }
  m.family("axon_fps_sim_bus_frames_total", MetricType::counter, "Frames that went on a bus's wire");
  for (const auto& bus : plane.buses())
    if (const auto medium = simulator.medium(bus)) m.sample(medium->stats().frames, {{"bus", bus.to_string()}});
  m.family("axon_fps_sim_bus_busy_seconds_total", MetricType::counter, "Wire time of those frames at the bus's bitrate, in seconds");
  for (const auto& bus : plane.buses())
    if (const auto medium = simulator.medium(bus))
      m.sample(std::chrono::duration<double>(medium->stats().busy).count(), {{"bus", bus.to_string()}});
}

std::string FpsSimView::metrics() const {
  MetricsText m;
  impl_->write_plane_metrics(m);
  impl_->write_robot_metrics(m);
  impl_->write_bus_metrics(m);
  return m.take();
}

void FpsSimView::publish(Source& source, unsigned metrics_every) {
  update();
  source.publish(state_json());
  if (metrics_every == 0 || impl_->publishes++ % metrics_every == 0) source.publish_metrics(metrics());
}

}  // namespace axon::web
