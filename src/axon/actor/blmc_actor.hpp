// BlmcActor: one motor driver board (two motors) as an actor (docs/actor.md, keywords in
// docs/schema/blmc.json). It adds the blmc verbs to an ActorCore and drives an open
// blmc::MotorBoard through the library's front end / back end split (blmc/host/front_end.hpp):
//
//   status                       board flags, the error code and its meaning, per motor enabled,
//                                ready, current, position, velocity; the loop, the action in force,
//                                the limits, the last run's report, the command counters
//   enable | disable             motors on (aligned, ready) | loop stopped, zero current, motors off
//   start [--max-current A] [--max-velocity KRPM]
//                                the 1 kHz loop with a FrontEnd, idle (zero current) until told
//   stop                         ends the loop (its report); the motors stay enabled at zero current
//   currents A1 A2               both motors' currents, amperes
//   current MOTOR A              one motor's current (1 or 2); the other keeps its action
//   pd P1 P2 [KP KD]             PD to positions P1, P2 (motor rev), gains A/rev and A/(rev/s)
//   idle                         the idle action (zero current on both motors), the loop runs on
//   home [SPEED_REV_S]           homing on the encoder index (MotorBoard::home), no loop running
//   errors                       the board's error code, the faults seen since start-up
//   recover                      the board's recovery after an error (MotorBoard::recover)
//
// The actor is the front end: the action a commander set stays in force, and the actor's watcher
// thread hands it to the loop again every watch period so that it never goes stale while the actor
// is alive (FrontEndOptions::stale_after is then the guard against the actor's own threads
// stalling: the loop falls back to zero current). The 1 kHz loop stays on the library's real-time
// thread; the actor only calls FrontEnd::set from its own threads.
//
// Unsolicited keywords to every listener (the watcher, every watch_period_s): `safety_stop` ('e')
// when the loop ended by itself (a board error, stale data, a limit: the library's fault text),
// `board_error` ('e' when the board reports an error code, 'i' when it clears), `stale_action`
// ('w', the front end's stale episodes), `stale_data` ('w' when the board's status frames stop
// outside the loop, 'i' when they resume), `broker_lost` ('w', see below) and the status every
// status_period_s.
//
// Safety without the bus: broker_state(false) (wire BusActor::on_state to it) sets the idle action
// at once, so a lost commander does not leave a current flowing; a warning says so once the broker
// is back. The board's own safety does not depend on the bus: the library's limits run in the loop
// (current clamp, velocity limit, stale data, board errors end the loop with zero current and the
// motors off), and the board's receive timeout stops it when the host stops sending.
//
// enable, start, stop, home and recover are exclusive (a second one while one runs is refused).
// disable is never refused: it interrupts an enable, home or recover in progress and turns the
// motors off. Setting an action is refused ('f') while no loop runs.
//
// The board must be open and outlive the actor. The destructor interrupts an enable, home or
// recover in progress, closes the core (later commands are refused), waits for the running ones,
// stops the watcher, stops the loop and disables the motors; it never throws.
#pragma once

#include "axon/actor/actor_core.hpp"
#include "axon/blmc/host/front_end.hpp"
#include "axon/blmc/host/motor_board.hpp"

#include <cstdint>
#include <functional>
#include <memory>

namespace axon::actor {

struct BlmcActorOptions {
  double status_period_s = 10.0;  // 0: no periodic status
  double watch_period_s = 0.02;   // the watcher: action refresh, loop end, errors, stale data
  // The loop's settings for `start`: the safety limits (a start may lower the current and velocity
  // limits, never raise them), period, real-time request.
  blmc::ControlSettings control{};
  blmc::FrontEndOptions front_end{};  // first_action_timeout, stale_after
  double status_stale_s = 3.0;        // outside the loop: status frames older than this are stale data
  double pd_kp = 5.0;                 // pd's default gains (as `axon blmc pd`), A/rev
  double pd_kd = 0.05;                // A/(rev/s)
  std::uint32_t recv_timeout_ms = 50;  // the board's receive timeout as opened (MotorBoardOptions), for status
  // Every read of the board's measurements the actor makes (its watcher's, every watch period, and
  // status), on the reading thread, never the loop's: for a view beside the actor (web::BlmcPage),
  // which must not call the board itself (one thread at a time). Keep it short. Empty: none.
  std::function<void(const blmc::host::Measurements&)> on_board_read{};
};

class BlmcActor {
 public:
  BlmcActor(ActorCore& core, blmc::MotorBoard& board, BlmcActorOptions options = {});
  ~BlmcActor();
  BlmcActor(const BlmcActor&) = delete;
  BlmcActor& operator=(const BlmcActor&) = delete;

  // The broker connection came or went (BusActor::on_state; quick, from any thread). Lost: the
  // idle action at once (zero current); back: a `broker_lost` warning to every listener.
  void broker_state(bool connected) noexcept;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace axon::actor
