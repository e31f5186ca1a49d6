// The Runner's counters (runner.hpp), apart so that the blocking SimulatedBoard can hand them out
// without the event loop's headers.
#pragma once

#include <cstdint>

namespace axon::blmc::sim {

struct RunnerStats {
  std::uint64_t ticks = 0;              // steps run by the timer
  std::uint64_t schedule_restarts = 0;  // the tick fell more than max_catch_up behind
  std::uint64_t send_errors = 0;        // a bus refused a frame (closed, overflow)
  std::uint64_t receive_errors = 0;     // frames the boards did not take (malformed or foreign)
};

}  // namespace axon::blmc::sim
