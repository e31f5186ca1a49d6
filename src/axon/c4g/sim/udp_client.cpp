#include "axon/c4g/sim/udp_client.hpp"

#include "axon/net/error.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace axon::c4g::sim {

Result<UdpClient> UdpClient::open(const net::Endpoint& server, const std::optional<net::Endpoint>& local) {
  AXON_TRY(to, net::resolve_ipv4(server));
  net::UdpOptions options;
  options.kernel_timestamps = true;  // replies are judged by their arrival, not by this thread's wake-up
  const net::Endpoint any{"0.0.0.0", 0};
  AXON_TRY(socket, net::UdpSocket::open(local ? *local : any, options));
  socket.set_peer(to);
  return UdpClient(std::move(socket), to);
}

Result<void> UdpClient::send(std::span<const std::byte> datagram) { return socket_.send_to(datagram, server_); }

Result<UdpClient::Received> UdpClient::receive(std::span<std::byte> buffer, Clock::time_point deadline) {
  for (;;) {
    // Past the deadline: only look (timeout 0), so that what came in time is still judged.
    const auto left = std::max(deadline - Clock::now(), Clock::duration::zero());
    auto got = socket_.receive(buffer, std::chrono::duration_cast<std::chrono::nanoseconds>(left));
    if (!got) {
      if (got.error() == net::NetErrc::timeout) return Received{};
      return got.error();
    }
    if (got.value().from != server_) {
      ++foreign_;
      continue;
    }
    if (got.value().wire_size == 0) continue;  // an empty datagram: nothing to judge
    // The size on the wire, so that an oversized reply is judged by its real length. The arrival:
    // the monotonic clock at return minus the wake-up latency the kernel's stamp shows.
    const auto& d = got.value();
    const std::int64_t arrived_ns = d.steady_ns - (d.kernel_timestamp ? std::max<std::int64_t>(d.wakeup_latency_ns, 0) : 0);
    return Received{d.wire_size, Clock::time_point(std::chrono::nanoseconds(arrived_ns))};
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
