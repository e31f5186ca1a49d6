// The board's own controller and switches that act without the host in the loop (spec 002): the
// optional P/D controller (messages KP 0x006, KD 0x007, POS_REF 0x008, VEL_REF 0x009 and its
// current limits, commands 0x28..0x2B), the position rollover error (0x1F) and the virtual springs
// (0x04, 0x05). Plain values, their checks and the frames that carry them; pure (no I/O).
// Board (board.hpp) and MotorBoard (motor_board.hpp) send them.
//
// The controller is documented but absent from the firmware in service (FIELD-NOTES): a board
// without it ignores these frames. As documented and as the simulator models it, every cycle an
// enabled, ready motor is driven with
//     Iq = IqRef + clamp(KP (POS_REF - position), +-P limit) + clamp(KD (VEL_REF - velocity), +-D limit)
// The limits default to 0, so nothing happens until they are set. The host's Safety clamps only
// the IqRef it sends, not these terms: the limits are the on-board controller's own bound.
//
// Units are the spec's: gains in A per motor revolution (KP) and A per krpm (KD, krpm = 1000 rev/
// min), references in motor revolutions and krpm, limits in amperes. Every value must be finite and
// fit Q24 (-128 .. 128); gains and limits must be >= 0 (a negative gain pushes away from the
// reference, a negative limit has no meaning).
//
// Positions. The controller compares POS_REF with the board's own counter, which covers
// [-100, 100) rev and rolls over; the host's positions are unwrapped (measurements.hpp). A position
// reference is given in the host's positions and sent as the counter reading of the same place on
// the counter's current turn; one outside that turn (e.g. 100.5 rev while the counter reads 99.8)
// is refused, since the board cannot hold it. A motor that crosses the rollover under the on-board
// controller sees a 200 rev error (bounded by the P limit): enable the rollover error to have the
// board stop itself there.
#pragma once

#include "axon/blmc/host/measurements.hpp"
#include "axon/can/frame.hpp"
#include "axon/core/error.hpp"

#include <array>
#include <vector>

namespace axon::blmc::host {

struct OnboardGains {
  MotorPair kp_a_per_rev;   // KP (0x006)
  MotorPair kd_a_per_krpm;  // KD (0x007)
};

struct OnboardReferences {
  MotorPair position_rev;   // POS_REF (0x008), in the host's (unwrapped) motor revolutions
  MotorPair velocity_krpm;  // VEL_REF (0x009)
};

struct OnboardCurrentLimits {
  MotorPair p_a;  // CAN_CMD_P_CONTROLLER_LIMIT_IQ_MTR1/2 (0x28, 0x29): bound of the P term
  MotorPair d_a;  // CAN_CMD_D_CONTROLLER_LIMIT_IQ_MTR1/2 (0x2A, 0x2B): bound of the D term
};

// The frames for each setting, in the order they go out, or HostErrc::invalid_argument naming the
// motor, the quantity, its unit and the value. `unwrap` is the board's Measurements::unwrap (where
// the counter's current turn lies).
Result<std::vector<can::Frame>> onboard_frames(const OnboardGains& gains);
Result<std::vector<can::Frame>> onboard_frames(const OnboardReferences& refs, const PositionUnwrap& unwrap);
Result<std::vector<can::Frame>> onboard_frames(const OnboardCurrentLimits& limits);
// ENABLE_POS_ROLLOVER_ERROR=0/1: with 1 the board raises POS_ROLLOVER (and disables itself) when a
// position reading rolls over at +-100 rev.
can::Frame rollover_error_frame(bool on);
// ENABLE_VSPRING1/2: a spring towards the position at the moment it is switched on replaces the
// motor's IqRef (index 0 = motor 1).
std::vector<can::Frame> virtual_spring_frames(std::array<bool, 2> on);
// What a host that used the settings above sends on its way out, after the usual disable: both
// controller limits 0 on both motors and both springs off, so that a later enable does not chase
// an old reference or spring anchor.
std::vector<can::Frame> onboard_reset_frames();

}  // namespace axon::blmc::host
