// The real-time cycle: a dedicated thread that waits for the controller's packet, lets a handler
// build the answer, sends it, and times the cycle.
//
// The thread asks for SCHED_FIFO, locked memory and CPU pinning (core::apply_realtime) when it
// starts; refusals are logged as warnings and reported, and the loop runs anyway. Inside the loop
// nothing allocates, locks or logs: buffers are sized at construction, statistics are atomics,
// and packet recording goes through the PcapRecorder's lock-free queue.
//
// Per cycle: t1 when the packet has been received, handler, send, t2 after the send returned
// (TimingStats); besides, the kernel's arrival stamp gives the wake-up latency (arrival to user
// space) and the reply latency (arrival to answer sent), both on the wall clock.
//
// stop() interrupts the socket wait (an eventfd) and joins: it returns within one handler call.
#pragma once

#include "axon/core/latency_histogram.hpp"
#include "axon/c4g/host/pcap_recorder.hpp"
#include "axon/c4g/host/timing_stats.hpp"
#include "axon/core/realtime.hpp"
#include "axon/net/udp_socket.hpp"

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <span>
#include <thread>
#include <vector>

namespace axon::c4g::host {

// What the cycle thread calls. All calls come from the cycle thread, one at a time; they must
// not block, and they must not throw (the Server wraps user code and catches).
class CycleHandler {
 public:
  virtual ~CycleHandler() = default;
  // Whether a received datagram is the handler's business at all. A refused datagram (a foreign
  // sender) leaves no trace in the cycle: no on_packet, no reply, no timing or latency sample, no
  // capture, and it does not postpone the cycle timeout.
  virtual bool accepts(std::span<const std::byte> request, const net::Datagram& info) noexcept {
    (void)request, (void)info;
    return true;
  }
  // One accepted datagram (possibly truncated: info.truncated()). Writes the answer into `reply`
  // and returns its length; 0 sends nothing.
  virtual std::size_t on_packet(std::span<const std::byte> request, const net::Datagram& info,
                                std::span<std::byte> reply) noexcept = 0;
  // No accepted datagram within the timeout; `before_first` while none has been accepted yet.
  virtual void on_timeout(bool before_first) noexcept { (void)before_first; }
};

struct CycleOptions {
  core::RealtimeRequest realtime;  // none by default: tests and laptops; set for a real robot
  // The field libraries wait 5 min for the first packet and 1 s between packets.
  std::chrono::nanoseconds first_packet_timeout = std::chrono::minutes(5);
  std::chrono::nanoseconds cycle_timeout = std::chrono::seconds(1);
  TimingConfig timing;
  std::size_t max_datagram = 2048;  // receive buffer; larger datagrams arrive truncated
  std::size_t max_reply = 2048;     // reply buffer handed to the handler
};

struct CycleCounters {
  std::atomic<std::uint64_t> cycles{0};          // accepted datagrams handled
  std::atomic<std::uint64_t> refused{0};         // datagrams the handler refused (accepts() false)
  std::atomic<std::uint64_t> replies{0};         // answers sent
  std::atomic<std::uint64_t> silent{0};          // datagrams the handler chose not to answer
  std::atomic<std::uint64_t> timeouts{0};        // waits that ended without a packet
  std::atomic<std::uint64_t> send_errors{0};
  std::atomic<std::uint64_t> receive_errors{0};
};

class CycleThread {
 public:
  // Takes the socket. `recorder` (optional) must outlive the thread.
  CycleThread(net::UdpSocket socket, CycleHandler& handler, const CycleOptions& options = {},
              PcapRecorder* recorder = nullptr);
  ~CycleThread();  // stop()
  CycleThread(const CycleThread&) = delete;
  CycleThread& operator=(const CycleThread&) = delete;

  // Starts the thread and waits until its real-time set-up is done; returns that report.
  core::RealtimeReport start();
  // Interrupts the wait and joins. Idempotent.
  void stop();
  [[nodiscard]] bool running() const noexcept { return running_.load(std::memory_order_acquire); }

  [[nodiscard]] net::SocketAddress local_address() const noexcept { return socket_.local_address(); }
  [[nodiscard]] const net::UdpSocket& socket() const noexcept { return socket_; }
  [[nodiscard]] const TimingStats& timing() const noexcept { return timing_; }
  // The controller's inter-packet period the timing figures compare against (any thread).
  void set_nominal_period(std::int64_t ns) noexcept { timing_.set_nominal_period_ns(ns); }
  [[nodiscard]] const core::LatencyHistogram& wakeup_latency() const noexcept { return wakeup_; }
  [[nodiscard]] const core::LatencyHistogram& reply_latency() const noexcept { return reply_latency_; }
  [[nodiscard]] const CycleCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] const core::RealtimeReport& realtime_report() const noexcept { return report_; }

  // TimingStats summary plus the latencies and counters.
  [[nodiscard]] std::string summary() const;

 private:
  void run();
  // Waits for the next datagram until `deadline_ns` (CLOCK_MONOTONIC; < 0: no deadline).
  Result<net::Datagram> receive_until(std::int64_t deadline_ns);
  void serve(const net::Datagram& d);

  net::UdpSocket socket_;
  CycleHandler& handler_;
  CycleOptions options_;
  PcapRecorder* recorder_;
  std::vector<std::byte> rx_;
  std::vector<std::byte> tx_;
  TimingStats timing_;
  core::LatencyHistogram wakeup_;
  core::LatencyHistogram reply_latency_;
  CycleCounters counters_;
  core::RealtimeReport report_;
  std::atomic<bool> running_{false};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace axon::c4g::host
