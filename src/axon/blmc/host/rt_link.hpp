// The hand-over of CAN frames between a real-time thread and the asio thread a can::Bus lives on.
//
// Why this shape: a can::Bus is single-threaded and its send() is a coroutine on the bus's
// executor, so the real-time thread must not call it. Posting a handler to the io_context from the
// real-time thread would take the io_context's mutex and may allocate. Instead the bus I/O stays on
// its thread and the two sides exchange frames through two preallocated lock-free
// single-producer/single-consumer queues:
//
//   bus thread  --rx queue-->  real-time thread   (frames the board sent; the RT side polls it at
//                                                  the start of each cycle or waits on its doorbell)
//   real-time thread --tx queue--> bus thread     (current references and commands; the RT side
//                                                  rings an eventfd the bus thread's coroutine waits on)
//
// Each direction has an eventfd doorbell: writing it is one non-blocking system call, with no
// user-space lock and no allocation, and asio waits on it like on a socket. The same code thus
// works over every transport (virtual bus, SocketCAN, socketcand, CAN@net) at the cost of one
// thread hop per frame, which bench/blmc_loop.cpp measures against the bare bus round trip.
//
// Exactly one thread uses each side. Full queues drop the new frame and count it.
#pragma once

#include "axon/can/frame.hpp"
#include "axon/core/clock.hpp"

#include <boost/lockfree/spsc_queue.hpp>

#include <atomic>
#include <cstddef>
#include <cstdint>

namespace axon::blmc::host {

class RtLink {
 public:
  // Throws axon::Exception (CoreErrc::io) if the eventfds cannot be made.
  explicit RtLink(std::size_t capacity = 256);
  ~RtLink();
  RtLink(const RtLink&) = delete;
  RtLink& operator=(const RtLink&) = delete;

  // ---- real-time side
  // Queues a frame for the bus and rings the tx doorbell; false (counted) when the queue is full.
  bool send(const can::Frame& f) noexcept;
  // The next frame from the bus, if any.
  bool receive(can::Frame& out) noexcept;
  // Waits until the rx doorbell rings or `timeout` passes (poll(2) on the eventfd, then clears
  // it). True when rung.
  bool wait_rx(core::Duration timeout) noexcept;
  [[nodiscard]] int rx_doorbell() const noexcept { return rx_bell_; }
  void clear_rx_doorbell() noexcept;

  // ---- bus side
  // Hands a received frame to the real-time side; false (counted) when its queue is full.
  bool deliver(const can::Frame& f) noexcept;
  // The next frame the real-time side queued.
  bool take(can::Frame& out) noexcept;
  // The fd the bus side waits on for frames to send (readable when rung).
  [[nodiscard]] int tx_doorbell() const noexcept { return tx_bell_; }
  // Clears the tx doorbell (after it became readable).
  void clear_tx_doorbell() noexcept;
  // Frames queued from the RT side and not yet taken.
  [[nodiscard]] bool tx_empty() noexcept { return tx_.empty(); }

  [[nodiscard]] std::uint64_t tx_dropped() const noexcept { return tx_dropped_.load(std::memory_order_relaxed); }
  [[nodiscard]] std::uint64_t rx_dropped() const noexcept { return rx_dropped_.load(std::memory_order_relaxed); }

 private:
  boost::lockfree::spsc_queue<can::Frame> rx_;
  boost::lockfree::spsc_queue<can::Frame> tx_;
  int rx_bell_ = -1;
  int tx_bell_ = -1;
  std::atomic<std::uint64_t> tx_dropped_{0};
  std::atomic<std::uint64_t> rx_dropped_{0};
};

}  // namespace axon::blmc::host
