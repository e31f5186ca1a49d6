#include "axon/web/blmc_view.hpp"

#include "axon/core/error.hpp"
#include "axon/web/json_text.hpp"
#include "axon/web/metrics_text.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>

namespace axon::web {
namespace {

namespace host = blmc::host;
namespace protocol = blmc::protocol;

// The jitter histogram's upper bounds (|period - nominal|), in microseconds; one more bucket above.
constexpr std::array<double, 10> kJitterBoundsUs{5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000};

struct Flag {
  std::string_view name;
  std::uint8_t mask;
  std::string_view meaning;
};
constexpr std::array<Flag, 5> kFlags{{
    {"system_enabled", 0x01, "the board's system is enabled (ENABLE_SYS)"},
    {"motor1_enabled", 0x02, "motor 1 is enabled (ENABLE_MTR1)"},
    {"motor1_ready", 0x04, "motor 1 finished its alignment"},
    {"motor2_enabled", 0x08, "motor 2 is enabled (ENABLE_MTR2)"},
    {"motor2_ready", 0x10, "motor 2 finished its alignment"},
}};

constexpr std::array<host::FaultKind, 6> kFaultKinds{host::FaultKind::board_error,    host::FaultKind::undocumented_error,
                                                     host::FaultKind::board_disabled, host::FaultKind::stale_data,
                                                     host::FaultKind::position_limit, host::FaultKind::bad_command};

std::string error_name(std::uint8_t code) {
  if (code == protocol::kUndocumentedErrorCode) return "UNDOCUMENTED_6";
  return std::string(protocol::name(static_cast<protocol::ErrorCode>(code & 7u)));
}

// A fault kind as a label value and JSON key: "stale data" -> "stale_data".
std::string kind_name(host::FaultKind k) {
  std::string name = host::to_string(k);
  std::replace(name.begin(), name.end(), ' ', '_');
  return name;
}

double seconds(core::Duration d) { return std::chrono::duration<double>(d).count(); }

struct Sample {
  double t = 0;
  host::MotorPair current, position, velocity;  // A, rev, krpm
};

struct Board {
  BlmcBoardInfo info;
  std::vector<Sample> ring;  // the last samples, oldest at `head` once full
  std::size_t head = 0;
  std::size_t size = 0;
  Sample latest;
  std::uint8_t status = 0;
  bool have_status = false;
  bool tripped = false;
  std::optional<host::Fault> fault;
  std::string fault_text;
  std::array<std::uint64_t, 8> errors{};  // new board errors by code
  std::array<std::uint64_t, kFaultKinds.size()> stops{};

  void push(const Sample& s) {
    latest = s;
    ring[(head + size) % ring.size()] = s;
    if (size < ring.size()) ++size;
    else head = (head + 1) % ring.size();
  }
  void set_status(std::uint8_t byte) {
    const auto code = protocol::error_bits(byte);
    if (code != 0 && (!have_status || protocol::error_bits(status) != code)) ++errors[code];
    status = byte;
    have_status = true;
  }
};

struct Loop {
  bool seen = false;     // records arrived or a run ended
  bool running = false;  // records arrived and the run has not ended
  std::uint64_t cycles = 0, overruns = 0, lost = 0, missed = 0;
  std::optional<std::uint64_t> last_cycle;
  std::array<std::uint64_t, kJitterBoundsUs.size() + 1> jitter{};
  std::uint64_t periods = 0;
  double jitter_sum_s = 0, jitter_max_s = 0, period_s = 0;
};

}  // namespace

std::string_view blmc_error_meaning(std::uint8_t code) noexcept {
  switch (code) {
    case 0: return "no error";
    case 1: return "encoder error: the board cannot read a motor's position";
    case 2: return "CAN receive timeout: no command within the board's receive timeout (SET_CAN_RECV_TIMEOUT)";
    case 3: return "critical temperature (reserved: the boards have no temperature sensing)";
    case 4: return "position converter module failure";
    case 5: return "position rollover at +-100 rev (only with ENABLE_POS_ROLLOVER_ERROR=1)";
    case 6: return "undocumented error code 6 (a newer firmware's code or a corrupted byte): the board reports an error";
    case 7: return "other error (the firmware reports a transmit failure with it)";
    default: return "not an error code";
  }
}

struct BlmcView::Impl {
  explicit Impl(BlmcViewOptions o) : options(std::move(o)) {}

