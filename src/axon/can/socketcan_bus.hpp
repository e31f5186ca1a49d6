// A Linux SocketCAN interface (can0, vcan0, slcan0...) as a can::Bus, through a CAN_RAW socket.
//
// Receiving: the socket is watched for readability on the bus's executor and drained without
// blocking. Each frame carries the kernel's receive timestamp (the host clock when the kernel
// gives none). Error reports from the controller are never delivered as frames: they move the
// bus state (bus-off, error-warning, error-passive, back to active) and bump counters.
//
// Sending: one 16-byte write per frame. When the kernel's transmit queue is full (EAGAIN or
// ENOBUFS, common when a bus has nobody to acknowledge or txqueuelen is small), send() waits for
// room and retries, at most SocketCanOptions::tx_timeout, then fails with tx_overflow. Frames
// leave in the order send() was called.
//
// Kernels without AF_CAN (containers, some VMs) make open() fail with CanErrc::not_supported;
// use a CAN@net or socketcand transport there. adopt() runs the same code on any datagram socket,
// which is how the tests exercise it without a CAN interface.
#pragma once

#include "axon/can/bus.hpp"
#include "axon/can/socketcan_frame.hpp"

#include <chrono>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace axon::can {

struct SocketCanOptions {
  // How long send() keeps retrying while the kernel queue is full before tx_overflow.
  core::Duration tx_timeout = std::chrono::milliseconds(100);
  // Receive filters applied from the start (also in the kernel on a CAN socket); see set_filters.
  std::vector<Filter> filters;
  // Ask the kernel for controller error reports (CAN_RAW_ERR_FILTER): needed for bus-state tracking.
  bool error_reports = true;
  // Also receive the frames this socket sent (CAN_RAW_RECV_OWN_MSGS).
  bool receive_own = false;
};

// Counters specific to this transport (the common ones are in Bus::stats()).
struct SocketCanStats {
  std::uint64_t tx_retries = 0;               // writes retried because the kernel queue was full
  std::uint64_t tx_timeouts = 0;              // sends given up after tx_timeout (tx_overflow)
  std::uint64_t kernel_rx_dropped = 0;        // frames the kernel dropped: our socket buffer was full
  std::uint64_t controller_rx_overflows = 0;  // error reports: controller receive FIFO overflowed
  std::uint64_t controller_tx_overflows = 0;  // error reports: controller transmit FIFO overflowed
  std::uint64_t lost_arbitration = 0;
  std::uint64_t bus_errors = 0;
  std::uint64_t no_ack = 0;                   // nobody acknowledged a frame we sent
  std::uint64_t tx_timeout_reports = 0;       // the driver gave up on a transmission
  std::uint64_t restarts = 0;                 // controller restarted after bus-off
  std::uint64_t timestamp_fallbacks = 0;      // frames stamped with the host clock
  std::uint64_t io_errors = 0;                // failed reads (e.g. interface went down)
  std::optional<std::uint8_t> tx_error_counter;  // last reported by the controller
  std::optional<std::uint8_t> rx_error_counter;
};

class SocketCanBus final : public Bus {
 public:
  // Opens a CAN_RAW socket on the interface ("any" receives from all CAN interfaces; sending then
  // needs a specific one). Errors: not_supported when the kernel has no AF_CAN or CAN_RAW;
  // bad_spec for an empty or too long name; io for a missing or non-CAN interface and other
  // socket errors, with the interface named in the detail.
  static Result<std::unique_ptr<SocketCanBus>> open(executor_type ex, std::string iface, BusOptions options = {},
                                                    SocketCanOptions socket_options = {});

  // Runs the bus over an already-open socket that carries one struct can_frame per datagram
  // (a CAN_RAW socket opened elsewhere, or a SOCK_DGRAM/SOCK_SEQPACKET socketpair in tests).
  // Takes ownership of fd, also when it fails. Stream sockets are refused (not_supported).
  static Result<std::unique_ptr<SocketCanBus>> adopt(executor_type ex, int fd, std::string name,
                                                     BusOptions options = {}, SocketCanOptions socket_options = {});

  ~SocketCanBus() override;

  asio::awaitable<Result<void>> send(const Frame& frame) override;
  void close() override;
  // The Bus filters, also installed in the kernel on a CAN socket so unwanted frames never wake
  // the process. A kernel refusal is logged; the user-space filters still apply.
  void set_filters(std::vector<Filter> filters) override;
  // send() calls waiting for room in the kernel queue.
  [[nodiscard]] std::size_t tx_pending() const noexcept override { return tx_waiting_; }

  [[nodiscard]] const SocketCanStats& socketcan_stats() const noexcept { return sc_stats_; }
  // True for an AF_CAN socket (kernel filters apply), false for an adopted non-CAN socket.
  [[nodiscard]] bool is_can_socket() const noexcept { return can_socket_; }
  // True when the kernel stamps received frames (SO_TIMESTAMPNS or SO_TIMESTAMP accepted).
  [[nodiscard]] bool kernel_timestamps() const noexcept { return kernel_timestamps_; }

 private:
  struct Io;

  SocketCanBus(executor_type ex, std::string name, BusOptions options, SocketCanOptions socket_options);
  // Common tail of open() and adopt(): owns fd from here on.
  static Result<std::unique_ptr<SocketCanBus>> start(executor_type ex, int fd, std::string name, BusOptions options,
                                                     SocketCanOptions socket_options, bool can_socket,
                                                     bool stream_like);
  static asio::awaitable<void> read_loop(std::shared_ptr<Io> io);
  // Reads what the socket holds without blocking; false once the bus had to close.
  bool drain();
  void handle_record(Result<socketcan::Decoded> decoded, std::optional<core::WallTime> stamp, bool local_origin);
  void handle_error_report(const socketcan::ErrorReport& report);
  void apply_kernel_filters();
  void release_tx() noexcept;

  SocketCanOptions socket_options_;
  std::shared_ptr<Io> io_;
  SocketCanStats sc_stats_;
  bool can_socket_ = false;
  bool stream_like_ = false;  // SOCK_SEQPACKET: a zero-length read means the peer closed
  bool kernel_timestamps_ = false;
  std::uint32_t kernel_drops_seen_ = 0;
  bool bad_record_logged_ = false;
  // Senders in order: the one writing holds tx_busy_; the others wait on their timers in tx_queue_.
  bool tx_busy_ = false;
  std::deque<asio::steady_timer*> tx_queue_;
  asio::steady_timer* tx_backoff_ = nullptr;  // the writer's retry timer, cancelled by close()
  std::size_t tx_waiting_ = 0;
};

}  // namespace axon::can
