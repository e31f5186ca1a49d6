// The controller's side of the UDP exchange: a net::UdpSocket bound to an ephemeral (or given)
// local port that talks to one PC server. Adds what the simulated controller needs on top of the
// socket: a receive with an absolute steady-clock deadline that ignores datagrams from anyone but
// the server and tells when each datagram arrived (the kernel's stamp, so that a reply is judged by
// its arrival and not by when this thread got the CPU), and a drain of replies that came too late.
#pragma once

#include "axon/core/error.hpp"
#include "axon/net/endpoint.hpp"
#include "axon/net/udp_socket.hpp"

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

namespace axon::c4g::sim {

class UdpClient {
 public:
  using Clock = std::chrono::steady_clock;

  // Resolves the server (IPv4), binds to an ephemeral local port (or `local` when given).
  static Result<UdpClient> open(const net::Endpoint& server, const std::optional<net::Endpoint>& local = std::nullopt);

  Result<void> send(std::span<const std::byte> datagram);
  struct Received {
    std::size_t size = 0;        // 0: nothing came
    Clock::time_point arrived{}; // the kernel's arrival stamp on the steady clock (else the return time)
  };
  // One datagram from the server: waits until the deadline, and once it has passed still returns
  // what is already queued (its arrival time tells whether it came in time). size 0: nothing.
  // Datagrams from other senders are dropped and counted (foreign()).
  Result<Received> receive(std::span<std::byte> buffer, Clock::time_point deadline);
  // Drops whatever is queued (replies that came after their deadline); returns how many.
  std::size_t drain(std::span<std::byte> scratch);
  [[nodiscard]] net::Endpoint local_endpoint() const;
  [[nodiscard]] std::uint64_t foreign() const noexcept { return foreign_; }
  [[nodiscard]] const net::UdpCounters& counters() const noexcept { return socket_.counters(); }

 private:
  UdpClient(net::UdpSocket socket, net::SocketAddress server) : socket_(std::move(socket)), server_(server) {}

  net::UdpSocket socket_;
  net::SocketAddress server_;
  std::uint64_t foreign_ = 0;
};

}  // namespace axon::c4g::sim
