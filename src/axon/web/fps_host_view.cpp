#include "axon/web/fps_host_view.hpp"

#include "axon/core/clock.hpp"
#include "axon/core/wakeup.hpp"
#include "axon/fps/host/focal_plane_array.hpp"
#include "axon/fps/host/concurrent.hpp"  // after the array: it needs the host's asio alias
#include "axon/fps/layout/focal_plane.hpp"
#include "axon/fps/protocol/status.hpp"
#include "axon/web/json_text.hpp"
#include "axon/web/metrics_text.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <iterator>
#include <map>
#include <optional>

namespace axon::web {
namespace {

namespace fhost = fps::host;
namespace fproto = fps::protocol;

constexpr std::array<std::string_view, 6> kHostStates{"ready", "moving", "not-initialised", "collided", "offline", "bootloader"};

std::size_t host_state_index(std::string_view s) {
  return static_cast<std::size_t>(std::find(kHostStates.begin(), kHostStates.end(), s) - kHostStates.begin());
}

// What this view's own reads found about one robot.
struct HostReads {
  std::optional<fhost::ArmAngles> angles;
  bool tried = false;       // a read of this view was answered or failed at least once
  bool answering = false;   // the latest read of this view was answered
  bool bootloader = false;  // its status read said the bootloader runs
  std::optional<core::TimePoint> last_reply;
  std::uint64_t failures = 0;
  std::string error;        // why the latest read failed
};

// One robot as the last update() saw it.
struct HostRow {
  std::uint16_t id = 0;
  std::size_t bus = 0;
  std::string bus_name;
  std::optional<fhost::ArmAngles> angles;
  std::string_view state;
  std::uint64_t status = 0;
  std::string firmware;
  std::uint64_t collisions = 0;  // collision reports the array recorded from it
  std::optional<double> ago_s;
  std::uint64_t failures = 0;
  std::string error;
};

std::string_view host_robot_state(const fhost::Array& array, const fhost::Positioner* p, const HostReads& r) {
  const auto& st = p ? p->last_status() : std::nullopt;
  const bool heard = r.tried ? r.answering : (p && (p->firmware() || st || p->last_bootloader_status()));
  if (!heard) return "offline";
  if (r.bootloader || (p && (p->in_bootloader() || (p->last_bootloader_status() && !st)))) return "bootloader";
  if (!st) return "offline";
  if (st->collided()) return "collided";
  if (array.moving().contains(p->id()) || (st->initialized() && !st->idle())) return "moving";
  if (!st->initialized() || !st->motors_calibrated()) return "not-initialised";
  return "ready";
}

}  // namespace

struct FpsHostView::Impl {
  explicit Impl(fhost::FocalPlaneArray& a) : fpa(a) {}

  boost::asio::awaitable<void> read_robot(std::uint16_t id, HostReads& r, HostReading mode);
  void fail(HostReads& r, const Error& e);
  void update_lock();
  void write_plane_metrics(MetricsText& m) const;
  void write_bus_metrics(MetricsText& m) const;
  void write_robot_metrics(MetricsText& m) const;

