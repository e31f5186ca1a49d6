#include "axon/blmc/host/safety.hpp"

#include "axon/blmc/host/error.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace axon::blmc::host {

const char* to_string(FaultKind k) noexcept {
  switch (k) {
    case FaultKind::none: return "none";
    case FaultKind::board_error: return "board error";
    case FaultKind::undocumented_error: return "undocumented board error";
    case FaultKind::board_disabled: return "board disabled";
    case FaultKind::stale_data: return "stale data";
    case FaultKind::position_limit: return "position limit";
    case FaultKind::bad_command: return "bad command";
  }
  return "?";
}

std::string Fault::describe() const {
  const bool host_side =
      kind != FaultKind::board_error && kind != FaultKind::undocumented_error && kind != FaultKind::none;
  if (host_side && board_error != protocol::ErrorCode::none)
    return fmt::format("{} (board error {})", without_board_error().describe(), protocol::name(board_error));
  if (host_side && undocumented_code != 0)
    return fmt::format("{} (board sent undocumented error code {})", without_board_error().describe(),
                       unsigned{undocumented_code});
  switch (kind) {
    case FaultKind::none: return "no fault";
    case FaultKind::board_error: return fmt::format("board error {}", protocol::name(board_error));
    case FaultKind::undocumented_error:
      return fmt::format("board sent undocumented error code {}", unsigned{undocumented_code});
    case FaultKind::board_disabled:
      return motor < 0 ? std::string("board reports the system disabled")
                       : fmt::format("board reports motor {} disabled", motor + 1);
    case FaultKind::stale_data:
      return fmt::format("stale data: no {} frame for {:.3f} s (limit {:.3f} s)", to_string(quantity), value, limit);
    case FaultKind::position_limit:
      return fmt::format("motor {} position {:.4f} rev outside its limit (crossed {:.4f} rev)", motor + 1, value,
                         limit);
    case FaultKind::bad_command: return fmt::format("controller asked motor {} for a non-finite current", motor + 1);
  }
  return "?";
}

Result<void> SafetyLimits::validate() const {
  auto bad = [](std::string text) { return Error(HostErrc::invalid_argument, "safety limits: " + std::move(text)); };
  if (!std::isfinite(max_current_a) || max_current_a <= 0)
    return bad(fmt::format("max current must be > 0 A, got {}", max_current_a));
  if (!std::isfinite(max_velocity_krpm) || max_velocity_krpm <= 0)
    return bad(fmt::format("max velocity must be > 0 krpm, got {}", max_velocity_krpm));
  if (stale_after <= core::Duration::zero() || status_stale_after <= core::Duration::zero())
    return bad("stale limits must be > 0");
  for (std::size_t i = 0; i < position.size(); ++i) {
    const auto& p = position[i];
    if (p.enabled && !(std::isfinite(p.min_rev) && std::isfinite(p.max_rev) && p.min_rev < p.max_rev))
      return bad(fmt::format("motor {} position limit needs min < max, got {} .. {}", i + 1, p.min_rev, p.max_rev));
  }
  return ok();
}

void Safety::arm(core::TimePoint now) noexcept { armed_ = now; }

void Safety::reset(core::TimePoint now) noexcept {
  fault_ = {};
  newly_ = false;
  arm(now);
}

Fault Safety::check(const Measurements& m, core::TimePoint now) const noexcept {
  Fault f;
  f.at = now;
  if (m.undocumented_error()) {
    f.kind = FaultKind::undocumented_error;
    f.undocumented_code = protocol::error_bits(m.status_byte.value);
    return f;
  }
  const auto& st = m.status;
  if (st.received() && st.value.error != protocol::ErrorCode::none) {
    f.kind = FaultKind::board_error;
    f.board_error = st.value.error;
    return f;
  }
  if (st.received()) {
    if (!st.value.system_enabled) {
      f.kind = FaultKind::board_disabled;
      return f;
    }
    const bool en[2] = {st.value.motor1_enabled, st.value.motor2_enabled};
    for (int i = 0; i < 2; ++i) {
      if (limits_.motors[static_cast<std::size_t>(i)] && !en[i]) {
        f.kind = FaultKind::board_disabled;
        f.motor = i;
        return f;
      }
    }
  }
  // Stale data: measured from the later of arm() and the last frame.
  auto stale = [&](Quantity q, core::Duration limit) {
    const core::TimePoint since = m.count(q) > 0 ? std::max(m.last(q), armed_) : armed_;
    if (now - since <= limit) return false;
    f.kind = FaultKind::stale_data;
    f.quantity = q;
    f.value = std::chrono::duration<double>(now - since).count();
    f.limit = std::chrono::duration<double>(limit).count();
    return true;
  };
  if (stale(Quantity::current, limits_.stale_after) || stale(Quantity::position, limits_.stale_after) ||
      stale(Quantity::velocity, limits_.stale_after) ||
      (limits_.check_adc && stale(Quantity::adc, limits_.stale_after)) ||
      stale(Quantity::status, limits_.status_stale_after)) {
    return f;
  }
  const double pos[2] = {m.position.value.motor1, m.position.value.motor2};
  for (std::size_t i = 0; i < 2; ++i) {
    const auto& lim = limits_.position[i];
    if (!limits_.motors[i] || !lim.enabled || !m.position.received()) continue;
    if (pos[i] < lim.min_rev || pos[i] > lim.max_rev) {
      f.kind = FaultKind::position_limit;
      f.motor = static_cast<int>(i);
      f.value = pos[i];
      f.limit = pos[i] < lim.min_rev ? lim.min_rev : lim.max_rev;
      return f;
    }
  }
  return f;
}

MotorPair Safety::apply(const Measurements& m, MotorPair requested, core::TimePoint now) noexcept {
  ++counters_.cycles;
  newly_ = false;
  if (tripped()) return {};
  Fault f = check(m, now);
  double req[2] = {requested.motor1, requested.motor2};
  if (f.kind == FaultKind::none) {
    for (int i = 0; i < 2; ++i) {
      if (limits_.motors[static_cast<std::size_t>(i)] && !std::isfinite(req[i])) {
        f.kind = FaultKind::bad_command;
        f.motor = i;
        break;
      }
    }
  }
  if (f.kind != FaultKind::none) {
    fault_ = f;
    newly_ = true;
    return {};
  }
  const double vel[2] = {m.velocity.value.motor1, m.velocity.value.motor2};
  for (std::size_t i = 0; i < 2; ++i) {
    if (!limits_.motors[i]) {
      req[i] = 0.0;
      continue;
    }
    if (std::abs(vel[i]) > limits_.max_velocity_krpm) {
      req[i] = 0.0;
      ++counters_.velocity_limited;
      continue;
    }
    const double c = std::clamp(req[i], -limits_.max_current_a, limits_.max_current_a);
    if (c != req[i]) ++counters_.clamped;
    req[i] = c;
  }
  return {req[0], req[1]};
}

}  // namespace axon::blmc::host
