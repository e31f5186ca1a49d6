#include "axon/net/udp_socket.hpp"

#include <arpa/inet.h>
#include <fmt/format.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/ip.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <utility>

namespace axon::net {

namespace {

std::int64_t clock_ns(clockid_t id) noexcept {
  timespec ts{};
  clock_gettime(id, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

sockaddr_in to_sockaddr(const SocketAddress& a) noexcept {
  sockaddr_in sa{};
  sa.sin_family = AF_INET;
  sa.sin_addr.s_addr = htonl(a.ip);
  sa.sin_port = htons(a.port);
  return sa;
}

SocketAddress from_sockaddr(const sockaddr_in& sa) noexcept {
  return SocketAddress{ntohl(sa.sin_addr.s_addr), ntohs(sa.sin_port)};
}

Error sys_error(NetErrc code, std::string_view what, int err) {
  return Error(code, fmt::format("{}: {}", what, std::strerror(err)));
}

inline void cpu_relax() noexcept {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}

}  // namespace

std::string SocketAddress::to_string() const {
  return fmt::format("{}.{}.{}.{}:{}", (ip >> 24) & 0xff, (ip >> 16) & 0xff, (ip >> 8) & 0xff, ip & 0xff, port);
}

Result<SocketAddress> resolve_ipv4(const Endpoint& endpoint) {
  if (endpoint.host.empty() || endpoint.host == "*" || endpoint.host == "0.0.0.0")
    return SocketAddress{0, endpoint.port};
  in_addr addr{};
  if (inet_pton(AF_INET, endpoint.host.c_str(), &addr) == 1) return SocketAddress{ntohl(addr.s_addr), endpoint.port};
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_DGRAM;
  addrinfo* list = nullptr;
  const int rc = getaddrinfo(endpoint.host.c_str(), nullptr, &hints, &list);
  if (rc != 0 || list == nullptr)
    return Error(NetErrc::resolve_failed, fmt::format("'{}': {}", endpoint.host, gai_strerror(rc)));
  SocketAddress out{ntohl(reinterpret_cast<const sockaddr_in*>(list->ai_addr)->sin_addr.s_addr), endpoint.port};
  freeaddrinfo(list);
  return out;
}

Result<UdpSocket> UdpSocket::open(const Endpoint& local, const UdpOptions& options) {
  AXON_TRY(addr, resolve_ipv4(local));
  return open(addr, options);
}

Result<UdpSocket> UdpSocket::open(const SocketAddress& local, const UdpOptions& options) {
  UdpSocket s;
  s.options_ = options;
  s.shared_ = std::make_unique<Shared>();
  s.fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (s.fd_ < 0) return sys_error(NetErrc::socket_failed, "socket(AF_INET, SOCK_DGRAM)", errno);
  s.wake_fd_ = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (s.wake_fd_ < 0) return sys_error(NetErrc::socket_failed, "eventfd", errno);

  auto set = [&](int level, int name, int value, const char* what) -> Result<void> {
    if (::setsockopt(s.fd_, level, name, &value, sizeof value) != 0)
      return sys_error(NetErrc::socket_failed, fmt::format("setsockopt({}, {})", what, value), errno);
    return ok();
  };
  if (options.reuse_address) {
    AXON_TRY(set(SOL_SOCKET, SO_REUSEADDR, 1, "SO_REUSEADDR"));
  }
  if (options.receive_buffer_bytes > 0) {
    AXON_TRY(set(SOL_SOCKET, SO_RCVBUF, options.receive_buffer_bytes, "SO_RCVBUF"));
  }
  if (options.send_buffer_bytes > 0) {
    AXON_TRY(set(SOL_SOCKET, SO_SNDBUF, options.send_buffer_bytes, "SO_SNDBUF"));
  }
  if (options.socket_priority >= 0) {
    AXON_TRY(set(SOL_SOCKET, SO_PRIORITY, options.socket_priority, "SO_PRIORITY"));
  }
  if (options.tos >= 0) {
    AXON_TRY(set(IPPROTO_IP, IP_TOS, options.tos, "IP_TOS"));
  }
  {
    const int one = 1;
    // Destination address per datagram, so a socket bound to any address knows which one was hit.
    (void)::setsockopt(s.fd_, IPPROTO_IP, IP_PKTINFO, &one, sizeof one);
  }
  if (options.kernel_timestamps) {
    const int one = 1;
    // A refusal is not fatal: arrival times then come from the clock at return.
    s.kernel_timestamps_ = ::setsockopt(s.fd_, SOL_SOCKET, SO_TIMESTAMPNS, &one, sizeof one) == 0;
  }

  const sockaddr_in sa = to_sockaddr(local);
  if (::bind(s.fd_, reinterpret_cast<const sockaddr*>(&sa), sizeof sa) != 0)
    return sys_error(NetErrc::bind_failed, fmt::format("bind {}", local.to_string()), errno);
  sockaddr_in bound{};
  socklen_t len = sizeof bound;
  if (::getsockname(s.fd_, reinterpret_cast<sockaddr*>(&bound), &len) != 0)
    return sys_error(NetErrc::socket_failed, "getsockname", errno);
  s.local_ = from_sockaddr(bound);
  return s;
}

UdpSocket::UdpSocket(UdpSocket&& o) noexcept
    : fd_(std::exchange(o.fd_, -1)),
      wake_fd_(std::exchange(o.wake_fd_, -1)),
      local_(o.local_),
      options_(o.options_),
      kernel_timestamps_(o.kernel_timestamps_),
      peer_(o.peer_),
      shared_(std::move(o.shared_)) {}

UdpSocket& UdpSocket::operator=(UdpSocket&& o) noexcept {
  if (this != &o) {
    close();
    fd_ = std::exchange(o.fd_, -1);
    wake_fd_ = std::exchange(o.wake_fd_, -1);
    local_ = o.local_;
    options_ = o.options_;
    kernel_timestamps_ = o.kernel_timestamps_;
    peer_ = o.peer_;
    shared_ = std::move(o.shared_);
  }
  return *this;
}

UdpSocket::~UdpSocket() { close(); }

void UdpSocket::close() noexcept {
  if (fd_ >= 0) ::close(std::exchange(fd_, -1));
  if (wake_fd_ >= 0) ::close(std::exchange(wake_fd_, -1));
}

void UdpSocket::interrupt() noexcept {
  if (!shared_) return;
  shared_->interrupted.store(true, std::memory_order_release);
  if (wake_fd_ >= 0) {
    const std::uint64_t one = 1;
    [[maybe_unused]] auto n = ::write(wake_fd_, &one, sizeof one);
  }
}

void UdpSocket::clear_interrupt() noexcept {
  if (!shared_) return;
  shared_->interrupted.store(false, std::memory_order_release);
  if (wake_fd_ >= 0) {
    std::uint64_t v = 0;
    [[maybe_unused]] auto n = ::read(wake_fd_, &v, sizeof v);
  }
}

Result<Datagram> UdpSocket::receive_ready(std::span<std::byte> buffer) {
  sockaddr_in from{};
  iovec iov{buffer.data(), buffer.size()};
  // Room for SCM_TIMESTAMPNS and IP_PKTINFO; on the stack, so nothing is allocated per packet.
  alignas(cmsghdr) unsigned char control[CMSG_SPACE(sizeof(timespec)) + CMSG_SPACE(sizeof(in_pktinfo))];
  msghdr msg{};
  msg.msg_name = &from;
  msg.msg_namelen = sizeof from;
  msg.msg_iov = &iov;
  msg.msg_iovlen = 1;
  msg.msg_control = control;
  msg.msg_controllen = sizeof control;
  // MSG_TRUNC makes the kernel report the datagram's real length even when it did not fit.
  const ssize_t n = ::recvmsg(fd_, &msg, MSG_DONTWAIT | MSG_TRUNC);
  if (n < 0) {
    if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return Error(NetErrc::timeout);
    shared_->counters.receive_errors.fetch_add(1, std::memory_order_relaxed);
    return sys_error(NetErrc::receive_failed, "recvmsg", errno);
  }
  Datagram d;
  d.steady_ns = clock_ns(CLOCK_MONOTONIC);
  const std::int64_t wall_now = clock_ns(CLOCK_REALTIME);
  d.wire_size = static_cast<std::size_t>(n);
  d.size = std::min(d.wire_size, buffer.size());
  d.from = from_sockaddr(from);
  d.to = local_;
  d.wall_ns = wall_now;
  for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
    if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS) {
      timespec ts{};
      std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
      d.wall_ns = static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
      d.kernel_timestamp = true;
      d.wakeup_latency_ns = wall_now - d.wall_ns;
    } else if (c->cmsg_level == IPPROTO_IP && c->cmsg_type == IP_PKTINFO) {
      in_pktinfo info{};
      std::memcpy(&info, CMSG_DATA(c), sizeof info);
      d.to.ip = ntohl(info.ipi_addr.s_addr);
    }
  }
  peer_ = d.from;
  shared_->counters.received.fetch_add(1, std::memory_order_relaxed);
  if (d.truncated()) shared_->counters.truncated.fetch_add(1, std::memory_order_relaxed);
  return d;
}

Result<Datagram> UdpSocket::receive(std::span<std::byte> buffer, std::chrono::nanoseconds timeout) {
  if (fd_ < 0) return Error(NetErrc::closed);
  const bool forever = timeout.count() < 0;
  const std::int64_t deadline = forever ? 0 : clock_ns(CLOCK_MONOTONIC) + timeout.count();
  for (;;) {
    if (shared_->interrupted.load(std::memory_order_acquire)) return Error(NetErrc::interrupted);
    auto r = receive_ready(buffer);
    if (r || r.error() != NetErrc::timeout) return r;
    const std::int64_t now = clock_ns(CLOCK_MONOTONIC);
    if (!forever && now >= deadline) {
      shared_->counters.timeouts.fetch_add(1, std::memory_order_relaxed);
      return Error(NetErrc::timeout);
    }
    if (options_.busy_poll) {
      cpu_relax();
      continue;
    }
    pollfd fds[2] = {{fd_, POLLIN, 0}, {wake_fd_, POLLIN, 0}};
    timespec ts{};
    if (!forever) {
      const std::int64_t left = deadline - now;
      ts.tv_sec = static_cast<time_t>(left / 1'000'000'000);
      ts.tv_nsec = static_cast<long>(left % 1'000'000'000);
    }
    const int rc = ::ppoll(fds, 2, forever ? nullptr : &ts, nullptr);
    if (rc < 0 && errno != EINTR) {
      shared_->counters.receive_errors.fetch_add(1, std::memory_order_relaxed);
      return sys_error(NetErrc::receive_failed, "ppoll", errno);
    }
    // Loop: either data is ready, the wake-up fd fired, or the deadline passed.
  }
}

Result<void> UdpSocket::send_to(std::span<const std::byte> payload, const SocketAddress& to) {
  if (fd_ < 0) return Error(NetErrc::closed);
  const sockaddr_in sa = to_sockaddr(to);
  ssize_t n;
  do {
    n = ::sendto(fd_, payload.data(), payload.size(), 0, reinterpret_cast<const sockaddr*>(&sa), sizeof sa);
  } while (n < 0 && errno == EINTR);
  if (n < 0) {
    shared_->counters.send_errors.fetch_add(1, std::memory_order_relaxed);
    return sys_error(NetErrc::send_failed, fmt::format("sendto {}", to.to_string()), errno);
  }
  if (static_cast<std::size_t>(n) != payload.size()) {
    shared_->counters.send_errors.fetch_add(1, std::memory_order_relaxed);
    return Error(NetErrc::send_failed, fmt::format("sendto {}: {} of {} bytes sent", to.to_string(), n, payload.size()));
  }
  shared_->counters.sent.fetch_add(1, std::memory_order_relaxed);
  return ok();
}

Result<void> UdpSocket::reply(std::span<const std::byte> payload) {
  if (!peer_) return Error(NetErrc::no_peer);
  return send_to(payload, *peer_);
}

}  // namespace axon::net