  fhost::FocalPlaneArray& fpa;
  HostReading reading = HostReading::all;
  bool in_round = false;  // read() under way
  std::map<std::uint16_t, HostReads> reads;
  std::vector<HostRow> rows;
  FpsHostLock lock;
  unsigned publishes = 0;
};

FpsHostView::FpsHostView(fhost::FocalPlaneArray& array) : impl_(std::make_unique<Impl>(array)) {}
FpsHostView::~FpsHostView() = default;

void FpsHostView::set_reading(HostReading mode) noexcept { impl_->reading = mode; }
HostReading FpsHostView::reading() const noexcept { return impl_->reading; }
bool FpsHostView::reading_now() const noexcept { return impl_->in_round; }
const FpsHostLock& FpsHostView::lock() const noexcept { return impl_->lock; }

void FpsHostView::Impl::fail(HostReads& r, const Error& e) {
  if (e == fhost::HostErrc::cancelled || e == fhost::HostErrc::closed) return;  // the array closing: nothing learnt
  r.tried = true;
  r.answering = false;
  ++r.failures;
  r.error = e.message();
}

boost::asio::awaitable<void> FpsHostView::Impl::read_robot(std::uint16_t id, HostReads& r, HostReading mode) {
  fhost::Positioner* p = fpa.array().find(id);
  if (!p) co_return;
  if (!p->firmware()) {
    auto fw = co_await p->read_firmware_version();
    if (!fw) co_return fail(r, fw.error());
  }
  if (p->in_bootloader()) {
    auto bs = co_await p->read_bootloader_status();
    if (!bs) co_return fail(r, bs.error());
    r.bootloader = true;
  } else {
    if (mode == HostReading::all) {
      auto st = co_await p->read_status();
      r.bootloader = !st && st.error() == fhost::HostErrc::not_ready;  // a 4-byte answer: the bootloader
      if (!st && !r.bootloader) co_return fail(r, st.error());
    }
    if (!r.bootloader) {
      auto pos = co_await p->read_position();
      if (!pos) co_return fail(r, pos.error());
      r.angles = pos.value();
    }
  }
  r.tried = true;
  r.answering = true;
  r.last_reply = core::steady_now();
  r.error.clear();
}

boost::asio::awaitable<void> FpsHostView::read() {
  const HostReading mode = impl_->reading;
  if (mode == HostReading::none) co_return;
  const auto ids = impl_->fpa.array().ids();
  std::vector<HostReads*> slots;
  slots.reserve(ids.size());
  for (auto id : ids) slots.push_back(&impl_->reads[id]);  // map nodes stay put while the reads run
  Impl* im = impl_.get();
  struct Round {  // in_round while the requests may go out, whatever ends the round
    bool& flag;
    ~Round() { flag = false; }
  } round{im->in_round};
  im->in_round = true;
  co_await fhost::for_each_concurrently(ids.size(), [im, &ids, &slots, mode](std::size_t i) -> boost::asio::awaitable<void> {
    co_await im->read_robot(ids[i], *slots[i], mode);
  });
}

void FpsHostView::Impl::update_lock() {
  const auto& ls = fpa.array().lock_state();
  std::vector<std::uint16_t> collided;
  auto add = [&collided](std::uint16_t id) {
    if (std::find(collided.begin(), collided.end(), id) == collided.end()) collided.push_back(id);
  };
  const fhost::Collision* cause = nullptr;
  for (const auto& c : ls.collisions) {
    if (c.caused_lock && !cause) cause = &c;
  }
  if (cause) add(cause->positioner);
  for (const auto& c : ls.collisions) add(c.positioner);
  for (const auto& r : rows)
    if (r.state == "collided") add(r.id);
  lock.locked = ls.locked;
  lock.reason = ls.locked ? ls.reason : std::string{};
  lock.collided = ls.locked ? std::move(collided) : std::vector<std::uint16_t>{};
  lock.count = fpa.array().counters().collision_locks;
  lock.robot = 0;
  lock.bus.clear();
  lock.arm.clear();
  if (!ls.locked || !cause) return;
  lock.robot = cause->positioner;
  lock.bus = cause->bus < fpa.bus_count() ? fpa.bus_ref(cause->bus).to_string() : std::string{};
  lock.arm = cause->code == fproto::ResponseCode::alpha_collision ? "alpha" : "beta";
}

void FpsHostView::update() {
  auto& im = *impl_;
  const auto& array = im.fpa.array();
  const auto ids = array.ids();
  const auto now = core::steady_now();
  std::map<std::uint16_t, std::uint64_t> reports;
  for (const auto& c : array.lock_state().collisions) ++reports[c.positioner];
  im.rows.resize(ids.size());
  for (std::size_t i = 0; i < ids.size(); ++i) {
    const auto* p = array.find(ids[i]);
    const auto& r = im.reads[ids[i]];
    HostRow& row = im.rows[i];
    row.id = ids[i];
    const auto bus = array.bus_of(ids[i]);
    row.bus = bus ? bus.value() : 0;
    row.bus_name = row.bus < im.fpa.bus_count() ? im.fpa.bus_ref(row.bus).to_string() : std::string{};
    row.angles = r.angles;
    row.state = host_robot_state(array, p, r);
    row.status = p && p->last_status() ? p->last_status()->raw() : 0;
    row.firmware = p && p->firmware() ? p->firmware()->to_string() : std::string{};
    const auto it = reports.find(ids[i]);
    row.collisions = it == reports.end() ? 0 : it->second;
    row.ago_s = r.last_reply ? std::optional<double>(std::chrono::duration<double>(now - *r.last_reply).count()) : std::nullopt;
    row.failures = r.failures;
    row.error = r.error;
  }
  im.update_lock();
}

std::string FpsHostView::info_json() const {
  const auto& plane = impl_->fpa.plane();
  std::string out;
  auto o = std::back_inserter(out);
  fmt::format_to(o, "{{\"family\":\"fps\",\"view\":\"host\",\"layout\":{},\"pitch_mm\":{},\"robots\":[", json_quote(plane.name()),
                 plane.pitch_mm());
  bool first = true;
  for (const auto& s : plane.robots()) {
    if (s.offline) continue;
    fmt::format_to(o, "{}{{\"id\":{},\"x\":{},\"y\":{},\"orientation\":{},\"alpha_mm\":{},\"beta_mm\":{},\"bus\":{},\"sextant\":{}}}",
                   first ? "" : ",", s.id, s.x_mm, s.y_mm, s.orientation_deg, s.alpha_length_mm.value_or(plane.arms().alpha_length_mm),
                   plane.arms().beta_collision_mm, json_quote(s.bus.to_string()), s.sextant);
    first = false;
  }
  out += "],\"fiducials\":[";
  first = true;
  for (const auto& f : plane.fiducials()) {
    fmt::format_to(o, "{}{{\"id\":{},\"x\":{},\"y\":{}}}", first ? "" : ",", f.id, f.x_mm, f.y_mm);
    first = false;
  }
  out += "],\"status_bits\":[";
  first = true;
  for (const auto& b : fproto::kStatusBits) {
    fmt::format_to(o, "{}{{\"bit\":{},\"name\":{},\"meaning\":{}}}", first ? "" : ",", static_cast<unsigned>(b.bit),
                   json_quote(b.name), json_quote(b.meaning));
    first = false;
  }
  out += "],\"states\":[";
  for (std::size_t i = 0; i < kHostStates.size(); ++i) fmt::format_to(o, "{}\"{}\"", i ? "," : "", kHostStates[i]);
  out += "]}";
  return out;
}

std::string FpsHostView::state_json() const {
  const auto& im = *impl_;
  std::array<std::size_t, kHostStates.size()> counts{};
  for (const auto& r : im.rows) counts[host_state_index(r.state)]++;
  std::string out;
  out.reserve(im.rows.size() * 140 + 512);
  auto o = std::back_inserter(out);
  const auto wall = std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  fmt::format_to(o, "{{\"wall_s\":{:.3f},\"moving\":{},\"states\":{{", wall, counts[1]);
  for (std::size_t i = 0; i < kHostStates.size(); ++i) fmt::format_to(o, "{}\"{}\":{}", i ? "," : "", kHostStates[i], counts[i]);
  const auto& l = im.lock;
  fmt::format_to(o, "}},\"lock\":{{\"locked\":{},\"robot\":{},\"bus\":{},\"arm\":{},\"count\":{},\"collided\":[{}],\"reason\":{}}},"
                 "\"robots\":[",
                 l.locked, l.robot, json_quote(l.bus), json_quote(l.arm), l.count, fmt::join(l.collided, ","), json_quote(l.reason));
  bool first = true;
  for (const auto& r : im.rows) {
    const auto a = r.angles ? fmt::format("{:.3f}", r.angles->alpha) : std::string("null");
    const auto b = r.angles ? fmt::format("{:.3f}", r.angles->beta) : std::string("null");
    const auto ago = r.ago_s ? fmt::format("{:.3f}", *r.ago_s) : std::string("null");
    fmt::format_to(o, "{}{{\"id\":{},\"a\":{},\"b\":{},\"s\":\"{}\",\"st\":\"{:016x}\",\"fw\":{},\"col\":{},\"ago\":{},\"err\":{}}}",
                   first ? "" : ",", r.id, a, b, r.state, r.status, json_quote(r.firmware), r.collisions, ago,
                   json_quote(r.error));
    first = false;
  }
  out += "]}";
  return out;
}

void FpsHostView::Impl::write_plane_metrics(MetricsText& m) const {
  std::array<std::uint64_t, kHostStates.size()> counts{};
  for (const auto& r : rows) counts[host_state_index(r.state)]++;
  m.family("axon_fps_host_robots", MetricType::gauge, "Robots the host knows, by the state their replies show");
  for (std::size_t i = 0; i < kHostStates.size(); ++i) m.sample(counts[i], {{"state", kHostStates[i]}});
  const auto& c = fpa.array().counters();
  m.family("axon_fps_host_locked", MetricType::gauge, "1 while the array is locked (collision or a stop of every robot), else 0")
      .sample(std::uint64_t{lock.locked});
  m.family("axon_fps_host_collision_locks_total", MetricType::counter, "Collision reports that locked the array")
      .sample(c.collision_locks);
  m.family("axon_fps_host_expected_collisions_total", MetricType::counter, "Collision reports while the array was already locked")
      .sample(c.expected_collisions);
  m.family("axon_fps_host_emergency_stops_total", MetricType::counter, "TRAJECTORY_ABORT broadcasts to every bus (stops of every robot)")
      .sample(c.emergency_stops);
  m.family("axon_fps_host_start_failures_total", MetricType::counter, "Trajectory starts some robot did not acknowledge")
      .sample(c.start_failures);
  m.family("axon_fps_host_unlocks_total", MetricType::counter, "Unlocks of the array").sample(c.unlocks);
  m.family("axon_fps_host_bus_off_restarts_total", MetricType::counter, "Bus-offs handled (every robot stopped, the channel restarted)")
      .sample(fpa.bus_off_restarts());
  m.family("axon_fps_host_gateway_losses_total", MetricType::counter, "Times a gateway's connection was lost");
  for (const auto& g : fpa.gateways()) m.sample(std::uint64_t{g.losses}, {{"gateway", fmt::format("{}", g.id)}});
  m.family("axon_fps_host_gateway_down", MetricType::gauge, "1 while a gateway's connection is lost and not restored");
  for (const auto& g : fpa.gateways()) m.sample(std::uint64_t{g.down}, {{"gateway", fmt::format("{}", g.id)}});
}

void FpsHostView::Impl::write_bus_metrics(MetricsText& m) const {
  struct Field {
    std::string_view name;
    std::string_view help;
    std::uint64_t (*get)(const fhost::ClientCounters&);
  };
  static constexpr std::array<Field, 9> kFields{{
      {"axon_fps_host_bus_requests_total", "Request frames the host sent on a bus (retries and broadcasts included)",
       [](const fhost::ClientCounters& c) { return c.sent; }},
      {"axon_fps_host_bus_replies_total", "Replies matched to a request or broadcast", [](const fhost::ClientCounters& c) { return c.replies; }},
      {"axon_fps_host_bus_timeouts_total", "Request attempts that got no reply in time", [](const fhost::ClientCounters& c) { return c.timeouts; }},
      {"axon_fps_host_bus_retries_total", "Repeated attempts of reads after a timeout", [](const fhost::ClientCounters& c) { return c.retries; }},
      {"axon_fps_host_bus_late_replies_total", "Replies that came after their request timed out",
       [](const fhost::ClientCounters& c) { return c.late; }},
      {"axon_fps_host_bus_unmatched_replies_total", "Replies no request or broadcast waited for",
       [](const fhost::ClientCounters& c) { return c.unmatched; }},
      {"axon_fps_host_bus_send_errors_total", "Request frames the bus refused", [](const fhost::ClientCounters& c) { return c.send_errors; }},
      {"axon_fps_host_bus_collision_reports_total", "Collision reports received on a bus",
       [](const fhost::ClientCounters& c) { return c.collisions; }},
      {"axon_fps_host_bus_refused_total", "Moves the collision lock refused (nothing sent)",
       [](const fhost::ClientCounters& c) { return c.refused; }},
  }};
  const auto& array = fpa.array();
  for (const auto& f : kFields) {
    m.family(f.name, MetricType::counter, f.help);
    for (std::size_t b = 0; b < array.bus_count(); ++b) m.sample(f.get(array.client(b).counters()), {{"bus", fpa.bus_ref(b).to_string()}});
  }
  m.family("axon_fps_host_bus_receive_overflows_total", MetricType::counter, "Frames lost because the host's receive queue of a bus was full");
  for (std::size_t b = 0; b < array.bus_count(); ++b)
    m.sample(array.client(b).bus().stats().rx_dropped, {{"bus", fpa.bus_ref(b).to_string()}});
}

void FpsHostView::Impl::write_robot_metrics(MetricsText& m) const {
  m.family("axon_fps_host_robot_collision_reports_total", MetricType::counter, "Collision reports the array recorded from a robot");
  for (const auto& r : rows) {
    const auto id = fmt::format("{}", r.id);
    m.sample(r.collisions, {{"robot", id}, {"bus", r.bus_name}});
  }
  m.family("axon_fps_host_robot_read_failures_total", MetricType::counter, "Reads of the web view a robot did not answer");
  for (const auto& r : rows) {
    const auto id = fmt::format("{}", r.id);
    m.sample(r.failures, {{"robot", id}, {"bus", r.bus_name}});
  }
}

std::string FpsHostView::metrics() const {
  MetricsText m;
  impl_->write_plane_metrics(m);
  impl_->write_bus_metrics(m);
  impl_->write_robot_metrics(m);
  return m.take();
}

void FpsHostView::publish(Source& source, unsigned metrics_every) {
  update();
  source.publish(state_json());
  if (metrics_every == 0 || impl_->publishes++ % metrics_every == 0) source.publish_metrics(metrics());
}

boost::asio::awaitable<void> FpsHostView::run(Source& source, std::chrono::milliseconds publish_period,
                                       std::chrono::milliseconds read_period, std::shared_ptr<const bool> alive) {
  FpsHostView* self = this;
  Source* src = &source;
  co_await fhost::for_each_concurrently(2, [self, src, publish_period, read_period, alive](std::size_t i) -> boost::asio::awaitable<void> {
    while (*alive) {
      if (i == 0) {
        const auto start = core::steady_now();
        self->publish(*src);  // the metrics every 10th time
        const auto spent = core::steady_now() - start;
        co_await core::sleep_for(spent < publish_period ? publish_period - spent : core::Duration{0});
      } else {
        const auto start = core::steady_now();
        co_await self->read();
        const auto spent = core::steady_now() - start;
        co_await core::sleep_for(spent < read_period ? read_period - spent : core::Duration{0});
      }
    }
  });
}

}  // namespace axon::web
