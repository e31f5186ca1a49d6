// Error codes of the net layer (UDP sockets for real-time loops, address resolution).
#pragma once

#include "axon/core/error.hpp"

namespace axon::net {

enum class NetErrc {
  resolve_failed = 1,  // a host name or address that does not resolve to an IPv4 address
  socket_failed,       // socket() or a socket option was refused
  bind_failed,         // the local address is in use or not ours
  timeout,             // nothing arrived within the timeout
  interrupted,         // interrupt() was called: the owner asked the waiting thread to return
  receive_failed,      // recvmsg() failed
  send_failed,         // sendto() failed or sent fewer bytes than asked
  no_peer,             // a reply was asked for before anything was received
  closed,              // the socket was closed
};

const std::error_category& net_category() noexcept;
inline std::error_code make_error_code(NetErrc e) noexcept { return {static_cast<int>(e), net_category()}; }

}  // namespace axon::net

template <>
struct std::is_error_code_enum<axon::net::NetErrc> : std::true_type {};
