// The controller's side of the UDP exchange with plain POSIX sockets: a connected UDP socket to the
// PC's server address, send, and receive with an absolute steady-clock deadline. Small on purpose,
// so it can be swapped for net::UdpSocket once that lands.
#pragma once

#include "core/error.hpp"
#include "net/endpoint.hpp"

#include <chrono>
#include <cstddef>
#include <optional>
#include <span>

namespace axon::c4g::sim {

class UdpClient {
 public:
  using Clock = std::chrono::steady_clock;

  // Resolves the server, binds to an ephemeral local port (or `local` when given) and connects.
  static Result<UdpClient> open(const net::Endpoint& server, const std::optional<net::Endpoint>& local = std::nullopt);
  UdpClient(UdpClient&& o) noexcept : fd_(o.fd_) { o.fd_ = -1; }
  UdpClient& operator=(UdpClient&& o) noexcept;
  UdpClient(const UdpClient&) = delete;
  UdpClient& operator=(const UdpClient&) = delete;
  ~UdpClient();

  Result<void> send(std::span<const std::byte> datagram);
  // One datagram before the deadline: its size, 0 at the deadline. ICMP "port unreachable" from
  // an absent server is not an error here (the controller counts the miss).
  Result<std::size_t> receive(std::span<std::byte> buffer, Clock::time_point deadline);
  // Drops whatever is queued (replies that came after their deadline); returns how many.
  std::size_t drain(std::span<std::byte> scratch);
  [[nodiscard]] net::Endpoint local_endpoint() const;

 private:
  explicit UdpClient(int fd) : fd_(fd) {}
  int fd_ = -1;
};

}  // namespace axon::c4g::sim
