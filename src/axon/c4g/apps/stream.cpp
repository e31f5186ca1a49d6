#include "axon/c4g/apps/stream.hpp"

#include "axon/c4g/protocol/mode.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace axon::c4g::apps {

using protocol::code;
using protocol::Mode;

namespace {
constexpr double kDeg = 180.0 / std::numbers::pi;
}

namespace {
OpenModeApp::Style stream_style(const StreamOptions& o) {
  return {.app = "stream", .waiting = "waiting for mode", .running = "playing", .mode = o.mode == 5 ? "5" : "4",
          .rearm = o.rearm, .exiting_runs = true};
}
}  // namespace

StreamApp::StreamApp(StreamOptions options) : OpenModeApp(stream_style(options)), options_(std::move(options)) {
  if (!options_.trajectory && options_.segments.empty())
    throw Exception(Error(CoreErrc::invalid_argument, "stream: no trajectory"));
  if (options_.trajectory && !options_.segments.empty())
    throw Exception(Error(CoreErrc::invalid_argument, "stream: give one trajectory or segments, not both"));
  for (std::size_t i = 0; i < options_.segments.size(); ++i) {
    const auto& seg = options_.segments[i];
    if (!seg.trajectory || seg.motion_type == 0)
      throw Exception(Error(CoreErrc::invalid_argument, "stream: a segment needs a trajectory and a motion type 1..255"));
    for (std::size_t k = 0; k < i; ++k)
      if (options_.segments[k].motion_type == seg.motion_type)
        throw Exception(Error(CoreErrc::invalid_argument, fmt::format("stream: two segments for motion type {}", seg.motion_type)));
  }
  if (options_.mode != 4 && options_.mode != 5)
    throw Exception(Error(CoreErrc::invalid_argument, fmt::format("stream: mode {} (4 or 5)", options_.mode)));
}

void StreamApp::setup(const protocol::InitPacket& init, const protocol::AxisMap& axes) {
  if (!begin_setup()) return;  // one run per serve (without re-arm)
  auto v = make_arm_view(init, axes, options_.arm);
  if (!v) return refuse("stream: %s", v.error().detail.c_str());
  view_ = std::move(v).value();
  const double period = view_->period_s;
  period_.store(period, std::memory_order_relaxed);
  tables_.clear();
  if (options_.trajectory) tables_.push_back(Table{0, options_.trajectory, {}, 0});
  for (const auto& seg : options_.segments) tables_.push_back(Table{seg.motion_type, seg.trajectory, {}, 0});
  for (auto& t : tables_)
    if (!build(*t.trajectory, t.motor, t.rows)) return set_phase(Phase::refused);
  table_ = tables_.front().motor.data();
  rows_ = tables_.front().rows;
  rows_shown_.store(rows_, std::memory_order_relaxed);
  hold_cycles_ = static_cast<std::size_t>(std::ceil(options_.hold_s / period - 1e-9));
}

bool StreamApp::build(const Trajectory& traj, std::vector<double>& table, std::size_t& rows) {
  const std::size_t n = view_->count;
  if (traj.axes() != n) {
    fail("stream: the trajectory has %zu axes, arm %zu has %zu", traj.axes(), options_.arm, n);
    return false;
  }
  const double period = view_->period_s;
  const double step = options_.per_cycle ? 1.0 : period;  // one cycle on the trajectory's clock
  rows = static_cast<std::size_t>(std::floor(traj.duration() / step + 1e-9)) + 1;
  if (traj.start_time() + static_cast<double>(rows - 1) * step < traj.end_time() - 1e-12) ++rows;  // end exactly
  table.assign(rows * n, 0.0);
  std::vector<double> pos(n), vel(n);
  protocol::ArmTransform::Vector link(static_cast<Eigen::Index>(n));
  for (std::size_t k = 0; k < rows; ++k) {
    const double t = std::min(traj.start_time() + static_cast<double>(k) * step, traj.end_time());
    traj.sample(t, pos, vel);
    for (std::size_t j = 0; j < n; ++j) link[static_cast<Eigen::Index>(j)] = pos[j];
    const auto motor = view_->transform.motor_velocity(link);  // the linear part K_r q / 2 pi
    for (std::size_t j = 0; j < n; ++j) table[k * n + j] = motor[static_cast<Eigen::Index>(j)];
  }
  const double max_step = options_.max_motor_speed * period;
  for (std::size_t k = 1; k < rows; ++k)
    for (std::size_t j = 0; j < n; ++j) {
      const double jump = std::fabs(table[k * n + j] - table[(k - 1) * n + j]);
      if (jump > max_step) {
        fail("stream: the trajectory is not continuous: axis %zu moves %.4f motor turns in one cycle at t=%.3f s "
             "(limit %.4f = %.1f turns/s x %.4f s)",
             j + 1, jump, (traj.start_time() / step + static_cast<double>(k)) * period, max_step, options_.max_motor_speed, period);
        return false;
      }
    }
  return true;
}

