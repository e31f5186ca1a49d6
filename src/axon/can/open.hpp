// Opening a bus from its specification (can/bus_spec.hpp), whatever the transport.
#pragma once

#include "axon/can/bus.hpp"
#include "axon/can/bus_spec.hpp"
#include "axon/can/provider.hpp"

#include <chrono>
#include <memory>
#include <vector>

namespace axon::can {

struct OpenOptions {
  BusOptions bus{};
  core::Duration connect_timeout = std::chrono::seconds(5);
  // Where virtual:NAME buses live; they exist only inside one process.
  BusProvider* local = nullptr;
};

asio::awaitable<Result<std::unique_ptr<Bus>>> open_bus(asio::any_io_executor ex, const BusSpec& spec,
                                                       OpenOptions options = {});

// CanErrc::bad_spec naming both specs when two of them are the same bus (however written).
Result<void> check_distinct(const std::vector<BusSpec>& specs);

// Opens several buses, in the order given. Channels of one CAN@net gateway (same address and port,
// host names resolved first: "localhost" and "127.0.0.1" are one gateway) share one connection: the gateway serves one client at a time, so a second connection would
// take it over and close the first (and its buses). The same bus listed twice is CanErrc::bad_spec.
// On any failure every bus opened so far is closed and the error names the spec.
asio::awaitable<Result<std::vector<std::unique_ptr<Bus>>>> open_buses(asio::any_io_executor ex,
                                                                      std::vector<BusSpec> specs,
                                                                      OpenOptions options = {});

}  // namespace axon::can
