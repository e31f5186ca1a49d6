#include "c4g/sim/udp_client.hpp"

#include <fmt/format.h>

#include <arpa/inet.h>
#include <cerrno>
#include <cstring>
#include <netdb.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

namespace axon::c4g::sim {
namespace {

Error sys_error(std::string_view what) { return Error(CoreErrc::io, fmt::format("{}: {}", what, std::strerror(errno))); }

Result<sockaddr_storage> resolve(const net::Endpoint& ep, socklen_t& len) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_DGRAM;
  addrinfo* res = nullptr;
  const std::string port = std::to_string(ep.port);
  const int rc = ::getaddrinfo(ep.host.empty() ? nullptr : ep.host.c_str(), port.c_str(), &hints, &res);
  if (rc != 0 || res == nullptr)
    return Error(CoreErrc::invalid_argument, fmt::format("cannot resolve {}: {}", ep.to_string(), ::gai_strerror(rc)));
  sockaddr_storage out{};
  std::memcpy(&out, res->ai_addr, res->ai_addrlen);
  len = static_cast<socklen_t>(res->ai_addrlen);
  ::freeaddrinfo(res);
  return out;
}

}  // namespace

Result<UdpClient> UdpClient::open(const net::Endpoint& server, const std::optional<net::Endpoint>& local) {
  socklen_t len = 0;
  AXON_TRY(addr, resolve(server, len));
  const int fd = ::socket(addr.ss_family, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return sys_error("socket");
  UdpClient c(fd);
  if (local) {
    socklen_t llen = 0;
    AXON_TRY(laddr, resolve(*local, llen));
    if (::bind(fd, reinterpret_cast<const sockaddr*>(&laddr), llen) != 0) return sys_error("bind " + local->to_string());
  }
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&addr), len) != 0) return sys_error("connect " + server.to_string());
  return c;
}

UdpClient& UdpClient::operator=(UdpClient&& o) noexcept {
  if (this != &o) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = o.fd_;
    o.fd_ = -1;
  }
  return *this;
}

UdpClient::~UdpClient() {
  if (fd_ >= 0) ::close(fd_);
}

Result<void> UdpClient::send(std::span<const std::byte> d) {
  for (;;) {
    const ssize_t n = ::send(fd_, d.data(), d.size(), 0);
    if (n == static_cast<ssize_t>(d.size())) return ok();
    if (n < 0 && errno == EINTR) continue;
    // A previous datagram's ICMP error surfaces here: the server is not there (yet).
    if (n < 0 && errno == ECONNREFUSED) return Error(CoreErrc::io, "send: connection refused (no server on that port)");
    return sys_error("send");
  }
}

Result<std::size_t> UdpClient::receive(std::span<std::byte> buffer, Clock::time_point deadline) {
  for (;;) {
    const auto left = deadline - Clock::now();
    if (left <= Clock::duration::zero()) return std::size_t{0};
    timespec ts{};
    const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(left).count();
    ts.tv_sec = static_cast<time_t>(ns / 1000000000);
    ts.tv_nsec = static_cast<long>(ns % 1000000000);
    pollfd p{fd_, POLLIN, 0};
    const int rc = ::ppoll(&p, 1, &ts, nullptr);
    if (rc < 0 && errno == EINTR) continue;
    if (rc < 0) return sys_error("poll");
    if (rc == 0) return std::size_t{0};
    const ssize_t n = ::recv(fd_, buffer.data(), buffer.size(), MSG_TRUNC);
    if (n < 0 && (errno == EINTR || errno == EAGAIN || errno == ECONNREFUSED)) continue;
    if (n < 0) return sys_error("recv");
    if (n == 0) continue;  // an empty datagram: nothing to judge
    return static_cast<std::size_t>(n);
  }
}

std::size_t UdpClient::drain(std::span<std::byte> scratch) {
  std::size_t n = 0;
  for (;;) {
    const ssize_t r = ::recv(fd_, scratch.data(), scratch.size(), MSG_DONTWAIT);
    if (r < 0 && errno == ECONNREFUSED) continue;
    if (r < 0) return n;
    ++n;
  }
}

net::Endpoint UdpClient::local_endpoint() const {
  sockaddr_storage a{};
  socklen_t len = sizeof a;
  net::Endpoint ep;
  if (::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len) != 0) return ep;
  char host[INET6_ADDRSTRLEN] = {};
  if (a.ss_family == AF_INET) {
    const auto* in = reinterpret_cast<const sockaddr_in*>(&a);
    ::inet_ntop(AF_INET, &in->sin_addr, host, sizeof host);
    ep.port = ntohs(in->sin_port);
  } else if (a.ss_family == AF_INET6) {
    const auto* in = reinterpret_cast<const sockaddr_in6*>(&a);
    ::inet_ntop(AF_INET6, &in->sin6_addr, host, sizeof host);
    ep.port = ntohs(in->sin6_port);
  }
  ep.host = host;
  return ep;
}

}  // namespace axon::c4g::sim
