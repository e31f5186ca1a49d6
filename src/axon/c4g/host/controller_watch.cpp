#include "axon/c4g/host/controller_watch.hpp"

#include "axon/c4g/protocol/mode.hpp"

#include <fmt/format.h>

#include <cmath>

namespace axon::c4g::host {
namespace {

namespace P = protocol;

// Modes in which the axis belongs to the PC until an exit (their standby codes excluded).
bool is_open_base(std::int32_t m) {
  return m == 1 || m == 2 || m == 4 || m == 5 || m == 7 || m == 8 || m == 9 || (m > 100 && m < 200);
}
bool is_open(std::int32_t m) { return is_open_base(m) || P::base_of_standby(m).has_value(); }

}  // namespace

std::string_view manual_name(ControllerError e) noexcept {
  switch (e) {
    case ControllerError::none: return "none";
    case ControllerError::communication: return "ERR_C4GOPEN_UDP";
    case ControllerError::configuration_ax: return "ERR_C4GOPEN_CONFIGURATION_AX";
    case ControllerError::forced_mode0: return "ERR_C4GOPEN_SET_0_MODALITY";
    case ControllerError::drive_off_server: return "ERR_C4GOPEN_DRIVEOFF_SERVER";
    case ControllerError::follow_error: return "ERR_C4GOPEN_FOLLOW_ERROR";
    case ControllerError::controller_stop: return "controller safety stop";
    case ControllerError::position_jump: return "position jump";
    case ControllerError::override_scaled: return "override scaling";
  }
  return "?";
}

std::string_view meaning(ControllerError e) noexcept {
  switch (e) {
    case ControllerError::none: return "";
    case ControllerError::communication:
      return "packets stopped without the end of the exchange (504): 'C4GOpen: communication error' after 10 unanswered "
             "packets (the controller needs a restart), or the controller restarted";
    case ControllerError::configuration_ax:
      return "'C4GOpen: Arm %d Axis %d not present': a start-up open mode on an axis the open-axis lists leave out (the "
             "controller ignores it)";
    case ControllerError::forced_mode0:
      return "'C4GOpen: arm %d , forced 0 modality': an open mode ended in mode 0 without exit-from-open, drives on: the "
             "state selector moved between AUTO and PROG";
    case ControllerError::drive_off_server: return "'C4GOpen: Drive Off from Pc': the drives went off on this PC's 505";
    case ControllerError::follow_error:
      return "'C4GOpen: arm %s axis %d Following error out of range': raised on this PC's 508, drives off";
    case ControllerError::controller_stop:
      return "drives off in an open mode without a request from this PC: the controller's own checks (chapter 14.17.1: "
             "following error, the maximum offset of modes 7/8/9, current) or an emergency stop";
    case ControllerError::position_jump:
      return "the controller's target jumped in mode 0: an open mode left without its exit, pos_i not updated to pos_k "
             "(modes 5/7 warning; recovery: $C4G_PA := 1, C4GOPEN_MODE := 0, CSA, CCRC)";
    case ControllerError::override_scaled:
      return "mode 5's increments applied at less than 100 %: the machine's general override scales them (chapter 14.8)";
  }
  return "";
}

void ControllerWatch::record(ControllerError e, std::size_t arm, std::size_t axis) noexcept {
  counts_[static_cast<std::size_t>(e)].fetch_add(1, std::memory_order_relaxed);
  last_arm_.store(static_cast<int>(arm), std::memory_order_relaxed);
  last_axis_.store(static_cast<int>(axis), std::memory_order_relaxed);
  last_.store(e, std::memory_order_release);
}

void ControllerWatch::configure(const P::InitPacket& init, const P::AxisMap& map) noexcept {
  map_ = map;
  have_map_ = true;
  have_prev_ = false;
  exit_asked_ = {};
  pc_asked_ = {};
  for (std::size_t arm = 1; arm <= P::kMaxArms; ++arm)
    for (std::size_t axis = 1; axis <= P::kAxesPerArm; ++axis)
      if (init.modes[arm - 1][axis - 1] != 0 && !map.open_index(arm, axis)) record(ControllerError::configuration_ax, arm, axis);
}

void ControllerWatch::observe(const P::Packet& req, const P::Packet& reply) noexcept {
  if (have_prev_ && prev_.count == req.count) {
    for (std::size_t arm = 1; arm <= P::kMaxArms; ++arm)
      if (P::exit_from_open(prev_reply_.infpar, arm)) exit_asked_[arm] = true;
    for (std::size_t i = 0; i < prev_reply_.count; ++i) {
      const std::int32_t asked = prev_reply_.axes[i].mode;
      if (asked == P::code(P::Mode::drive_off) || asked == P::code(P::Mode::following_error))
        pc_asked_[have_map_ ? map_.logical(i).arm : 1] = asked;
    }
    reported_ = {};
    bool five_before = false, five_now = false;
    for (std::size_t i = 0; i < req.count; ++i) {
      watch_axis(i, req);
      watch_mode5(i, req);
      five_before |= prev_.axes[i].mode == 5;
      five_now |= req.axes[i].mode == 5;
    }
    if (five_before && !five_now && sent5_ > 1e-4) {
      const double percent = 100.0 * applied5_ / sent5_;
      applied_percent_.store(percent, std::memory_order_relaxed);
      if (percent < 100.0 * (1.0 - options_.override_tolerance)) record(ControllerError::override_scaled, 1, 0);
      sent5_ = applied5_ = 0;
    }
  }
  prev_ = req;
  prev_reply_ = reply;
  have_prev_ = true;
}

void ControllerWatch::watch_axis(std::size_t i, const P::Packet& req) noexcept {
  const std::size_t arm = have_map_ ? map_.logical(i).arm : 1;
  const std::size_t axis = have_map_ ? map_.logical(i).axis : i + 1;
  if (arm < 1 || arm > P::kMaxArms) return;
  const std::int32_t pm = prev_.axes[i].mode, m = req.axes[i].mode;
  const bool on_before = P::arm_byte(prev_.infpar, arm) == P::kDrivesOn, on_now = P::arm_byte(req.infpar, arm) == P::kDrivesOn;
  auto once = [&](ControllerError e) {
    if (reported_[arm]) return;
    reported_[arm] = true;
    record(e, arm, axis);
  };
  if (is_open_base(m) && !is_open(pm)) exit_asked_[arm] = false;  // the arm's open mode begins
  if (m == 0 && pm == 0) pc_asked_[arm] = 0;
  if (m != pm && m == P::code(P::Mode::drive_off) && pc_asked_[arm] == m) once(ControllerError::drive_off_server);
  else if (m != pm && m == P::code(P::Mode::following_error) && pc_asked_[arm] == m) once(ControllerError::follow_error);
  else if (on_before && !on_now && pc_asked_[arm] == 0 && is_open(pm)) once(ControllerError::controller_stop);
  else if (m == 0 && is_open_base(pm) && on_now && !exit_asked_[arm]) once(ControllerError::forced_mode0);
  if (m == 0 && pm != P::code(P::Mode::driving_on) && on_before && on_now) {
    const float jump = std::fabs(req.axes[i].d1 - prev_.axes[i].d1);
    if (jump > options_.jump_turns) {
      if (jump > jump_.load(std::memory_order_relaxed)) jump_.store(jump, std::memory_order_relaxed);
      counts_[static_cast<std::size_t>(ControllerError::position_jump)].fetch_add(1, std::memory_order_relaxed);
      last_arm_.store(static_cast<int>(arm), std::memory_order_relaxed);
      last_axis_.store(static_cast<int>(axis), std::memory_order_relaxed);
      last_.store(ControllerError::position_jump, std::memory_order_release);
    }
  }
}

// Mode 5: the reply to packet k carries the PC's increment D2; packet k+1 shows the controller's target
// D1 moved by what it applied (the program moves nothing in mode 5).
void ControllerWatch::watch_mode5(std::size_t i, const P::Packet& req) noexcept {
  if (prev_.axes[i].mode != 5 || req.axes[i].mode != 5) return;
  const double sent = std::fabs(prev_reply_.axes[i].d2);
  if (sent < 1e-7) return;
  sent5_ += sent;
  applied5_ += std::fabs(static_cast<double>(req.axes[i].d1) - static_cast<double>(prev_.axes[i].d1));
}

void ControllerWatch::on_silence() noexcept {
  if (have_prev_) {
    bool ended = false;
    for (std::size_t i = 0; i < prev_.count; ++i) ended |= prev_.axes[i].mode == P::code(P::Mode::exit_open);
    if (!ended) record(ControllerError::communication, 0, 0);
  }
  have_prev_ = false;
}

std::string ControllerWatch::summary() const {
  std::string out;
  for (std::size_t k = 1; k < kControllerErrorCount; ++k) {
    const auto e = static_cast<ControllerError>(k);
    if (count(e) == 0) continue;
    out += fmt::format("Controller error: {} x{}{}{}: {}\n", manual_name(e), count(e),
                       e == ControllerError::override_scaled ? fmt::format(" ({:.1f} % applied)", applied_percent()) : "",
                       e == ControllerError::position_jump ? fmt::format(" (largest {:.3f} motor turns)", jump_turns()) : "",
                       meaning(e));
  }
  return out.empty() ? "Controller errors: none seen\n" : out;
}

std::string ControllerWatch::names() const {
  std::string out;
  for (std::size_t k = 1; k < kControllerErrorCount; ++k) {
    const auto e = static_cast<ControllerError>(k);
    if (count(e) > 0) out += fmt::format("{}{} x{}", out.empty() ? "" : ", ", manual_name(e), count(e));
  }
  return out.empty() ? "none" : out;
}

}  // namespace axon::c4g::host
