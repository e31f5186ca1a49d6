// The baseline that c4g round-trip figures are measured against (DESIGN.md: "a minimal C UDP echo
// server on the same sockets"): a plain blocking socket on its own thread that sends every datagram
// straight back to its sender. Nothing of axon's server (decode, safety, timing) is in the path,
// so server time / echo time shows what the server adds on this machine, in this run.
#pragma once

#include "axon/core/error.hpp"
#include "axon/net/udp_socket.hpp"

#include <atomic>
#include <memory>
#include <thread>

namespace axon::net {

class UdpEchoServer {
 public:
  // Binds 127.0.0.1 on a free port and starts echoing.
  static Result<std::unique_ptr<UdpEchoServer>> start();
  ~UdpEchoServer();
  UdpEchoServer(const UdpEchoServer&) = delete;
  UdpEchoServer& operator=(const UdpEchoServer&) = delete;

  [[nodiscard]] SocketAddress address() const noexcept { return address_; }
  [[nodiscard]] std::uint64_t echoed() const noexcept { return echoed_.load(); }
  void stop();

 private:
  UdpEchoServer(int fd, SocketAddress address);
  void run();

  int fd_;
  SocketAddress address_;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> echoed_{0};
  std::thread thread_;
};

}  // namespace axon::net