  void sample_record(const host::CycleRecord& r, double t);
  void time_record(const host::CycleRecord& r);
  void write_loop_metrics(MetricsText& m) const;
  void write_board_metrics(MetricsText& m) const;
  [[nodiscard]] std::string board_json(const Board& b) const;
  [[nodiscard]] std::string loop_json() const;

  BlmcViewOptions options;
  std::vector<Board> boards;
  Loop loop;
  std::optional<core::TimePoint> t0;  // the first record's start
  double next_sample_t = 0;
  double now_t = 0;
  unsigned publishes = 0;
};

BlmcView::BlmcView(BlmcViewOptions options) : impl_(std::make_unique<Impl>(std::move(options))) {
  const auto& o = impl_->options;
  if (o.boards.empty() || o.boards.size() > host::kMaxBoards)
    throw Exception(Error(CoreErrc::invalid_argument, fmt::format("blmc view: 1 to {} boards, not {}", host::kMaxBoards, o.boards.size())));
  if (!(o.sample_hz > 0) || !(o.history_s > 0) || o.nominal_period <= core::Duration::zero())
    throw Exception(Error(CoreErrc::invalid_argument, "blmc view: the sample rate, history and period must be > 0"));
  const auto capacity = static_cast<std::size_t>(std::ceil(o.sample_hz * o.history_s));
  for (const auto& b : o.boards) {
    Board board;
    board.info = b;
    board.ring.resize(std::max<std::size_t>(capacity, 1));
    impl_->boards.push_back(std::move(board));
  }
}
BlmcView::~BlmcView() = default;

void BlmcView::Impl::time_record(const host::CycleRecord& r) {
  loop.seen = loop.running = true;
  if (loop.last_cycle && r.cycle > *loop.last_cycle + 1) loop.lost += r.cycle - *loop.last_cycle - 1;
  if (loop.last_cycle && r.cycle > 0) {
    // The first cycle has no period (LoopTiming counts periods from the second).
    const double p = seconds(r.period);
    const double j = std::abs(p - seconds(options.nominal_period));
    const auto it = std::lower_bound(kJitterBoundsUs.begin(), kJitterBoundsUs.end(), j * 1e6);
    ++loop.jitter[static_cast<std::size_t>(it - kJitterBoundsUs.begin())];
    ++loop.periods;
    loop.jitter_sum_s += j;
    loop.jitter_max_s = std::max(loop.jitter_max_s, j);
    loop.period_s = p;
  }
  loop.last_cycle = r.cycle;
  loop.cycles = r.cycle + 1;
  loop.overruns = r.overruns;
}

void BlmcView::Impl::sample_record(const host::CycleRecord& r, double t) {
  const auto n = std::min<std::size_t>(r.boards, boards.size());
  for (std::size_t i = 0; i < n; ++i) {
    const auto& rb = r.board[i];
    auto& b = boards[i];
    b.set_status(rb.status);
    b.tripped = b.tripped || rb.tripped;
    if (t >= next_sample_t) b.push({t, rb.current, rb.position, rb.velocity});
  }
  if (t >= next_sample_t) {
    next_sample_t += 1.0 / options.sample_hz;
    if (next_sample_t <= t) next_sample_t = t + 1.0 / options.sample_hz;  // fell behind: no burst
  }
}

void BlmcView::add_record(const host::CycleRecord& record) {
  auto& im = *impl_;
  if (!im.t0) im.t0 = record.start;
  im.now_t = seconds(record.start - *im.t0);
  im.time_record(record);
  im.sample_record(record, im.now_t);
}

void BlmcView::add_measurements(std::size_t board, double t_s, const host::Measurements& m) {
  auto& im = *impl_;
  if (board >= im.boards.size()) return;
  auto& b = im.boards[board];
  im.now_t = t_s;
  if (m.status_byte.received()) b.set_status(m.status_byte.value);
  b.push({t_s, m.current.value, m.position.value, m.velocity.value});
}

void BlmcView::set_status(std::size_t board, std::uint8_t status_byte) {
  if (board < impl_->boards.size()) impl_->boards[board].set_status(status_byte);
}

void BlmcView::end_run(const host::LoopStats& stats, const std::optional<host::LoopFault>& fault) {
  auto& im = *impl_;
  im.loop.seen = true;
  im.loop.running = false;
  im.loop.cycles = stats.cycles;
  im.loop.overruns = stats.overruns;
  im.loop.missed = stats.missed;
  if (!fault || fault->board >= im.boards.size()) return;
  auto& b = im.boards[fault->board];
  b.tripped = true;
  b.fault = fault->fault;
  b.fault_text = fault->fault.describe();
  const auto k = std::find(kFaultKinds.begin(), kFaultKinds.end(), fault->fault.kind);
  if (k != kFaultKinds.end()) ++b.stops[static_cast<std::size_t>(k - kFaultKinds.begin())];
}

std::string BlmcView::info_json() const {
  const auto& o = impl_->options;
  std::string out;
  auto it = std::back_inserter(out);
  fmt::format_to(it, "{{\"family\":\"blmc\",\"command\":{},\"sample_hz\":{},\"history_s\":{},\"nominal_period_us\":{},\"boards\":[",
                 json_quote(o.command), o.sample_hz, o.history_s, seconds(o.nominal_period) * 1e6);
  for (std::size_t i = 0; i < o.boards.size(); ++i) {
    const auto& b = o.boards[i];
    fmt::format_to(it, "{}{{\"name\":{},\"limits\":", i ? "," : "", json_quote(b.name));
    if (!b.limits) {
      out += "null}";
      continue;
    }
    const auto& l = *b.limits;
    fmt::format_to(it, "{{\"motors\":[{},{}],\"max_current_a\":{},\"max_velocity_krpm\":{},\"stale_after_ms\":{},"
                       "\"status_stale_after_ms\":{},\"check_adc\":{},\"position\":[",
                   l.motors[0], l.motors[1], l.max_current_a, l.max_velocity_krpm, seconds(l.stale_after) * 1e3,
                   seconds(l.status_stale_after) * 1e3, l.check_adc);
    for (std::size_t m = 0; m < 2; ++m)
      fmt::format_to(it, "{}{{\"enabled\":{},\"min_rev\":{},\"max_rev\":{}}}", m ? "," : "", l.position[m].enabled,
                     l.position[m].min_rev, l.position[m].max_rev);
    out += "]}}";
  }
  out += "],\"flags\":[";
  for (std::size_t i = 0; i < kFlags.size(); ++i)
    fmt::format_to(it, "{}{{\"name\":\"{}\",\"mask\":{},\"meaning\":{}}}", i ? "," : "", kFlags[i].name, kFlags[i].mask,
                   json_quote(kFlags[i].meaning));
  out += "],\"error_codes\":[";
  for (std::uint8_t c = 0; c < 8; ++c)
    fmt::format_to(it, "{}{{\"code\":{},\"name\":\"{}\",\"meaning\":{}}}", c ? "," : "", c, error_name(c),
                   json_quote(blmc_error_meaning(c)));
  fmt::format_to(it, "],\"jitter_bounds_us\":[{}]}}", fmt::join(kJitterBoundsUs, ","));
  return out;
}

std::string BlmcView::Impl::loop_json() const {
  if (!loop.seen) return "null";
  const double mean = loop.periods ? loop.jitter_sum_s / static_cast<double>(loop.periods) : 0.0;
  return fmt::format("{{\"running\":{},\"cycles\":{},\"overruns\":{},\"missed\":{},\"records_lost\":{},\"period_us\":{:.1f},"
                     "\"jitter_mean_us\":{:.2f},\"jitter_max_us\":{:.1f},\"jitter\":[{}]}}",
                     loop.running, loop.cycles, loop.overruns, loop.missed, loop.lost, loop.period_s * 1e6, mean * 1e6,
                     loop.jitter_max_s * 1e6, fmt::join(loop.jitter, ","));
}

std::string BlmcView::Impl::board_json(const Board& b) const {
  std::string out;
  auto it = std::back_inserter(out);
  const auto code = protocol::error_bits(b.status);
  fmt::format_to(it, "{{\"name\":{},\"have_status\":{},\"status\":{},\"flags\":{{", json_quote(b.info.name), b.have_status,
                 b.status);
  for (std::size_t i = 0; i < kFlags.size(); ++i)
    fmt::format_to(it, "{}\"{}\":{}", i ? "," : "", kFlags[i].name, (b.status & kFlags[i].mask) != 0);
  fmt::format_to(it, "}},\"error\":{{\"code\":{},\"name\":\"{}\",\"meaning\":{}}},\"errors\":{{", code, error_name(code),
                 json_quote(blmc_error_meaning(code)));
  bool first = true;
  for (std::uint8_t c = 1; c < 8; ++c) {
    if (b.errors[c] == 0) continue;
    fmt::format_to(it, "{}\"{}\":{}", first ? "" : ",", error_name(c), b.errors[c]);
    first = false;
  }
  fmt::format_to(it, "}},\"tripped\":{},\"fault\":", b.tripped);
  if (b.fault) fmt::format_to(it, "{{\"kind\":\"{}\",\"text\":{}}}", kind_name(b.fault->kind), json_quote(b.fault_text));
  else out += "null";
  // The traces, oldest first, one array per series (the page plots them as they are).
  const auto series = [&](const char* key, auto get, const char* spec) {
    fmt::format_to(it, ",\"{}\":[", key);
    for (std::size_t k = 0; k < b.size; ++k) {
      if (k) out += ',';
      fmt::format_to(it, fmt::runtime(spec), get(b.ring[(b.head + k) % b.ring.size()]));
    }
    out += ']';
  };
  out += ",\"samples\":{\"n\":" + std::to_string(b.size);
  series("t", [](const Sample& s) { return s.t; }, "{:.3f}");
  series("i1", [](const Sample& s) { return s.current.motor1; }, "{:.4g}");
  series("i2", [](const Sample& s) { return s.current.motor2; }, "{:.4g}");
  series("p1", [](const Sample& s) { return s.position.motor1; }, "{:.5g}");
  series("p2", [](const Sample& s) { return s.position.motor2; }, "{:.5g}");
  series("v1", [](const Sample& s) { return s.velocity.motor1; }, "{:.4g}");
  series("v2", [](const Sample& s) { return s.velocity.motor2; }, "{:.4g}");
  out += "}}";
  return out;
}

std::string BlmcView::state_json() const {
  const auto& im = *impl_;
  std::string out;
  out.reserve(im.boards.size() * (im.boards.front().ring.size() * 50 + 1024) + 512);
  const auto wall = std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  fmt::format_to(std::back_inserter(out), "{{\"t_s\":{:.3f},\"wall_s\":{:.3f},\"command\":{},\"loop\":{},\"boards\":[", im.now_t,
                 wall, json_quote(im.options.command), im.loop_json());
  for (std::size_t i = 0; i < im.boards.size(); ++i) {
    if (i) out += ',';
    out += im.board_json(im.boards[i]);
  }
  out += "]}";
  return out;
}

void BlmcView::Impl::write_loop_metrics(MetricsText& m) const {
  if (!loop.seen) return;
  m.family("axon_blmc_loop_running", MetricType::gauge, "1 while the control loop runs, else 0").sample(std::uint64_t{loop.running});
  m.family("axon_blmc_loop_cycles_total", MetricType::counter, "Cycles the real-time control loop ran").sample(loop.cycles);
  m.family("axon_blmc_loop_overruns_total", MetricType::counter, "Cycles that finished after the next cycle's deadline")
      .sample(loop.overruns);
  m.family("axon_blmc_loop_records_lost_total", MetricType::counter,
           "Cycle records the loop could not hand over (its queue was full): missing from the traces and the histogram")
      .sample(loop.lost);
  m.family("axon_blmc_loop_nominal_period_seconds", MetricType::gauge, "The loop's nominal period, in seconds")
      .sample(seconds(options.nominal_period));
  std::array<double, kJitterBoundsUs.size()> bounds{};
  std::transform(kJitterBoundsUs.begin(), kJitterBoundsUs.end(), bounds.begin(), [](double us) { return us / 1e6; });
  m.family("axon_blmc_loop_jitter_seconds", MetricType::histogram,
           "Jitter of the control loop: |period - nominal period| of each cycle, in seconds")
      .histogram(bounds, loop.jitter, loop.jitter_sum_s);
}

void BlmcView::Impl::write_board_metrics(MetricsText& m) const {
  struct Quantity {
    std::string_view name, help;
    double scale;
    host::MotorPair Sample::*pair;
  };
  static constexpr std::array<Quantity, 3> kQuantities{{
      {"axon_blmc_current_amperes", "A motor's latest measured current (Iq), in amperes", 1.0, &Sample::current},
      {"axon_blmc_position_revolutions", "A motor's latest position, in motor revolutions (unwrapped)", 1.0, &Sample::position},
      {"axon_blmc_velocity_revolutions_per_second", "A motor's latest velocity, in motor revolutions per second", 1000.0 / 60.0,
       &Sample::velocity},
  }};
  for (const auto& q : kQuantities) {
    m.family(q.name, MetricType::gauge, q.help);
    for (const auto& b : boards) {
      const auto& p = b.latest.*q.pair;
      m.sample(p.motor1 * q.scale, {{"board", b.info.name}, {"motor", "1"}}).sample(p.motor2 * q.scale, {{"board", b.info.name}, {"motor", "2"}});
    }
  }
  m.family("axon_blmc_status_flag", MetricType::gauge, "A flag of the board's latest status frame, 1 when set");
  for (const auto& b : boards)
    for (const auto& f : kFlags) m.sample(std::uint64_t{(b.status & f.mask) != 0}, {{"board", b.info.name}, {"flag", f.name}});
  m.family("axon_blmc_error_code", MetricType::gauge, "The error code of the board's latest status frame (0: none)");
  for (const auto& b : boards) m.sample(std::uint64_t{protocol::error_bits(b.status)}, {{"board", b.info.name}});
  m.family("axon_blmc_board_errors_total", MetricType::counter, "Errors the board reported, by code (a status error code that changed to it)");
  for (const auto& b : boards)
    for (std::uint8_t c = 1; c < 8; ++c) m.sample(b.errors[c], {{"board", b.info.name}, {"code", error_name(c)}});
  m.family("axon_blmc_safety_tripped", MetricType::gauge, "1 once the host's safety supervisor stopped the board, else 0");
  for (const auto& b : boards) m.sample(std::uint64_t{b.tripped}, {{"board", b.info.name}});
  m.family("axon_blmc_safety_stops_total", MetricType::counter,
           "Control runs the host's safety supervisor ended, by the fault's kind (stale_data: a measurement too old)");
  for (const auto& b : boards)
    for (std::size_t k = 0; k < kFaultKinds.size(); ++k) m.sample(b.stops[k], {{"board", b.info.name}, {"kind", kind_name(kFaultKinds[k])}});
}

std::string BlmcView::metrics() const {
  MetricsText m;
  impl_->write_loop_metrics(m);
  impl_->write_board_metrics(m);
  m.family("axon_blmc_limit_max_current_amperes", MetricType::gauge, "The current clamp in force, in amperes");
  for (const auto& b : impl_->boards)
    if (b.info.limits) m.sample(b.info.limits->max_current_a, {{"board", b.info.name}});
  m.family("axon_blmc_limit_max_velocity_revolutions_per_second", MetricType::gauge,
           "The velocity above which a motor gets zero current, in motor revolutions per second");
  for (const auto& b : impl_->boards)
    if (b.info.limits) m.sample(host::krpm_to_rev_per_s(b.info.limits->max_velocity_krpm), {{"board", b.info.name}});
  return m.take();
}

void BlmcView::publish(Source& source, unsigned metrics_every) {
  source.publish(state_json());
  if (metrics_every == 0 || impl_->publishes++ % metrics_every == 0) source.publish_metrics(metrics());
}

}  // namespace axon::web