std::size_t StreamApp::find(std::uint8_t type) const noexcept {
  for (std::size_t i = 0; i < tables_.size(); ++i)
    if (tables_[i].motion_type == type && type != 0) return i;
  return static_cast<std::size_t>(-1);
}

bool StreamApp::start(std::size_t idx, const protocol::Packet& req, bool from_command) noexcept {
  const std::size_t n = view_->count, first = view_->first;
  const Table& t = tables_[idx];
  protocol::ArmTransform::Vector motor(static_cast<Eigen::Index>(n));
  for (std::size_t j = 0; j < n; ++j) motor[static_cast<Eigen::Index>(j)] = req.axes[first + j].d3;
  const auto link = view_->transform.link_position(motor);
  const auto& q0 = view_->transform.calibration();
  const Trajectory& traj = *t.trajectory;
  for (std::size_t j = 0; j < n; ++j) {
    const double begin = traj.value(0, j);
    const double here = options_.relative ? 0.0 : link[static_cast<Eigen::Index>(j)];
    if (std::fabs(begin - here) > options_.start_tolerance_rad) {
      if (options_.relative)
        refuse("stream: start point: a relative trajectory must start at 0, axis %zu starts at %.3f deg", j + 1, begin * kDeg);
      else
        refuse("stream: start point: axis %zu is at %.3f deg, the trajectory%s starts at %.3f deg (tolerance %.3f deg)",
               j + 1, here * kDeg, t.motion_type != 0 ? " segment" : "", begin * kDeg, options_.start_tolerance_rad * kDeg);
      return false;
    }
  }
  table_ = t.motor.data();
  rows_ = t.rows;
  rows_shown_.store(rows_, std::memory_order_relaxed);
  for (std::size_t j = 0; j < n; ++j) {
    if (options_.relative) base_[j] = (from_command ? last_[j] : req.axes[first + j].d3) - table_[j];
    else base_[j] = q0[static_cast<Eigen::Index>(j)];
  }
  if (!from_command)
    for (std::size_t j = 0; j < n; ++j) last_[j] = command(j, 0);
  s_ = 0;
  rate_ = 1;
  held_ = 0;
  hold_last_ = false;
  segment_.store(t.motion_type, std::memory_order_relaxed);
  set_phase(Phase::running);
  return true;
}

double StreamApp::command(std::size_t j, double s) const noexcept {
  const std::size_t n = view_->count;
  const double top = static_cast<double>(rows_ - 1);
  s = std::clamp(s, 0.0, top);
  const auto k = static_cast<std::size_t>(std::floor(s));
  const double a = s - static_cast<double>(k);
  const double p0 = table_[k * n + j];
  const double p1 = k + 1 < rows_ ? table_[(k + 1) * n + j] : p0;
  return base_[j] + p0 + a * (p1 - p0);
}

void StreamApp::enter(const host::CycleContext& ctx) noexcept {
  const std::size_t n = view_->count, first = view_->first;
  const bool segmented = !options_.segments.empty();
  const std::uint8_t type = ctx.motion_type(view_->arm);
  type_ = type;
  played_ = false;
  const std::size_t idx = segmented ? find(type) : 0;
  if (idx == static_cast<std::size_t>(-1)) {
    for (std::size_t j = 0; j < n; ++j) last_[j] = ctx.request.axes[first + j].d3;
    hold_last_ = true;
    set_phase(Phase::idle);
    note(kNoteUnknownType + type);
  } else if (start(idx, ctx.request, false)) {
    played_ = true;
    started(segmented ? kNoteSegment + type : kNoteStarted);
  }
}

void StreamApp::change_segment(const host::CycleContext& ctx, std::uint8_t type) noexcept {
  type_ = type;
  const std::size_t idx = find(type);
  if (type == 0 && played_) {
    set_phase(Phase::exiting);
    note(kNoteTypeCleared);
  } else if (idx == static_cast<std::size_t>(-1)) {
    hold_last_ = true;
    set_phase(Phase::idle);
    note(kNoteUnknownType + type);
  } else if (start(idx, ctx.request, true)) {
    played_ = true;
    note(kNoteSegment + type);
  }
}

void StreamApp::advance_playback() noexcept {
  const Phase ph = phase();
  if (ph == Phase::running) {
    if (stop_requested() && rate_ == 1.0) note(kNoteStopping);
    if (stop_requested()) rate_ = std::max(0.0, rate_ - view_->period_s / std::max(options_.stop_ramp_s, view_->period_s));
    if (rate_ < 1e-9) rate_ = 0;
    s_ += rate_;
    if (s_ >= static_cast<double>(rows_ - 1)) {
      s_ = static_cast<double>(rows_ - 1);
      set_phase(Phase::holding);
      note(kNoteEnded);
    } else if (rate_ <= 0.0) {
      set_phase(Phase::exiting);
    }
  } else if (ph == Phase::holding || ph == Phase::idle) {
    // Segments: hold until the motion type changes (or a stop request).
    if ((options_.segments.empty() && ++held_ >= hold_cycles_) || stop_requested()) set_phase(Phase::exiting);
  }
}

