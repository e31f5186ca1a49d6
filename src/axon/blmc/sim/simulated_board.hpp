// SimulatedBoard: simulated motor driver boards served in-process behind a blocking face, for a
// test, an example or a notebook that wants a board in one line:
//
//   axon::blmc::sim::SimulatedBoard sim;                  // one board, socketcand on 127.0.0.1:<any>
//   axon::blmc::MotorBoard board(sim.bus_spec());         // the host connects like to real hardware
//   sim.inject(axon::blmc::sim::FaultKind::encoder);      // the firmware raises ENCODER next cycle
//
// It owns an event loop on a thread of its own (core::LoopThread) running the boards' 1 kHz tick
// (Runner), one virtual bus per board (can0, can1 ...) and a socketcand server over them, so the
// host side (any process, python-can too) reaches board i at bus_spec(i). `axon sim blmc` is this
// object and a wait for Ctrl-C.
//
// Errors: the constructor throws axon::Exception for an invalid configuration or fault plan
// (CoreErrc::invalid_argument) or an address it cannot bind (can::CanErrc::io). Accessors throw
// std::out_of_range for a board that does not exist. The destructor stops everything and never
// throws. Thread-safe: every call goes to the loop's thread.
#pragma once

#include "axon/blmc/protocol/status.hpp"
#include "axon/blmc/sim/board.hpp"
#include "axon/blmc/sim/board_config.hpp"
#include "axon/blmc/sim/fault_plan.hpp"
#include "axon/blmc/sim/runner_stats.hpp"
#include "axon/core/realtime.hpp"

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace axon::blmc::sim {

struct SimulatedBoardOptions {
  unsigned boards = 1;                  // board i on bus can<i>
  BoardConfig config{};                 // every board's motors, alignment time, ADC ...
  std::vector<BoardFaultPlan> faults;   // per board (fewer entries: no faults for the rest)
  std::string socketcand = "127.0.0.1:0";  // where to serve (port 0: any free port)
  bool bus_load = true;                 // account bit times on the buses (bus_load() figures)
  // The loop thread's scheduling (core/realtime.hpp): a board keeps its 1 kHz whatever else runs,
  // so a simulator that stands in for one next to a real-time host may ask for SCHED_FIFO too.
  // Nothing by default; a refusal is a logged warning.
  core::RealtimeRequest realtime{};
};

// One board's state and counters at the moment of the call.
struct SimulatedBoardReport {
  protocol::Status status{};
  std::uint8_t status_byte = 0;        // the status as sent (shows an undocumented error code 6)
  std::array<MotorState, 2> motors{};  // enabled, ready, the last IqRef ...
  std::array<double, 2> position_rev{};   // as the board reports it (wrapping at the counter's rollover)
  std::array<double, 2> velocity_krpm{};  // the shafts' velocity
  std::array<double, 2> current_a{};      // the motors' quadrature current
  BoardStats stats{};
  double bus_load = 0;  // 0..1 over the last second (bus_load option)
};

class SimulatedBoard {
 public:
  explicit SimulatedBoard(SimulatedBoardOptions options = {});
  ~SimulatedBoard();
  SimulatedBoard(const SimulatedBoard&) = delete;
  SimulatedBoard& operator=(const SimulatedBoard&) = delete;

  // "socketcand://127.0.0.1:PORT/can<i>": what MotorBoard, `axon blmc --bus` or python-can open.
  [[nodiscard]] std::string bus_spec(unsigned board = 0) const;
  // The socketcand server's address, "HOST:PORT".
  [[nodiscard]] std::string endpoint() const;
  [[nodiscard]] unsigned boards() const noexcept;

  // A fault the firmware raises at its next cycle (a duration keeps its cause; see board.hpp).
  void inject(FaultKind kind, unsigned board = 0, core::Duration duration = core::Duration::zero());
  // Power off and on: the alignment runs again at the next enable.
  void power_cycle(unsigned board = 0);
  [[nodiscard]] SimulatedBoardReport report(unsigned board = 0) const;
  [[nodiscard]] RunnerStats runner_stats() const;

  // Stops serving and ticking (the boards stay readable). Idempotent; the destructor calls it.
  void stop();

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace axon::blmc::sim
