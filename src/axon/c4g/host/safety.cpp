#include "axon/c4g/host/safety.hpp"

#include "axon/c4g/protocol/mode.hpp"
#include "axon/c4g/protocol/safety.hpp"
#include "axon/c4g/protocol/transform.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <numbers>

namespace axon::c4g::host {

using protocol::Mode;
using protocol::code;

std::string_view to_string(FaultReason r) noexcept {
  switch (r) {
    case FaultReason::none: return "none";
    case FaultReason::following_error: return "following error over threshold";
    case FaultReason::stroke_end: return "commanded position beyond a stroke end";
    case FaultReason::discontinuity: return "commanded position jumped more than the allowed step";
    case FaultReason::not_finite: return "reply holds a value that is not finite";
    case FaultReason::unused_field: return "reply carries data in a field its mode does not use";
    case FaultReason::controller_exception: return "controller threw an exception";
    case FaultReason::controller_late: return "controller overran its budget";
    case FaultReason::bad_packet: return "malformed packet from the robot controller";
    case FaultReason::user_request: return "stop requested by the application";
  }
  return "unknown";
}

namespace {

bool pc_closes_loops(std::int32_t m) noexcept {
  return m == code(Mode::mode1) || m == code(Mode::mode2) || m == code(Mode::mode1_standby) ||
         m == code(Mode::mode2_standby);
}

bool pc_supplies_current(std::int32_t m) noexcept { return pc_closes_loops(m) || m == code(Mode::mode9); }

// Modes whose target the following error is measured against: the PC closes the loops (1, 2) or
// generates the trajectory (4, 5).
bool pc_checks_following(std::int32_t m) noexcept {
  return pc_closes_loops(m) || m == code(Mode::mode4) || m == code(Mode::mode4_standby) || m == code(Mode::mode5) ||
         m == code(Mode::mode5_standby);
}

// Modes where the PC changes the motion without commanding a position: the actual position is
// held to the stroke ends.
bool pc_contributes(std::int32_t m) noexcept {
  return m == code(Mode::mode2) || m == code(Mode::mode2_standby) || m == code(Mode::mode8) || m == code(Mode::mode9);
}

// Modes whose reply commands an increment on the controller's target (continuity from D1).
bool incremental(std::int32_t m) noexcept {
  return m == code(Mode::mode5) || m == code(Mode::mode5_standby) || m == code(Mode::mode7) ||
         m == code(Mode::mode7_standby);
}

bool finite(const protocol::Axis& a) noexcept {
  return std::isfinite(a.d1) && std::isfinite(a.d2) && std::isfinite(a.d3) && std::isfinite(a.d4) &&
         std::isfinite(a.d5) && std::isfinite(a.ext1) && std::isfinite(a.ext2) && std::isfinite(a.ext3);
}

Error bad_stroke_end(std::string_view text, std::string_view why) {
  return Error(CoreErrc::invalid_argument,
               fmt::format("stroke end '{}': {} (expected [ARM.]AXIS=MIN:MAX in degrees, e.g. 3=-120:150)", text, why));
}

bool parse_number(std::string_view t, double& out) {
  const auto r = std::from_chars(t.data(), t.data() + t.size(), out);
  return r.ec == std::errc{} && r.ptr == t.data() + t.size();
}

}  // namespace

Result<void> parse_stroke_end(std::string_view text, std::size_t default_arm, SafetyConfig& config) {
  const auto eq = text.find('=');
  const auto colon = text.find(':', eq == std::string_view::npos ? 0 : eq);
  if (eq == std::string_view::npos || colon == std::string_view::npos) return bad_stroke_end(text, "no '=' or ':'");
  std::string_view who = text.substr(0, eq);
  double arm = static_cast<double>(default_arm), axis = 0, lo = 0, hi = 0;
  if (const auto dot = who.find('.'); dot != std::string_view::npos) {
    if (!parse_number(who.substr(0, dot), arm)) return bad_stroke_end(text, "the arm is not a number");
    who = who.substr(dot + 1);
  }
  if (!parse_number(who, axis)) return bad_stroke_end(text, "the axis is not a number");
  if (!parse_number(text.substr(eq + 1, colon - eq - 1), lo) || !parse_number(text.substr(colon + 1), hi))
    return bad_stroke_end(text, "MIN and MAX must be numbers");
  if (arm < 1 || arm > protocol::kMaxArms || arm != std::floor(arm)) return bad_stroke_end(text, "arms are 1..4");
  if (axis < 1 || axis > protocol::kAxesPerArm || axis != std::floor(axis)) return bad_stroke_end(text, "axes are 1..10");
  if (!(lo < hi)) return bad_stroke_end(text, "MIN must be below MAX");
  config.joints[static_cast<std::size_t>(arm) - 1][static_cast<std::size_t>(axis) - 1] = {lo, hi};
  return ok();
}

Safety::Safety(const SafetyConfig& config) : config_(config) {
  thresholds_ = config.following_error_override;
  limits_ = config.current_limit_override;
  set_steps(0.002);  // until the initialization packet gives the period: the controllers' usual 2 ms
}

void Safety::set_steps(double period_s) noexcept {
  for (std::size_t i = 0; i < protocol::kMaxAxes; ++i)
    steps_[i] = config_.axes[i].max_step > 0 ? config_.axes[i].max_step : static_cast<float>(config_.max_motor_speed * period_s);
}

void Safety::configure(const protocol::InitPacket& init, const protocol::AxisMap& map) noexcept {
  const auto thresholds = map.per_open_axis(init.following_error);
  const auto limits = map.per_open_axis(init.current_limit);
  for (std::size_t i = 0; i < protocol::kMaxAxes; ++i) {
    thresholds_[i] = config_.following_error_override[i] > 0 ? config_.following_error_override[i] : thresholds[i];
    limits_[i] = config_.current_limit_override[i] > 0 ? config_.current_limit_override[i] : std::fabs(limits[i]);
  }
  set_steps(init.period_ms > 0 ? init.period_ms * 1e-3 : 0.002);
  configure_arms(init, map);
  have_last_ = {};
  // A new initialization packet: the peaks start again.
  fe_peak_local_ = {};
  for (auto& p : fe_peak_) p.store(0.0f, std::memory_order_relaxed);
}

void Safety::configure_arms(const protocol::InitPacket& init, const protocol::AxisMap& map) noexcept {
  arms_ = {};
  try {  // the transform's error path may allocate its message; a bad arm is then left unchecked
    for (std::size_t arm = 1; arm <= protocol::kMaxArms; ++arm) {
      if (map.arm_count(arm) == 0) continue;
      auto t = protocol::ArmTransform::from_init(init, arm);
      if (!t) continue;
      ArmCheck& a = arms_[arm - 1];
      a.axes = t.value().axes();
      for (std::size_t k = 0; k < a.axes; ++k) {
        const auto open = map.open_index(arm, k + 1);
        a.open[k] = open ? static_cast<int>(*open) : -1;
        a.q0[k] = t.value().calibration()[static_cast<Eigen::Index>(k)];
        for (std::size_t j = 0; j < a.axes; ++j)
          a.kr_inv[k][j] = t.value().kr_inverse()(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(j));
        a.min_rad[k] = config_.joints[arm - 1][k].min_deg * std::numbers::pi / 180.0;
        a.max_rad[k] = config_.joints[arm - 1][k].max_deg * std::numbers::pi / 180.0;
      }
    }
  } catch (...) {
  }
}

bool Safety::commanded_position(const protocol::Axis& req, const protocol::Axis& rep, float& out) noexcept {
  switch (req.mode) {
    case code(Mode::mode1):
    case code(Mode::mode1_standby):
    case code(Mode::mode4):
    case code(Mode::mode4_standby): out = rep.d1; return true;
    case code(Mode::mode5):
    case code(Mode::mode5_standby):
    case code(Mode::mode7):
    case code(Mode::mode7_standby): out = req.d1 + rep.d1; return true;
    default: return false;
  }
}

void Safety::latch(FaultReason r, int axis) noexcept {
  FaultReason expected = FaultReason::none;
  // The first fault wins: it is the cause, later ones are consequences.
  if (reason_.compare_exchange_strong(expected, r, std::memory_order_acq_rel)) {
    fault_axis_.store(axis, std::memory_order_relaxed);
    counters_.faults.fetch_add(1, std::memory_order_relaxed);
  }
}

void Safety::trip(FaultReason reason, int axis) noexcept { latch(reason, axis); }

void Safety::make_drive_off(const protocol::Packet& request, protocol::Packet& reply) noexcept {
  reply.count = request.count;
  reply.infpar = 0;
  reply.cmd = 0;
  for (std::size_t i = 0; i < reply.open_axes().size(); ++i) {
    reply.axes[i] = protocol::Axis{};
    reply.axes[i].mode = code(Mode::drive_off);
  }
}

void Safety::begin_cycle() noexcept {
  if (reset_requested_.exchange(false, std::memory_order_acq_rel)) {
    reason_.store(FaultReason::none, std::memory_order_release);
    fault_axis_.store(-1, std::memory_order_relaxed);
    drive_off_done_.store(false, std::memory_order_release);
    have_last_ = {};
  }
}

bool Safety::check_axis(std::size_t i, const protocol::Axis& q, protocol::Axis& r) noexcept {
  const int axis = static_cast<int>(i);
  checked_[i] = false;
  if (!finite(r)) return latch(FaultReason::not_finite, axis), false;
  if (config_.check_following_error && pc_checks_following(q.mode) &&
      protocol::following_error_exceeded(q.d1, q.d3, thresholds_[i]))
    return latch(FaultReason::following_error, axis), false;
  if (config_.saturate_current && pc_supplies_current(q.mode) && limits_[i] > 0) {
    const float c = protocol::saturate_current(r.d5, limits_[i]);
    if (c != r.d5) {
      r.d5 = c;
      counters_.currents_clamped.fetch_add(1, std::memory_order_relaxed);
    }
  }
  float pos = 0;
  const bool commands = commanded_position(q, r, pos);
  if (!commands) {
    have_last_[i] = false;  // continuity restarts when the axis next commands a position
    if (!pc_contributes(q.mode)) return true;
    pos = q.d3;  // the PC moves the robot without a target: hold its actual position
  }
  position_[i] = pos;
  checked_[i] = true;
  const AxisLimits& lim = config_.axes[i];
  if (config_.check_stroke_ends && !(pos >= lim.min_position && pos <= lim.max_position))
    return latch(FaultReason::stroke_end, axis), false;
  if (!commands) return true;
  // Continuity: from the last command, or (entering the mode, or an increment) the controller's target.
  const float from = have_last_[i] && !incremental(q.mode) ? last_position_[i] : q.d1;
  if (config_.check_continuity && !(std::fabs(pos - from) <= steps_[i]))
    return latch(FaultReason::discontinuity, axis), false;
  last_position_[i] = pos;
  have_last_[i] = true;
  return true;
}

bool Safety::check_joints(const protocol::Packet& request) noexcept {
  const auto req = request.open_axes();
  for (const ArmCheck& a : arms_) {
    bool any = false;
    for (std::size_t k = 0; k < a.axes; ++k) any = any || (a.open[k] >= 0 && checked_[static_cast<std::size_t>(a.open[k])]);
    if (!any) continue;
    // Motor turns of every axis of the arm: the checked position, else the controller's target.
    std::array<double, protocol::kAxesPerArm> m{};
    for (std::size_t k = 0; k < a.axes; ++k) {
      const int o = a.open[k];
      const auto u = static_cast<std::size_t>(o);
      m[k] = (o < 0 || u >= req.size() ? a.q0[k] : checked_[u] ? position_[u] : req[u].d1) - a.q0[k];
    }
    for (std::size_t k = 0; k < a.axes; ++k) {
      if (a.open[k] < 0 || !checked_[static_cast<std::size_t>(a.open[k])]) continue;
      double q = 0;
      for (std::size_t j = 0; j < a.axes; ++j) q += a.kr_inv[k][j] * m[j];
      q *= 2.0 * std::numbers::pi;
      if (!(q >= a.min_rad[k] && q <= a.max_rad[k])) return latch(FaultReason::stroke_end, a.open[k]), false;
    }
  }
  return true;
}

bool Safety::checks_following_error(std::int32_t mode) noexcept { return pc_checks_following(mode); }

void Safety::track_following_errors(std::span<const protocol::Axis> request) noexcept {
  for (std::size_t i = 0; i < request.size() && i < protocol::kMaxAxes; ++i) {
    const auto& q = request[i];
    const float e = std::fabs(q.d1 - q.d3);
    if (q.mode != fe_mode_[i]) {
      fe_mode_[i] = q.mode;
      fe_peak_local_[i] = 0.0f;
    }
    if (!(e <= fe_peak_local_[i])) fe_peak_local_[i] = e;  // a NaN sticks until the mode changes
    fe_now_[i].store(e, std::memory_order_relaxed);
    fe_peak_[i].store(fe_peak_local_[i], std::memory_order_relaxed);
  }
}

FaultReason Safety::apply(const protocol::Packet& request, protocol::Packet& reply) noexcept {
  begin_cycle();
  const auto req = request.open_axes();
  auto rep = reply.open_axes();
  track_following_errors(req);
  const std::size_t n = std::min(req.size(), rep.size());

  if (!faulted()) {
    bool ok = true;
    for (std::size_t i = 0; i < n && ok; ++i) ok = check_axis(i, req[i], rep[i]);
    for (std::size_t i = n; i < protocol::kMaxAxes; ++i) checked_[i] = false;
    if (ok && config_.check_stroke_ends) check_joints(request);
  }

  const FaultReason r = reason();
  if (r == FaultReason::none) return r;
  if (!drive_off_done_.load(std::memory_order_relaxed)) {
    // The controller has obeyed once every axis is back in mode 0 and no arm reports drives on.
    bool settled = true;
    for (std::size_t arm = 1; arm <= protocol::kMaxArms; ++arm)
      if (protocol::drives_on(request.infpar, arm)) settled = false;
    for (const auto& q : req)
      if (q.mode != code(Mode::mode0)) settled = false;
    drive_off_done_.store(settled, std::memory_order_release);
  }
  if (drive_off_done_.load(std::memory_order_relaxed)) return r;  // stop asking; the reply is the safe echo the Server built
  const int axis = fault_axis();
  if (r == FaultReason::following_error && axis >= 0 && static_cast<std::size_t>(axis) < n) {
    rep[static_cast<std::size_t>(axis)] = protocol::Axis{};
    rep[static_cast<std::size_t>(axis)].mode = code(Mode::following_error);
    counters_.following_error_replies.fetch_add(1, std::memory_order_relaxed);
  } else {
    make_drive_off(request, reply);
    counters_.drive_off_replies.fetch_add(1, std::memory_order_relaxed);
  }
  return r;
}

}  // namespace axon::c4g::host
