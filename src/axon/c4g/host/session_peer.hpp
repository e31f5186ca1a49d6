// Whom the Server's session belongs to: the one controller address whose packets it answers.
//
// The open interface has no authentication: any host that can reach the server's port can send a
// packet of the cyclic size. A session is therefore bound to one source address and port, and
// every datagram from anywhere else is foreign: counted, never answered, and it changes nothing
// (no reply, no safety latch, no timing sample, no capture).
//
// The peer comes from the allowed set (ServerOptions::controller: a host and port, a host with any
// port, or anyone) and is fixed by the first well-formed packet from that set: a cyclic-sized
// packet that decodes (the controller's sync packets come before its initialization packet and
// must be answered from the first one on, field notes) or an initialization packet that decodes.
// Malformed datagrams never choose the peer. The session ends when the peer has been silent for
// the cycle timeout (the controller stopped or restarted, possibly from another port); the next
// well-formed packet from the allowed set then starts a new one.
//
// Threads: the cycle thread decides (matches, learn, forget); any thread may read current().
#pragma once

#include "axon/net/udp_socket.hpp"

#include <atomic>
#include <cstdint>
#include <optional>

namespace axon::c4g::host {

class SessionPeer {
 public:
  // `allowed`: ip 0 = any host, port 0 = any port (so {} allows anyone).
  explicit SessionPeer(net::SocketAddress allowed = {}) noexcept : allowed_(allowed) {}

  [[nodiscard]] const net::SocketAddress& allowed() const noexcept { return allowed_; }
  // The source may start a session (it is in the allowed set).
  [[nodiscard]] bool admits(const net::SocketAddress& from) const noexcept {
    return (allowed_.ip == 0 || allowed_.ip == from.ip) && (allowed_.port == 0 || allowed_.port == from.port);
  }
  [[nodiscard]] bool known() const noexcept { return packed_.load(std::memory_order_relaxed) != kNone; }
  // The datagram belongs to the session: the peer is known and it is the sender.
  [[nodiscard]] bool matches(const net::SocketAddress& from) const noexcept {
    return packed_.load(std::memory_order_relaxed) == pack(from);
  }
  void learn(const net::SocketAddress& from) noexcept { packed_.store(pack(from), std::memory_order_release); }
  void forget() noexcept { packed_.store(kNone, std::memory_order_release); }
  // The session's peer (any thread); nullopt while none.
  [[nodiscard]] std::optional<net::SocketAddress> current() const noexcept { return unpack(packed_.load(std::memory_order_acquire)); }

  // An address in one atomic word (bit 48 set: an address is there).
  static constexpr std::uint64_t kNone = 0;
  static constexpr std::uint64_t pack(const net::SocketAddress& a) noexcept {
    return (std::uint64_t{1} << 48) | (std::uint64_t{a.ip} << 16) | a.port;
  }
  static constexpr std::optional<net::SocketAddress> unpack(std::uint64_t v) noexcept {
    if (v == kNone) return std::nullopt;
    return net::SocketAddress{static_cast<std::uint32_t>(v >> 16), static_cast<std::uint16_t>(v & 0xffff)};
  }

 private:
  net::SocketAddress allowed_;
  std::atomic<std::uint64_t> packed_{kNone};
};

}  // namespace axon::c4g::host
