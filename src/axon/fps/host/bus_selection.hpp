// Which CAN buses a host opens: a CAN@net gateway's channels, a socketcand server's channels, any
// bus spec (can/bus_spec.hpp), or all of them; from a program, the command line or a YAML bus file
// (gateway, channels, socketcand, channel, buses, timeout_ms). What is given directly wins over the
// file, and the file over the defaults (channel 1 of the gateway, can0 of socketcand, 1 s replies).
#pragma once

#include "axon/can/bus_spec.hpp"
#include "axon/core/error.hpp"

#include <string>
#include <vector>

namespace axon::fps::host {

// Empty lists and a negative timeout mean "not given".
struct BusSelection {
  std::string gateway;                    // CAN@net gateway HOST[:PORT]
  std::vector<int> channels;              // its channels, 1..4
  std::string socketcand;                 // socketcand server HOST[:PORT]
  std::vector<std::string> scd_channels;  // its channels (can0, ...)
  std::vector<std::string> buses;         // any bus specs
  double timeout_s = -1;                  // per reply

  // Fills what is not given from a bus file. Unknown keys, bad values and repeated channels are
  // errors located by file:line.
  [[nodiscard]] Result<void> apply_file(const std::string& path);
  // What is still not given, from the defaults.
  void apply_defaults();
  [[nodiscard]] bool empty() const noexcept { return gateway.empty() && socketcand.empty() && buses.empty(); }
  // The bus specs selected, in that order. Errors (CoreErrc::invalid_argument): nothing selected, a
  // spec or address that does not parse, one bus twice.
  [[nodiscard]] Result<std::vector<can::BusSpec>> specs() const;
};

}  // namespace axon::fps::host