void StreamApp::step(const host::CycleContext& ctx, host::ReplyBuilder& reply) {
  if (!view_ || (rows_ == 0 && phase() != Phase::refused)) return;
  const auto& req = ctx.request;
  const std::size_t n = view_->count, first = view_->first;
  const std::int32_t mode = options_.mode;
  const std::int32_t standby = mode == 4 ? code(Mode::mode4_standby) : code(Mode::mode5_standby);
  Gate g = gate_for(req, first, n, mode);
  g.inside = g.entered || g.first_mode == standby;
  const Turn turned = turn(g, reply, view_->arm);
  if (turned == Turn::skip) return;
  const std::uint8_t type = ctx.motion_type(view_->arm);
  const Phase ph = phase();
  if (turned == Turn::start) enter(ctx);
  else if (!options_.segments.empty() && type != type_ && g.entered &&
           (ph == Phase::running || ph == Phase::holding || ph == Phase::idle))
    change_segment(ctx, type);  // the program picked another segment
  if (phase() == Phase::refused) {
    // Nothing moves: mode 4 holds (the server's safe reply: last target or actual position), mode 5
    // adds nothing; leave the open mode.
    if (g.entered) exit_from_open(reply, view_->arm);
    return;
  }
  advance(view_->period_s);
  advance_playback();
  if (g.first_mode == standby) {
    // Leaving (4' / 5'): hold the last target, no increments.
    for (std::size_t j = 0; j < n; ++j) {
      auto& r = reply.axis(first + j);
      r.d1 = mode == 4 ? static_cast<float>(last_[j]) : 0.0f;
      r.d2 = 0;
    }
    if (phase() == Phase::running || phase() == Phase::holding) set_phase(Phase::exiting);
    return;
  }
  for (std::size_t j = 0; j < n; ++j) {
    const double c = hold_last_ ? last_[j] : command(j, s_);
    const double delta = c - last_[j];
    auto& r = reply.axis(first + j);
    r.d1 = static_cast<float>(mode == 4 ? c : delta);
    r.d2 = static_cast<float>(delta);
    last_[j] = c;
  }
  progress_.store(s_, std::memory_order_relaxed);
  if (phase() == Phase::exiting) exit_from_open(reply, view_->arm);
}

void StreamApp::silence() noexcept {
  const Phase p = phase();
  if (p == Phase::running || p == Phase::holding) refuse("stream: packets stopped during the trajectory");
}

std::string StreamApp::note_text(std::int32_t c) const {
  switch (c) {
    case kNoteStarted:
      return fmt::format("stream: trajectory started (mode {}, arm {}, {} cycles)", options_.mode, options_.arm, table_rows());
    case kNoteEnded: return "stream: trajectory ended, holding the last point";
    case kNoteStopping: return "stream: stop requested, slowing down to rest";
    case kNoteTypeCleared: return "stream: motion type 0: the segments are over, leaving the open mode";
    default:
      if (c >= kNoteUnknownType && c < kNoteUnknownType + 256)
        return fmt::format("stream: no segment for motion type {}: holding", c - kNoteUnknownType);
      if (c >= kNoteSegment && c < kNoteSegment + 256) {
        const auto i = find(static_cast<std::uint8_t>(c - kNoteSegment));
        return fmt::format("stream: segment for motion type {} started (mode {}, arm {}, {} cycles)", c - kNoteSegment,
                           options_.mode, options_.arm, i < tables_.size() ? tables_[i].rows : 0);
      }
      return OpenModeApp::note_text(c);
  }
}

std::string StreamApp::status() const {
  const double period = period_.load(std::memory_order_relaxed);
  const std::string_view text = phase() == Phase::idle ? "holding (no segment)" : phase_text();
  const std::size_t rows = table_rows();
  return App::status() + fmt::format(" {} t={:.3f}/{:.3f} s", text, progress() * period,
                                     rows > 0 ? static_cast<double>(rows - 1) * period : 0.0);
}

std::string StreamApp::summary() const {
  const double period = period_.load(std::memory_order_relaxed);
  const std::size_t rows = table_rows();
  return App::summary() + fmt::format("stream: played {:.3f} s of {:.3f} s, phase {}\n", progress() * period,
                                      rows > 0 ? static_cast<double>(rows - 1) * period : 0.0, to_string(phase()));
}

}  // namespace axon::c4g::apps
