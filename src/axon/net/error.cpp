#include "axon/net/error.hpp"

namespace axon::net {

namespace {
class NetCategory final : public std::error_category {
 public:
  const char* name() const noexcept override { return "axon.net"; }
  std::string message(int c) const override {
    switch (static_cast<NetErrc>(c)) {
      case NetErrc::resolve_failed: return "address does not resolve to IPv4; give a dotted address or a known host name";
      case NetErrc::socket_failed: return "socket could not be created or configured; check limits and permissions";
      case NetErrc::bind_failed: return "cannot bind the local address; is another server running, and is the address on this host?";
      case NetErrc::timeout: return "no packet within the timeout; check that the peer runs and sends to this address";
      case NetErrc::interrupted: return "wait interrupted by the owner";
      case NetErrc::receive_failed: return "receiving a datagram failed";
      case NetErrc::send_failed: return "sending a datagram failed; check the route to the peer";
      case NetErrc::no_peer: return "no peer yet: nothing has been received to reply to";
      case NetErrc::closed: return "socket closed";
    }
    return "unknown net error";
  }
};
}  // namespace

const std::error_category& net_category() noexcept {
  static const NetCategory c;
  return c;
}

}  // namespace axon::net
