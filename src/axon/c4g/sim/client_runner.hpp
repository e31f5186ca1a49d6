// Runs a simulated controller against a real PC server over UDP: one tick per period on a steady
// absolute schedule (clock_nanosleep, CLOCK_MONOTONIC), sending, waiting for the reply up to the
// reply window, and measuring the round-trip time of each accepted reply.
//
// The reply window is the manual's T_CYCLE1 unless told otherwise (reply_window.hpp). A reply is
// judged by its arrival time (the socket's kernel stamp), so a simulator thread that wakes up late
// does not turn an answer that came in time into a miss; one that arrived after the window is
// handed to the controller once the tick is closed, where it counts as late.
#pragma once

#include "axon/c4g/sim/controller.hpp"
#include "axon/c4g/sim/reply_window.hpp"
#include "axon/core/latency_histogram.hpp"
#include "axon/c4g/sim/udp_client.hpp"

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>

namespace axon::c4g::sim {

struct RunReport {
  core::LatencyHistogram rtt;  // 1 us buckets to 20 ms
  std::uint64_t overruns = 0;   // ticks that started more than a period late (schedule reset)
  std::int64_t window_ns = 0;   // the reply window used
  double elapsed_s = 0;
  bool stopped = false;         // ended by stop or duration rather than by the controller
};

struct RunOptions {
  double duration_s = 0;                          // 0: until the controller finishes (or stop)
  ReplyWindow window = ReplyWindow::manual;
  std::chrono::nanoseconds reply_deadline{0};     // > 0: this window after the send, whatever `window` says
  const std::atomic<bool>* stop = nullptr;        // set from another thread / a signal handler
  std::function<void(const Event&)> on_event;     // called on the cycle thread, between ticks
  // Called after each tick's events with the report so far, on the cycle thread: keep it short,
  // without allocation or locks (SimulatedController copies its live state here).
  std::function<void(const Controller&, const RunReport&)> on_tick;
};

RunReport run_client(Controller& controller, UdpClient& udp, const RunOptions& options);

}  // namespace axon::c4g::sim
