// UdpRelay: a UDP relay on loopback between a client and a server, for fault injection. The client
// sends to port() instead of the server; every datagram goes through a hook, which forwards it as
// it is, changed, twice, later, or not at all (to_server(), to_client()). One thread of its own
// runs the sockets and the hooks; tick() runs on it at least once a millisecond.
//
// Used by the c4g tests (malformed, reordered, duplicated datagrams) and the c4g soak (random
// loss, duplication and reordering with every reply checked).
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <thread>

#include <netinet/in.h>

namespace axon::net {

class UdpRelay {
 public:
  using Hook = std::function<void(UdpRelay&, std::span<const std::byte>)>;
  struct Hooks {
    Hook from_client;              // default: to_server()
    Hook from_server;              // default: to_client()
    std::function<void()> tick;    // optional
  };

  // Binds two sockets on 127.0.0.1 (ephemeral ports) and starts the thread. Throws axon::Exception
  // (CoreErrc::io) when a socket cannot be opened or bound.
  UdpRelay(std::uint16_t server_port, Hooks hooks);
  ~UdpRelay();  // stops the thread, closes the sockets
  UdpRelay(const UdpRelay&) = delete;
  UdpRelay& operator=(const UdpRelay&) = delete;

  // Where the client sends.
  [[nodiscard]] std::uint16_t port() const;
  // From the relay's thread (the hooks): forward a datagram.
  void to_server(std::span<const std::byte> d);
  void to_client(std::span<const std::byte> d);  // to the address the client last sent from

 private:
  void loop();

  Hooks hooks_;
  int client_side_ = -1;  // the client sends here
  int server_side_ = -1;  // the server answers here
  sockaddr_in server_{};
  sockaddr_in client_{};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace axon::net
