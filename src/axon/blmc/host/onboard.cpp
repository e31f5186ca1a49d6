#include "axon/blmc/host/onboard.hpp"

#include "axon/blmc/host/error.hpp"
#include "axon/blmc/protocol/command.hpp"
#include "axon/blmc/protocol/frames.hpp"
#include "axon/blmc/protocol/q24.hpp"

#include <fmt/format.h>

#include <cmath>

namespace axon::blmc::host {

namespace {

using protocol::CommandCode;
using protocol::MessageId;

Error refuse(std::string text) { return Error(HostErrc::invalid_argument, "on-board controller: " + std::move(text)); }

// Each motor's value finite, within Q24 and, for gains and limits, not negative.
Result<void> check(const MotorPair& v, const char* what, const char* unit, bool non_negative) {
  const double x[2] = {v.motor1, v.motor2};
  const double low = non_negative ? 0.0 : protocol::kQ24Min;
  for (int i = 0; i < 2; ++i) {
    if (!(std::isfinite(x[i]) && x[i] >= low && x[i] <= protocol::kQ24Max))
      return refuse(fmt::format("motor {} {} must be a finite number within {} .. 128 {}, got {}", i + 1, what, low,
                                unit, x[i]));
  }
  return ok();
}

// The value was checked: encoding cannot fail.
can::Frame pair(MessageId id, const MotorPair& v) { return protocol::encode(protocol::PairMessage{id, v}).value(); }
can::Frame flag(CommandCode code, bool on) { return protocol::encode(protocol::Command::flag(code, on).value()).value(); }
can::Frame limit(CommandCode code, double amperes) {
  return protocol::encode(protocol::Command::current_limit(code, amperes).value()).value();
}

// The counter reading of the host position `rev` on the counter's current turn.
Result<double> counter_position(const PositionUnwrap& unwrap, std::size_t motor, double rev) {
  if (!std::isfinite(rev)) return refuse(fmt::format("motor {} position reference must be finite, got {}", motor + 1, rev));
  const double offset = unwrap.offset_rev(motor);
  const double raw = rev - offset;
  if (!(raw >= -protocol::kPositionRolloverRev && raw < protocol::kPositionRolloverRev))
    return refuse(fmt::format("motor {} position reference {} rev lies outside {} .. {} rev, the span of the board's "
                              "position counter on the motor's current turn",
                              motor + 1, rev, offset - protocol::kPositionRolloverRev,
                              offset + protocol::kPositionRolloverRev));
  return raw;
}

}  // namespace

Result<std::vector<can::Frame>> onboard_frames(const OnboardGains& gains) {
  AXON_TRY(check(gains.kp_a_per_rev, "KP", "A/rev", true));
  AXON_TRY(check(gains.kd_a_per_krpm, "KD", "A/krpm", true));
  return std::vector<can::Frame>{pair(MessageId::kp, gains.kp_a_per_rev), pair(MessageId::kd, gains.kd_a_per_krpm)};
}

Result<std::vector<can::Frame>> onboard_frames(const OnboardReferences& refs, const PositionUnwrap& unwrap) {
  AXON_TRY(check(refs.velocity_krpm, "velocity reference", "krpm", false));
  AXON_TRY(p1, counter_position(unwrap, 0, refs.position_rev.motor1));
  AXON_TRY(p2, counter_position(unwrap, 1, refs.position_rev.motor2));
  return std::vector<can::Frame>{pair(MessageId::pos_ref, {p1, p2}), pair(MessageId::vel_ref, refs.velocity_krpm)};
}

Result<std::vector<can::Frame>> onboard_frames(const OnboardCurrentLimits& limits) {
  AXON_TRY(check(limits.p_a, "P current limit", "A", true));
  AXON_TRY(check(limits.d_a, "D current limit", "A", true));
  return std::vector<can::Frame>{limit(CommandCode::p_controller_limit_iq_mtr1, limits.p_a.motor1),
                                 limit(CommandCode::p_controller_limit_iq_mtr2, limits.p_a.motor2),
                                 limit(CommandCode::d_controller_limit_iq_mtr1, limits.d_a.motor1),
                                 limit(CommandCode::d_controller_limit_iq_mtr2, limits.d_a.motor2)};
}

can::Frame rollover_error_frame(bool on) { return flag(CommandCode::enable_pos_rollover_error, on); }

std::vector<can::Frame> virtual_spring_frames(std::array<bool, 2> on) {
  return {flag(CommandCode::enable_vspring1, on[0]), flag(CommandCode::enable_vspring2, on[1])};
}

std::vector<can::Frame> onboard_reset_frames() {
  auto frames = onboard_frames(OnboardCurrentLimits{}).value();
  for (const auto& f : virtual_spring_frames({false, false})) frames.push_back(f);
  return frames;
}

}  // namespace axon::blmc::host
