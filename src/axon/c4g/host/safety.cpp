#include "axon/c4g/host/safety.hpp"

#include "axon/c4g/protocol/mode.hpp"
#include "axon/c4g/protocol/safety.hpp"

#include <cmath>

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

bool finite(const protocol::Axis& a) noexcept {
  return std::isfinite(a.d1) && std::isfinite(a.d2) && std::isfinite(a.d3) && std::isfinite(a.d4) &&
         std::isfinite(a.d5) && std::isfinite(a.ext1) && std::isfinite(a.ext2) && std::isfinite(a.ext3);
}

}  // namespace

Safety::Safety(const SafetyConfig& config) : config_(config) {
  thresholds_ = config.following_error_override;
  limits_ = config.current_limit_override;
}

void Safety::configure(const protocol::InitPacket& init, const protocol::AxisMap& map) noexcept {
  const auto thresholds = map.per_open_axis(init.following_error);
  const auto limits = map.per_open_axis(init.current_limit);
  for (std::size_t i = 0; i < protocol::kMaxAxes; ++i) {
    thresholds_[i] = config_.following_error_override[i] > 0 ? config_.following_error_override[i] : thresholds[i];
    limits_[i] = config_.current_limit_override[i] > 0 ? config_.current_limit_override[i] : std::fabs(limits[i]);
  }
  have_last_ = {};
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
    drive_off_done_ = false;
    have_last_ = {};
  }
}

FaultReason Safety::apply(const protocol::Packet& request, protocol::Packet& reply) noexcept {
  begin_cycle();
  const auto req = request.open_axes();
  auto rep = reply.open_axes();
  const std::size_t n = std::min(req.size(), rep.size());

  if (!faulted()) {
    for (std::size_t i = 0; i < n && !faulted(); ++i) {
      const auto& q = req[i];
      auto& r = rep[i];
      const int axis = static_cast<int>(i);
      if (!finite(r)) {
        latch(FaultReason::not_finite, axis);
        break;
      }
      if (config_.check_following_error && pc_closes_loops(q.mode) &&
          protocol::following_error_exceeded(q.d1, q.d3, thresholds_[i])) {
        latch(FaultReason::following_error, axis);
        break;
      }
      if (config_.saturate_current && pc_supplies_current(q.mode) && limits_[i] > 0) {
        const float c = protocol::saturate_current(r.d5, limits_[i]);
        if (c != r.d5) {
          r.d5 = c;
          counters_.currents_clamped.fetch_add(1, std::memory_order_relaxed);
        }
      }
      float pos = 0;
      if (commanded_position(q, r, pos)) {
        const AxisLimits& lim = config_.axes[i];
        if (!(pos >= lim.min_position && pos <= lim.max_position)) {
          latch(FaultReason::stroke_end, axis);
          break;
        }
        if (lim.max_step > 0 && have_last_[i] && !(std::fabs(pos - last_position_[i]) <= lim.max_step)) {
          latch(FaultReason::discontinuity, axis);
          break;
        }
        last_position_[i] = pos;
        have_last_[i] = true;
      } else {
        have_last_[i] = false;  // continuity restarts when the axis next commands a position
      }
    }
  }

  const FaultReason r = reason();
  if (r == FaultReason::none) return r;
  if (!drive_off_done_) {
    // The controller has obeyed once every axis is back in mode 0 and no arm reports drives on.
    bool settled = true;
    for (std::size_t arm = 1; arm <= protocol::kMaxArms; ++arm)
      if (protocol::drives_on(request.infpar, arm)) settled = false;
    for (const auto& q : req)
      if (q.mode != code(Mode::mode0)) settled = false;
    drive_off_done_ = settled;
  }
  if (drive_off_done_) return r;  // stop asking; the reply is the safe echo the Server built
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
