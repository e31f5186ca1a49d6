// Opening a bus from its specification (can/bus_spec.hpp), whatever the transport.
#pragma once

#include "can/bus.hpp"
#include "can/bus_spec.hpp"
#include "can/provider.hpp"

#include <chrono>
#include <memory>

namespace axon::can {

struct OpenOptions {
  BusOptions bus{};
  core::Duration connect_timeout = std::chrono::seconds(5);
  // Where virtual:NAME buses live; they exist only inside one process.
  BusProvider* local = nullptr;
};

asio::awaitable<Result<std::unique_ptr<Bus>>> open_bus(asio::any_io_executor ex, const BusSpec& spec,
                                                       OpenOptions options = {});

}  // namespace axon::can
