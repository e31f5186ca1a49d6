// Something that hands out bus endpoints by channel name: what the socketcand and CAN@net servers
// serve. Each call to open() gives a new, independent endpoint (its own receive queue and
// filters), the way every client of socketcand gets its own raw socket on the interface.
#pragma once

#include "axon/can/bus.hpp"

#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace axon::can {

class BusProvider {
 public:
  virtual ~BusProvider() = default;
  // A new endpoint on the named channel; CanErrc::bad_spec if there is no such channel.
  virtual Result<std::unique_ptr<Bus>> open(std::string_view channel, BusOptions options = {}) = 0;
  // The channel names this provider serves, in order.
  [[nodiscard]] virtual std::vector<std::string> channels() const = 0;
};

}  // namespace axon::can
