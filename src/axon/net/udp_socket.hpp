// A UDP socket for real-time loops: plain POSIX, one owning thread, no allocation per packet.
//
// The owning thread calls receive() (blocking in ppoll with a timeout, or spinning on a
// non-blocking recvmsg when busy polling is chosen), then reply() or send_to(). Each datagram
// comes with the kernel's arrival time (SO_TIMESTAMPNS, CLOCK_REALTIME) when the kernel gives
// one, else the wall clock at return, plus the monotonic clock at return for cycle statistics.
// Another thread may call interrupt() to make a waiting receive() return promptly (stop()).
//
// IPv4 only: the controllers this serves speak IPv4, and pcap recording synthesizes IPv4 headers.
#pragma once

#include "axon/core/error.hpp"
#include "axon/net/endpoint.hpp"
#include "axon/net/error.hpp"

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>

namespace axon::net {

// An IPv4 address and port, both in host byte order (0x7f000001 is 127.0.0.1).
struct SocketAddress {
  std::uint32_t ip = 0;
  std::uint16_t port = 0;

  [[nodiscard]] std::string to_string() const;  // "10.2.12.150:1000"
  friend bool operator==(const SocketAddress&, const SocketAddress&) = default;
};

// Resolves "HOST:PORT" to an IPv4 address. An empty host, "*" and "0.0.0.0" mean any address.
// May block in the resolver: call it at set-up, never in a cycle.
Result<SocketAddress> resolve_ipv4(const Endpoint& endpoint);

struct UdpOptions {
  bool kernel_timestamps = true;  // SO_TIMESTAMPNS; falls back to the clock if refused
  bool busy_poll = false;         // spin on recvmsg(MSG_DONTWAIT) instead of sleeping in ppoll
  int receive_buffer_bytes = 0;   // SO_RCVBUF; 0 keeps the system default
  int send_buffer_bytes = 0;      // SO_SNDBUF; 0 keeps the system default
  int socket_priority = -1;       // SO_PRIORITY (0..6 without privileges); -1 leaves it
  int tos = -1;                   // IP_TOS byte (e.g. 0xb8 for DSCP EF); -1 leaves it
  bool reuse_address = false;     // SO_REUSEADDR
};

// One received datagram. The payload is in the caller's buffer.
struct Datagram {
  std::size_t size = 0;       // bytes stored in the caller's buffer
  std::size_t wire_size = 0;  // bytes the datagram carried; larger than size when truncated
  SocketAddress from;
  SocketAddress to;  // the address it was sent to (tells which local address when bound to any)
  std::int64_t wall_ns = 0;           // arrival, ns since the epoch: the kernel's stamp if any
  std::int64_t steady_ns = 0;         // CLOCK_MONOTONIC when receive() got the datagram
  std::int64_t wakeup_latency_ns = 0; // wall clock at return minus the kernel stamp (0 without one)
  bool kernel_timestamp = false;      // wall_ns came from the kernel

  [[nodiscard]] bool truncated() const noexcept { return wire_size > size; }
};

// Counters, updated by the owning thread and readable from any thread.
struct UdpCounters {
  std::atomic<std::uint64_t> received{0};
  std::atomic<std::uint64_t> sent{0};
  std::atomic<std::uint64_t> timeouts{0};
  std::atomic<std::uint64_t> truncated{0};
  std::atomic<std::uint64_t> receive_errors{0};
  std::atomic<std::uint64_t> send_errors{0};
};

class UdpSocket {
 public:
  // Binds to `local` (port 0 picks a free port; see local_address()).
  static Result<UdpSocket> open(const SocketAddress& local, const UdpOptions& options = {});
  // Resolves then binds; "HOST:PORT" as users write it.
  static Result<UdpSocket> open(const Endpoint& local, const UdpOptions& options = {});

  UdpSocket(UdpSocket&& other) noexcept;
  UdpSocket& operator=(UdpSocket&& other) noexcept;
  UdpSocket(const UdpSocket&) = delete;
  UdpSocket& operator=(const UdpSocket&) = delete;
  ~UdpSocket();

  // Waits for one datagram and copies it into `buffer`. timeout < 0 waits for ever, 0 only
  // looks. Errors: timeout, interrupted, receive_failed, closed. The sender becomes the peer.
  Result<Datagram> receive(std::span<std::byte> buffer, std::chrono::nanoseconds timeout);

  Result<void> send_to(std::span<const std::byte> payload, const SocketAddress& to);
  // Sends to the peer (the sender of the last datagram received, or set_peer()).
  Result<void> reply(std::span<const std::byte> payload);

  [[nodiscard]] const std::optional<SocketAddress>& peer() const noexcept { return peer_; }
  void set_peer(const SocketAddress& peer) noexcept { peer_ = peer; }

  // Makes a waiting or later receive() return `interrupted` until clear_interrupt(). Any thread.
  void interrupt() noexcept;
  void clear_interrupt() noexcept;

  [[nodiscard]] SocketAddress local_address() const noexcept { return local_; }
  [[nodiscard]] std::uint16_t local_port() const noexcept { return local_.port; }
  [[nodiscard]] bool kernel_timestamps() const noexcept { return kernel_timestamps_; }
  [[nodiscard]] const UdpOptions& options() const noexcept { return options_; }
  [[nodiscard]] const UdpCounters& counters() const noexcept { return shared_->counters; }
  [[nodiscard]] int native_handle() const noexcept { return fd_; }
  [[nodiscard]] bool is_open() const noexcept { return fd_ >= 0; }

  void close() noexcept;

 private:
  UdpSocket() = default;
  Result<Datagram> receive_ready(std::span<std::byte> buffer);  // one non-blocking recvmsg

  int fd_ = -1;
  int wake_fd_ = -1;  // eventfd written by interrupt()
  SocketAddress local_;
  UdpOptions options_;
  bool kernel_timestamps_ = false;
  std::optional<SocketAddress> peer_;
  // Heap-held so that the socket stays movable while other threads may reach these.
  struct Shared {
    std::atomic<bool> interrupted{false};
    UdpCounters counters;
  };
  std::unique_ptr<Shared> shared_;
};

}  // namespace axon::net
