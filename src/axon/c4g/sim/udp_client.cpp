#include "axon/c4g/sim/udp_client.hpp"

#include "axon/net/error.hpp"

#include <fmt/format.h>

namespace axon::c4g::sim {

Result<UdpClient> UdpClient::open(const net::Endpoint& server, const std::optional<net::Endpoint>& local) {
  AXON_TRY(to, net::resolve_ipv4(server));
  net::UdpOptions options;
  options.kernel_timestamps = false;  // the controller times its round trips with its own clock
  const net::Endpoint any{"0.0.0.0", 0};
  AXON_TRY(socket, net::UdpSocket::open(local ? *local : any, options));
  socket.set_peer(to);
  return UdpClient(std::move(socket), to);
}

Result<void> UdpClient::send(std::span<const std::byte> datagram) { return socket_.send_to(datagram, server_); }

Result<std::size_t> UdpClient::receive(std::span<std::byte> buffer, Clock::time_point deadline) {
  for (;;) {
    const auto left = deadline - Clock::now();
    if (left <= Clock::duration::zero()) return std::size_t{0};
    auto got = socket_.receive(buffer, std::chrono::duration_cast<std::chrono::nanoseconds>(left));
    if (!got) {
      if (got.error() == net::NetErrc::timeout) return std::size_t{0};
      return got.error();
    }
    if (got.value().from != server_) {
      ++foreign_;
      continue;
    }
    if (got.value().wire_size == 0) continue;  // an empty datagram: nothing to judge
    // The size on the wire, so that an oversized reply is judged by its real length.
    return got.value().wire_size;
  }
}

std::size_t UdpClient::drain(std::span<std::byte> scratch) {
  std::size_t n = 0;
  for (;;) {
    auto got = socket_.receive(scratch, std::chrono::nanoseconds(0));
    if (!got) return n;
    ++n;
  }
}

net::Endpoint UdpClient::local_endpoint() const {
  const auto a = socket_.local_address();
  return net::Endpoint{fmt::format("{}.{}.{}.{}", a.ip >> 24, (a.ip >> 16) & 0xff, (a.ip >> 8) & 0xff, a.ip & 0xff), a.port};
}

}  // namespace axon::c4g::sim
