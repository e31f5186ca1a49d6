// Runs a simulated controller against a real PC server over UDP: one tick per period on a steady
// absolute schedule (clock_nanosleep, CLOCK_MONOTONIC), sending, waiting for the reply up to the
// deadline, and measuring the round-trip time of each accepted reply.
#pragma once

#include "axon/c4g/sim/controller.hpp"
#include "axon/core/latency_histogram.hpp"
#include "axon/c4g/sim/udp_client.hpp"

#include <atomic>
#include <chrono>
#include <functional>

namespace axon::c4g::sim {

struct RunOptions {
  double duration_s = 0;                          // 0: until the controller finishes (or stop)
  std::chrono::nanoseconds reply_deadline{0};     // after the send; 0: one period
  const std::atomic<bool>* stop = nullptr;        // set from another thread / a signal handler
  std::function<void(const Event&)> on_event;     // called on the cycle thread, between ticks
};

struct RunReport {
  core::LatencyHistogram rtt;  // 1 us buckets to 20 ms
  std::uint64_t overruns = 0;   // ticks that started more than a period late (schedule reset)
  double elapsed_s = 0;
  bool stopped = false;         // ended by stop or duration rather than by the controller
};

RunReport run_client(Controller& controller, UdpClient& udp, const RunOptions& options);

}  // namespace axon::c4g::sim
