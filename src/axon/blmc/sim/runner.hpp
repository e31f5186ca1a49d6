// Serves simulated boards on CAN bus endpoints: one board per bus (as in service), each fed the
// frames its endpoint receives and advanced by a 1 kHz tick that sends what the firmware emits.
//
//   Runner runner(io.get_executor());                         // RunnerOptions: clock, tick period
//   Board* b = runner.add(BoardConfig{}, BoardFaultPlan{}, registry, "can0").value();
//   runner.start();  ...  runner.stop();
//
// Time: each board's time starts when it is added (its power-up) and follows the runner's clock
// (core::SteadyClock unless RunnerOptions::clock says otherwise). The tick waits for absolute
// deadlines (start + k periods), so wake-up latency never accumulates; when the process falls
// further behind than max_catch_up (descheduled, a debugger), the schedule restarts from now and
// the boards send the data of their last few cycles only, not a burst no real board would send.
//
// Tests with a core::ManualClock set tick = 0 (no timer), move the clock, then call step() and
// let the executor run (io.poll()) to deliver frames. Everything runs on one executor.
#pragma once

#include "axon/blmc/sim/board.hpp"
#include "axon/blmc/sim/runner_stats.hpp"
#include "axon/can/bus.hpp"
#include "axon/can/provider.hpp"
#include "axon/can/virtual_bus.hpp"
#include "axon/core/clock.hpp"

#include <boost/asio/any_io_executor.hpp>

#include <chrono>
#include <cstdint>
#include <memory>
#include <string_view>

namespace axon::blmc::sim {

namespace asio = boost::asio;

struct RunnerOptions {
  core::Duration tick = kCycle;  // real time between steps; 0: no timer, the caller calls step()
  core::Duration max_catch_up = std::chrono::milliseconds(2);
  const core::Clock* clock = nullptr;  // default: core::SteadyClock::instance()
};

class Runner {
 public:
  explicit Runner(asio::any_io_executor executor, RunnerOptions options = {});
  Runner(const Runner&) = delete;
  Runner& operator=(const Runner&) = delete;
  ~Runner();  // stop()s

  // A new board on a new endpoint of `channel` (or of `medium`), powered up now. Invalid configs
  // and plans are CoreErrc::invalid_argument; a stopped runner is CoreErrc::closed.
  Result<Board*> add(BoardConfig config, BoardFaultPlan faults, can::BusProvider& provider, std::string_view channel);
  Result<Board*> add(BoardConfig config, BoardFaultPlan faults, can::VirtualBus& medium);

  void start();  // receive loops and the tick; idempotent
  void stop();   // closes the endpoints, stops the tick; idempotent; boards stay readable
  [[nodiscard]] bool running() const noexcept;

  // Advances every board to the clock's now and sends what they emit (what the tick does).
  void step();

  [[nodiscard]] std::size_t size() const noexcept;
  [[nodiscard]] Board& board(std::size_t i);
  [[nodiscard]] const can::Bus& endpoint(std::size_t i) const;
  // Board i's time now.
  [[nodiscard]] BoardTime now(std::size_t i) const;
  [[nodiscard]] const RunnerStats& stats() const noexcept;

  struct State;

 private:
  std::shared_ptr<State> state_;
};

}  // namespace axon::blmc::sim
