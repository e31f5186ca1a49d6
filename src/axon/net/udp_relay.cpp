#include "axon/net/udp_relay.hpp"

#include "axon/core/error.hpp"

#include <arpa/inet.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <string>

namespace axon::net {
namespace {

int bind_loopback() {
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (fd < 0 || ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    const std::string why = std::strerror(errno);
    if (fd >= 0) ::close(fd);
    throw Exception(Error(CoreErrc::io, "UDP relay: cannot bind a loopback socket: " + why));
  }
  return fd;
}

void send_to(int fd, const sockaddr_in& to, std::span<const std::byte> d) {
  (void)::sendto(fd, d.data(), d.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to);
}

}  // namespace

UdpRelay::UdpRelay(std::uint16_t server_port, Hooks hooks) : hooks_(std::move(hooks)) {
  if (!hooks_.from_client) hooks_.from_client = [](UdpRelay& r, std::span<const std::byte> d) { r.to_server(d); };
  if (!hooks_.from_server) hooks_.from_server = [](UdpRelay& r, std::span<const std::byte> d) { r.to_client(d); };
  client_side_ = bind_loopback();
  try {
    server_side_ = bind_loopback();
  } catch (...) {
    ::close(client_side_);
    throw;
  }
  server_.sin_family = AF_INET;
  server_.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  server_.sin_port = htons(server_port);
  thread_ = std::thread([this] { loop(); });
}

UdpRelay::~UdpRelay() {
  stop_ = true;
  thread_.join();
  ::close(client_side_);
  ::close(server_side_);
}

std::uint16_t UdpRelay::port() const {
  sockaddr_in a{};
  socklen_t len = sizeof a;
  ::getsockname(client_side_, reinterpret_cast<sockaddr*>(&a), &len);
  return ntohs(a.sin_port);
}

void UdpRelay::to_server(std::span<const std::byte> d) { send_to(server_side_, server_, d); }
void UdpRelay::to_client(std::span<const std::byte> d) { send_to(client_side_, client_, d); }

void UdpRelay::loop() {
  std::array<std::byte, 2048> buf{};
  while (!stop_) {
    pollfd p[2] = {{client_side_, POLLIN, 0}, {server_side_, POLLIN, 0}};
    const int n = ::poll(p, 2, 1);
    if (hooks_.tick) hooks_.tick();
    if (n <= 0) continue;
    if ((p[0].revents & POLLIN) != 0) {
      socklen_t len = sizeof client_;
      const auto got = ::recvfrom(client_side_, buf.data(), buf.size(), 0, reinterpret_cast<sockaddr*>(&client_), &len);
      if (got > 0) hooks_.from_client(*this, {buf.data(), static_cast<std::size_t>(got)});
    }
    if ((p[1].revents & POLLIN) != 0) {
      const auto got = ::recvfrom(server_side_, buf.data(), buf.size(), 0, nullptr, nullptr);
      if (got > 0) hooks_.from_server(*this, {buf.data(), static_cast<std::size_t>(got)});  // errors: a refused send
    }
  }
}

}  // namespace axon::net
