// A receive() still waiting when its bus and then its io_context go away (a program torn down with
// work pending) must not touch the destroyed bus. The sanitizer build turns a violation into a failure.
#include "axon/can/virtual_bus.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/io_context.hpp>
#include <gtest/gtest.h>

#include <memory>

using namespace axon;
namespace asio = boost::asio;

TEST(BusLifetime, WaitingReceiverOutlivesItsBus) {
  auto io = std::make_unique<asio::io_context>();
  auto medium = can::VirtualBus::create(io->get_executor(), "vcan0");
  auto node = medium->attach("host");
  bool resumed = false;
  asio::co_spawn(
      *io,
      [&node, &resumed]() -> asio::awaitable<void> {
        (void)co_await node->receive();
        resumed = true;
      },
      asio::detached);
  io->poll();  // the coroutine starts and parks in receive()
  EXPECT_FALSE(resumed);
  node.reset();    // the bus goes first ...
  medium.reset();
  io.reset();      // ... then the io_context destroys the parked coroutine
  EXPECT_FALSE(resumed);
}
