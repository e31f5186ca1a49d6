// A simulated blmc motor driver board: the firmware of one board with its two motors, as a pure
// state machine driven by the time the caller passes in (no threads, no clock, no I/O).
//
// API in brief (namespace axon::blmc::sim):
//   Board board(BoardConfig{}, BoardFaultPlan{});      // power-up at board time 0; throws
//                                                      // axon::Exception for an invalid config/plan
//   board.receive(frame, now);       // a frame from the bus at board time `now`; a malformed frame
//                                    // is counted (stats().malformed) and its error returned
//   board.advance(now, out);         // runs every 1 ms firmware cycle up to `now`, appending the
//                                    // frames the board sends to `out` (a std::vector<can::Frame>)
//   board.status();                  // what the next status frame will say
//   board.motor(0|1);                // the MotorModel (physics, encoder) of motor 1 | 2
//   board.inject(FaultKind::encoder);// a fault raised at the next cycle (programmatic fault plan)
//   board.power_cycle();             // back to power-up state (alignment runs again)
//   board.stats();                   // counters (frames in/out, malformed, faults applied ...)
// Runner (runner.hpp) serves boards on can::Bus endpoints at 1 kHz.
//
// Firmware behaviour (spec 002 and the field notes):
// - Cycle k runs at board time k ms: it applies the frames received up to then, raises due
//   faults, checks the receive timeout, sends what is due and then integrates the motors over the
//   next millisecond. Frames therefore take effect at the first cycle at or after their arrival.
// - Status (0x010) every second (cycle 0, 1000, 2000 ...), whatever the state. Current,
//   position, velocity and ADC (0x020..0x050) every cycle, in that order, each when its SEND_ flag
//   is set and the system is enabled (BoardConfig::data_while_disabled lifts the second condition).
//   Encoder index frames (0x060) when SEND_ENC_INDEX is set (SEND_ALL sets it too), in the cycle
//   after the mark passed.
// - A motor is driven when the system and the motor are enabled. Its first enable after power-up
//   runs the alignment (BoardConfig::alignment_time): the rotor is held, IqRef is ignored, then the
//   motor reports ready and follows IqRef (+ the optional PD terms) for good. Disabling a motor
//   during alignment aborts it; it starts over at the next enable.
// - Receive timeout (SET_CAN_RECV_TIMEOUT, ms, 0 = off): only IqRef frames reset it; it is checked
//   while the system is on and an enabled motor has a non-zero IqRef; more than the timeout since
//   the last IqRef raises CAN_RECV_TIMEOUT.
// - Errors latch; any error disables the system and both motors. With several, the status reports
//   encoder > transmit (as OTHER) > receive timeout > position converter > rollover, an
//   over-current trip (no code of its own) as OTHER below all of those, and last an undocumented
//   error (FaultKind::undocumented, a fault hook for hosts) as the code 6 the spec leaves undefined.
// - Recovery: ENABLE_SYS=1 clears the latched errors whose cause is gone (a fault plan event with a
//   duration or marked persistent keeps its cause) and enables the system, unless one remains.
//   Then IqRef=0 and ENABLE_MTRx=1, as the spec says (a stale non-zero IqRef would time out again).
// - Optional on-board PD controller (KP, KD, POS_REF, VEL_REF, commands 0x28..0x2B), documented but
//   absent from the firmware in service: Iq = IqRef + clamp(KP (POS_REF - pos), +-P limit)
//   + clamp(KD (VEL_REF - vel), +-D limit), positions in motor revolutions, velocities in krpm. The
//   limits default to 0, so the PD terms contribute nothing until the host sets limits.
// - Virtual spring (ENABLE_VSPRINGx=1): IqRef is replaced by a spring towards the position at the
//   moment of enabling it (BoardConfig::vspring_gain_a_per_rev).
// - ENABLE_POS_ROLLOVER_ERROR=1: a position reading wrapping at +-100 rev raises POS_ROLLOVER.
#pragma once

#include "axon/blmc/protocol/frames.hpp"
#include "axon/blmc/protocol/status.hpp"
#include "axon/blmc/sim/board_config.hpp"
#include "axon/blmc/sim/fault_plan.hpp"
#include "axon/blmc/sim/motor_model.hpp"
#include "axon/can/frame.hpp"
#include "axon/core/clock.hpp"

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <limits>
#include <random>
#include <vector>

