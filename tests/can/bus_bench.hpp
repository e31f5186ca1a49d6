// Test support for the hostile-peer tests of the CAN servers: one virtual bus, can0, on a loop
// thread of its own, with an endpoint (the tap) through which a test puts frames on it. A server
// under test is made on the loop by the derived bench, which destroys it there too.
#pragma once

#include "axon/can/virtual_bus.hpp"
#include "axon/core/loop_thread.hpp"

#include <boost/asio/post.hpp>
#include <boost/asio/use_awaitable.hpp>

#include <chrono>
#include <cstdint>
#include <memory>

namespace axon::can::test {

struct BusBench {
  core::LoopThread loop;
  std::unique_ptr<VirtualBusRegistry> registry;
  std::unique_ptr<Bus> tap;

  BusBench() {
    loop.call([&] {
      registry = std::make_unique<VirtualBusRegistry>(loop.executor());
      registry->add("can0").value();
      tap = registry->open("can0").value();
    });
  }
  ~BusBench() {
    loop.call([&] { tap->close(); });
    loop.stop();
  }
  BusBench(const BusBench&) = delete;
  BusBench& operator=(const BusBench&) = delete;

  // Puts n frames on can0 from the tap.
  void flood(int n) {
    loop.run(
        [&]() -> asio::awaitable<void> {
          const std::uint8_t data[8] = {1, 2, 3, 4, 5, 6, 7, 8};
          for (int i = 0; i < n;) {  // a full transmit queue: let the bus take what it has, then retry
            if (co_await tap->send(Frame::standard(0x123, data).value())) ++i;
            else co_await asio::post(loop.executor(), asio::use_awaitable);
          }
        },
        std::chrono::seconds(30));
  }
};

}  // namespace axon::can::test
