// A receive() still waiting when its bus goes away must not touch the destroyed bus: neither when
// the io_context goes next (a program torn down with work pending) nor when the loop runs on and
// resumes it (a reader woken by close() whose owner dropped the bus before the loop ran again).
// The sanitizer build turns a violation into a failure (heap-use-after-free).
#include "axon/can/cannet_client.hpp"
#include "axon/can/cannet_server.hpp"
#include "axon/can/error.hpp"
#include "axon/can/socketcand_client.hpp"
#include "axon/can/socketcand_server.hpp"
#include "axon/can/virtual_bus.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/io_context.hpp>
#include <gtest/gtest.h>

#include <memory>
#include <optional>
#include <system_error>

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

namespace {

enum class Ending { close_then_destroy, destroy_only };

// Parks a reader in bus->receive(), ends the bus as `ending` says before the loop runs again, then
// runs the loop: the reader must resume and end with `closed`, without reading the freed bus.
void expect_parked_reader_survives(asio::io_context& io, std::unique_ptr<can::Bus> bus, Ending ending) {
  std::optional<std::error_code> got;
  asio::co_spawn(
      io,
      [b = bus.get(), &got]() -> asio::awaitable<void> {
        auto r = co_await b->receive();
        got = r ? std::error_code() : r.error().code;
      },
      asio::detached);
  io.poll();
  ASSERT_FALSE(got) << "the reader should be parked in receive()";
  if (ending == Ending::close_then_destroy) bus->close();
  bus.reset();
  io.poll();
  ASSERT_TRUE(got) << "the reader was not woken when its bus went";
  EXPECT_EQ(*got, can::CanErrc::closed);
}

// Runs `connect` on `io` until it has handed over its bus.
template <class Connect>
std::unique_ptr<can::Bus> connected(asio::io_context& io, Connect connect) {
  std::unique_ptr<can::Bus> bus;
  asio::co_spawn(
      io,
      [&bus, connect]() -> asio::awaitable<void> {
        auto b = co_await connect();
        if (b) bus = std::move(b).value();
        else ADD_FAILURE() << b.error().message();
      },
      asio::detached);
  for (int i = 0; i < 1000 && !bus; ++i) io.run_one_for(std::chrono::milliseconds(10));
  return bus;
}

TEST(BusLifetime, ReaderWokenByCloseResumesAfterItsVirtualBusIsGone) {
  asio::io_context io;
  auto medium = can::VirtualBus::create(io.get_executor(), "vcan0");
  expect_parked_reader_survives(io, medium->attach("host"), Ending::close_then_destroy);
}

TEST(BusLifetime, ReaderParkedOnADestroyedBusEndsWithClosed) {
  asio::io_context io;
  auto medium = can::VirtualBus::create(io.get_executor(), "vcan0");
  expect_parked_reader_survives(io, medium->attach("host"), Ending::destroy_only);
}

TEST(BusLifetime, ReaderWokenByCloseResumesAfterItsSocketcandBusIsGone) {
  asio::io_context io;
  can::VirtualBusRegistry registry(io.get_executor());
  ASSERT_TRUE(registry.add("vcan0"));
  can::SocketcandServer server(io.get_executor(), registry, net::Endpoint{"127.0.0.1", 0});
  const auto ep = server.local_endpoint();
  auto bus = connected(io, [ex = io.get_executor(), ep]() -> asio::awaitable<Result<std::unique_ptr<can::Bus>>> {
    auto r = co_await can::SocketcandBus::connect(ex, ep, "vcan0");
    if (!r) co_return r.error();
    co_return std::unique_ptr<can::Bus>(std::move(r).value());
  });
  ASSERT_TRUE(bus);
  expect_parked_reader_survives(io, std::move(bus), Ending::close_then_destroy);
  server.stop();
}

TEST(BusLifetime, ReaderWokenByCloseResumesAfterItsCanNetBusIsGone) {
  asio::io_context io;
  can::VirtualBusRegistry registry(io.get_executor());
  ASSERT_TRUE(registry.add("can0"));
  can::CanNetEmulatorOptions options;
  options.port = 0;
  can::CanNetGatewayEmulator emulator(io.get_executor(), registry, std::vector<std::string>{"can0"}, options);
  ASSERT_TRUE(emulator.start());
  const auto ep = emulator.local_endpoint();
  auto bus = connected(io, [ex = io.get_executor(), ep]() -> asio::awaitable<Result<std::unique_ptr<can::Bus>>> {
    std::vector<int> channels{1};  // named: gcc 12 cannot keep a braced list alive across co_await
    const can::CanNetOptions no_options;
    auto g = co_await can::CanNetGateway::connect(ex, ep, channels, no_options);
    if (!g) co_return g.error();
    co_return g.value()->bus(1);
  });
  ASSERT_TRUE(bus);
  expect_parked_reader_survives(io, std::move(bus), Ending::close_then_destroy);
}

}  // namespace
