// The host driver against the board simulator (src/axon/blmc/sim) on the in-process virtual bus: the
// simulator ticks at 1 kHz on the test's io thread; a ControlLoop runs on its own thread.
#pragma once

#include "axon/blmc/host/control_loop.hpp"
#include "axon/blmc/sim/runner.hpp"
#include "rig.hpp"

namespace axon::blmc::host::testing {

namespace sim = axon::blmc::sim;

struct SimRig {
  asio::io_context io;
  can::VirtualBusRegistry registry{io.get_executor()};
  sim::Runner runner{io.get_executor()};
  sim::Board* sim = nullptr;
  std::unique_ptr<can::Bus> host;

  explicit SimRig(sim::BoardConfig cfg = config(), sim::BoardFaultPlan plan = {}) {
    registry.add("can0").value();
    host = registry.open("can0").value();
    sim = runner.add(cfg, plan, registry, "can0").value();
    runner.start();
  }
  static sim::BoardConfig config() {
    sim::BoardConfig c;
    c.alignment_time = 200ms;
    return c;
  }
  void run(std::function<asio::awaitable<void>()> body) {
    bool finished = false;
    std::exception_ptr failure;
    asio::co_spawn(
        io,
        [&]() -> asio::awaitable<void> {
          try {
            co_await body();
          } catch (...) {
            failure = std::current_exception();
          }
          finished = true;
          runner.stop();
          if (host) host->close();  // a test may have dropped the bus
          io.stop();
        },
        [](std::exception_ptr) {});
    io.run_for(60s);
    EXPECT_TRUE(finished) << "test body did not finish";
    if (failure) std::rethrow_exception(failure);
  }
};

// The limits these tests run with: the defaults, except the stale-data limit. The simulator shares
// the io thread with the test and a loaded (or sanitized) machine can hold it for more than the
// real 10 ms; a test about another fault must not end in stale data. The stall test's gap (2.5 s)
// is far beyond this limit.
inline SafetyLimits test_limits() {
  SafetyLimits lim;
  lim.stale_after = 250ms;
  return lim;
}

inline LoopOptions loop_options() {
  LoopOptions o;
  o.realtime = false;
  return o;
}

}  // namespace axon::blmc::host::testing
