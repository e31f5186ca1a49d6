#include "axon/can/relay.hpp"

#include <spdlog/spdlog.h>

namespace axon::can {

asio::awaitable<void> relay(Bus& from, Bus& to, RelayStats& stats) {
  for (;;) {
    auto f = co_await from.receive();
    if (!f) co_return;  // closed
    auto r = co_await to.send(f.value());
    if (r) {
      ++stats.forwarded;
    } else {
      if (stats.failed++ == 0)
        spdlog::warn("relay {} -> {}: {} (further failures only counted)", from.name(), to.name(), r.error().message());
      if (r.error() == CanErrc::closed) co_return;
    }
  }
}

}  // namespace axon::can
