// Forwarding frames from one bus to another: what bridges and gateways do in between.
#pragma once

#include "axon/can/bus.hpp"

#include <cstdint>

namespace axon::can {

struct RelayStats {
  std::uint64_t forwarded = 0;
  std::uint64_t failed = 0;  // frames the destination refused (logged once each kind)
};

// Forwards every frame received on `from` to `to` until `from` closes. Frames `to` refuses are
// counted (never silently): the caller sees them in `stats`. Both buses must share an executor.
asio::awaitable<void> relay(Bus& from, Bus& to, RelayStats& stats);

}  // namespace axon::can
