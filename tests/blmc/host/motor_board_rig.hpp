// What the tests of the blocking MotorBoard against the in-process SimulatedBoard share: the
// simulator's and the board's options, the control settings with slack for a loaded machine, a
// poll for a condition and the check that the board was left off.
#pragma once

#include "axon/blmc/host/motor_board.hpp"
#include "axon/blmc/sim/simulated_board.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <functional>
#include <thread>

namespace axon::blmc::board_rig {

inline sim::SimulatedBoardOptions sim_options() {
  sim::SimulatedBoardOptions o;
  o.config.alignment_time = 200ms;
  return o;
}

// Loaded machines (two cores for several builds) hold threads for longer than a real board's
// timing allows (10 ms stale data, a 50 ms receive timeout): the tests that are not about those
// limits give them slack.
inline ControlSettings settings() {
  ControlSettings s;
  s.realtime = false;
  s.limits.stale_after = 500ms;
  return s;
}

inline MotorBoardOptions board_options() {
  MotorBoardOptions o;
  o.recv_timeout_ms = 500;
  return o;
}

// The disable travels over socketcand: the board applies it a moment after the host sent it.
inline void expect_board_off(const sim::SimulatedBoard& sim) {
  const auto off = [&] {
    const auto r = sim.report();
    return !r.status.system_enabled && !r.motors[0].enabled && !r.motors[1].enabled;
  };
  for (int i = 0; i < 300 && !off(); ++i) std::this_thread::sleep_for(10ms);
  const auto r = sim.report();
  EXPECT_FALSE(r.status.system_enabled);
  EXPECT_FALSE(r.motors[0].enabled);
  EXPECT_FALSE(r.motors[1].enabled);
  EXPECT_EQ(r.motors[0].iq_ref_a, 0.0);
  EXPECT_EQ(r.motors[1].iq_ref_a, 0.0);
}

// Polls `done` every 10 ms for up to `limit` (the simulator runs on its own thread).
// True as soon as one poll sees it (a motor passing through its band counts; callers that need it
// to stay check again later).
inline bool wait_for(const std::function<bool()>& done, std::chrono::milliseconds limit = 10s) {
  for (auto t = 0ms; t < limit; t += 10ms) {
    if (done()) return true;
    std::this_thread::sleep_for(10ms);
  }
  return done();
}

}  // namespace axon::blmc::board_rig
