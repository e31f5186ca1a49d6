// Bus specifications: how users name a bus on the command line and in configuration files.
//
//   virtual:NAME                     an in-process virtual bus (simulators, bridge, tests)
//   socketcand://HOST[:PORT]/CHANNEL a socketcand daemon or `axon can bridge` (port 29536)
//   cannet://HOST[:PORT]/N           channel N (1..4) of a CAN@net NT gateway or its emulator (port 19228)
//   socketcan:IFACE                  a Linux SocketCAN interface (can0, vcan0)
//
// The same program drives simulated or real devices by changing only this string.
#pragma once

#include "axon/can/error.hpp"
#include "axon/net/endpoint.hpp"

#include <string>
#include <string_view>

namespace axon::can {

inline constexpr std::uint16_t kSocketcandPort = 29536;
inline constexpr std::uint16_t kCanNetPort = 19228;

struct BusSpec {
  enum class Kind : std::uint8_t { virtual_bus, socketcand, cannet, socketcan };
  Kind kind = Kind::virtual_bus;
  net::Endpoint endpoint;  // socketcand, cannet
  std::string channel;     // virtual bus name, socketcand channel, SocketCAN interface
  int cannet_channel = 0;  // 1..4 for cannet
  std::string text;        // as written

  [[nodiscard]] std::string to_string() const;
  // A short name for logs and candump files: the channel (vcan0, can0) or "cannetN".
  [[nodiscard]] std::string short_name() const;
};

Result<BusSpec> parse_bus_spec(std::string_view text);

}  // namespace axon::can
