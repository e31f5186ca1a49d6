#include "axon/net/udp_echo.hpp"

#include "axon/net/error.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace axon::net {

Result<std::unique_ptr<UdpEchoServer>> UdpEchoServer::start() {
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return Error(CoreErrc::io, std::string("echo socket: ") + std::strerror(errno));
  sockaddr_in sa{};
  sa.sin_family = AF_INET;
  sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof sa;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&sa), sizeof sa) != 0 ||
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&sa), &len) != 0) {
    const int e = errno;
    ::close(fd);
    return Error(CoreErrc::io, std::string("echo bind: ") + std::strerror(e));
  }
  return std::unique_ptr<UdpEchoServer>(new UdpEchoServer(fd, SocketAddress{ntohl(sa.sin_addr.s_addr), ntohs(sa.sin_port)}));
}

UdpEchoServer::UdpEchoServer(int fd, SocketAddress address) : fd_(fd), address_(address) {
  thread_ = std::thread([this] { run(); });
}

UdpEchoServer::~UdpEchoServer() { stop(); }

void UdpEchoServer::stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

void UdpEchoServer::run() {
  char buf[2048];
  while (!stop_) {
    pollfd pf{fd_, POLLIN, 0};
    if (::poll(&pf, 1, 50) <= 0) continue;
    sockaddr_in from{};
    socklen_t fl = sizeof from;
    const auto n = ::recvfrom(fd_, buf, sizeof buf, 0, reinterpret_cast<sockaddr*>(&from), &fl);
    if (n <= 0) continue;
    if (::sendto(fd_, buf, static_cast<std::size_t>(n), 0, reinterpret_cast<sockaddr*>(&from), fl) == n) ++echoed_;
  }
}

}  // namespace axon::net