namespace axon::blmc::sim {

// Board time: the duration since the board was created (power-up).
using BoardTime = core::Duration;
inline constexpr core::Duration kCycle = std::chrono::milliseconds(1);

struct BoardStats {
  std::uint64_t frames_received = 0;  // frames handed to receive()
  std::uint64_t commands = 0;         // command frames applied
  std::uint64_t iq_refs = 0;          // IqRef frames applied
  std::uint64_t controller_frames = 0;  // KP, KD, POS_REF, VEL_REF frames applied
  std::uint64_t malformed = 0;        // frames with a blmc host id that do not decode
  std::uint64_t ignored = 0;          // extended/remote frames and ids not addressed to a board
  std::uint64_t rx_overflow = 0;      // lost because the firmware's receive queue was full
  std::uint64_t rx_stalled = 0;       // fault plan: lost in a stall window
  std::uint64_t rx_dropped = 0;       // fault plan: lost at random
  std::uint64_t frames_sent = 0;      // frames appended to advance()'s output
  std::uint64_t tx_stalled = 0;       // fault plan: not sent in a stall window
  std::uint64_t tx_dropped = 0;       // fault plan: not sent at random
  std::uint64_t data_skipped = 0;     // data frames of cycles too far behind advance()'s `now`
  std::uint64_t index_frames = 0;     // encoder index frames sent
  std::uint64_t errors_raised = 0;    // faults latched (counting each kind once per latch)
  std::uint64_t recoveries_refused = 0;  // ENABLE_SYS=1 while a fault's cause remained
  std::uint64_t encode_errors = 0;    // a reading that did not fit Q24 (not sent)
};

// What the firmware holds for one motor.
struct MotorState {
  bool enabled = false;
  bool ready = false;        // alignment done (until power-cycled)
  bool aligning = false;
  BoardTime alignment_start{0};
  bool vspring = false;
  double vspring_anchor_rev = 0;
  double iq_ref_a = 0;       // the last IqRef received
  double kp = 0, kd = 0;     // A/rev, A/krpm
  double pos_ref_rev = 0, vel_ref_krpm = 0;
  double p_limit_a = 0, d_limit_a = 0;
  double command_a = 0;      // what the firmware asked the driver for in the last cycle
};

// The firmware's switches.
struct FirmwareSettings {
  bool system_enabled = false;
  bool send_current = false, send_position = false, send_velocity = false, send_adc = false, send_enc_index = false;
  std::uint32_t recv_timeout_ms = 0;
  bool rollover_error = false;
};

class Board {
 public:
  explicit Board(BoardConfig config = {}, BoardFaultPlan faults = {});

  // A frame from the bus arriving at `now` (applied at the first cycle at or after `now`).
  // Malformed frames (a host id with a bad length, command or value) are counted in
  // stats().malformed, frames of other devices in stats().ignored; both return the decode error.
  Result<void> receive(const can::Frame& frame, BoardTime now);
  // Runs the firmware cycles due up to `now` and appends what the board sends to `out`. With
  // max_data_cycles, only the data frames of that many latest cycles are sent (a runner that fell
  // behind does not flush a burst no real board would send); status and index frames always are.
  void advance(BoardTime now, std::vector<can::Frame>& out,
               std::size_t max_data_cycles = std::numeric_limits<std::size_t>::max());

  // A fault raised at the next cycle, like a fault plan event (duration/persistent as there).
  void inject(FaultKind kind, core::Duration duration = core::Duration::zero(), bool persistent = false);
  // Power off and on: firmware state and motors back to power-up (alignment runs again, faults
  // and their causes are gone, the encoders read their initial positions). Time goes on.
  void power_cycle();

  // What the next status frame will say. An undocumented error (FaultKind::undocumented) shows
  // only in status_byte(), as error code 6, which a protocol::Status cannot hold.
  [[nodiscard]] protocol::Status status() const noexcept;
  [[nodiscard]] std::uint8_t status_byte() const noexcept;
  [[nodiscard]] const protocol::FaultSet& faults() const noexcept { return faults_; }
  [[nodiscard]] bool over_current_latched() const noexcept { return over_current_; }
  [[nodiscard]] const FirmwareSettings& settings() const noexcept { return settings_; }
  [[nodiscard]] const MotorState& motor_state(std::size_t i) const { return state_.at(i); }
  [[nodiscard]] const MotorModel& motor(std::size_t i) const { return motors_.at(i); }
  [[nodiscard]] MotorModel& motor(std::size_t i) { return motors_.at(i); }
  [[nodiscard]] const BoardConfig& config() const noexcept { return config_; }
  // Time of the next cycle to run.
  [[nodiscard]] BoardTime next_cycle_time() const noexcept { return kCycle * static_cast<std::int64_t>(next_cycle_); }
  [[nodiscard]] const BoardStats& stats() const noexcept { return stats_; }

 private:
  struct Pending {
    BoardTime at;
    protocol::ToBoard msg;
  };
  void run_cycle(std::uint64_t k, bool send_data, std::vector<can::Frame>& out);
  void apply(const protocol::ToBoard& msg, BoardTime at);
  void apply_command(const protocol::Command& cmd, BoardTime at);
  void raise(FaultKind kind, core::Duration duration, bool persistent, BoardTime at);
  void latch(bool& flag);
  void disable_all() noexcept;
  [[nodiscard]] bool any_fault() const noexcept;
  [[nodiscard]] double motor_command(std::size_t i, BoardTime t);
  void emit(const Result<can::Frame>& frame, BoardTime t, std::vector<can::Frame>& out);
  [[nodiscard]] bool link_lost(LinkDirection dir, BoardTime t);
  void reset_firmware();

  BoardConfig config_;
  BoardFaultPlan plan_;
  std::mt19937_64 rng_;
  std::size_t next_event_ = 0;  // plan_.events sorted by time
  std::vector<FaultEvent> injected_;
  std::array<MotorModel, 2> motors_;
  std::array<MotorState, 2> state_{};
  FirmwareSettings settings_{};
  protocol::FaultSet faults_{};
  bool over_current_ = false;
  bool undocumented_ = false;
  // When the cause of each FaultKind ends (zero: none; max: until power-cycled).
  std::array<BoardTime, 5> cause_until_{};
  BoardTime last_iq_ref_{0};
  std::uint64_t next_cycle_ = 0;
  std::deque<Pending> pending_;
  BoardStats stats_;
};

}  // namespace axon::blmc::sim
