// Test rig for the blmc host: an io_context, a virtual bus with a host node and a scripted peer
// node (not a simulator: the test decides what the "board" answers to each frame).
#pragma once

#include "axon/blmc/protocol/frames.hpp"
#include "axon/can/virtual_bus.hpp"
#include "axon/core/wakeup.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/io_context.hpp>
#include <gtest/gtest.h>

#include <chrono>
#include <functional>
#include <memory>
#include <vector>

// ASSERT_* returns, which a coroutine cannot: this fails the test and co_returns instead.
#define CO_ASSERT(cond)                         \
  do {                                          \
    if (!(cond)) {                              \
      ADD_FAILURE() << "assertion failed: " #cond; \
      co_return;                                \
    }                                           \
  } while (0)

namespace axon::blmc::host::testing {

namespace asio = boost::asio;
using namespace std::chrono_literals;
namespace proto = axon::blmc::protocol;

inline can::Frame status_frame(bool sys, bool m1e, bool m1r, bool m2e, bool m2r,
                               proto::ErrorCode e = proto::ErrorCode::none) {
  proto::Status s{sys, m1e, m1r, m2e, m2r, e};
  return proto::encode(s).value();
}
inline can::Frame pair_frame(proto::MessageId id, double a, double b) {
  return proto::encode(proto::PairMessage{id, {a, b}}).value();
}

struct Rig {
  asio::io_context io;
  can::VirtualBusRegistry registry{io.get_executor()};
  std::unique_ptr<can::Bus> host;
  std::unique_ptr<can::Bus> peer;
  std::vector<can::Frame> received;  // what the peer got, in order
  // Replies the peer sends for each frame it receives (may be empty).
  std::function<std::vector<can::Frame>(const can::Frame&)> script = [](const can::Frame&) {
    return std::vector<can::Frame>{};
  };

  Rig() {
    registry.add("vcan0").value();
    host = registry.open("vcan0").value();
    peer = registry.open("vcan0").value();
  }

  asio::awaitable<void> peer_loop() {
    for (;;) {
      auto r = co_await peer->receive();
      if (!r) co_return;
      received.push_back(r.value());
      const auto replies = script(r.value());
      for (const auto& f : replies) {
        auto s = co_await peer->send(f);
        if (!s) co_return;
      }
    }
  }

  // The peer sends frames now.
  asio::awaitable<void> send(std::vector<can::Frame> frames) {
    for (const auto& f : frames) {
      auto s = co_await peer->send(f);
      EXPECT_TRUE(s);
    }
  }

  // Runs `body` with the peer active, then closes both nodes so every coroutine ends.
  void run(std::function<asio::awaitable<void>()> body) {
    bool finished = false;
    std::exception_ptr failure;
    asio::co_spawn(io, peer_loop(), [](std::exception_ptr) {});
    asio::co_spawn(
        io,
        [&]() -> asio::awaitable<void> {
          try {
            co_await body();
          } catch (...) {
            failure = std::current_exception();
          }
          finished = true;
          peer->close();
          host->close();
        },
        [](std::exception_ptr) {});
    io.run_for(60s);
    EXPECT_TRUE(finished) << "test body did not finish";
    if (failure) std::rethrow_exception(failure);
  }

  // Frames received by the peer with this id.
  std::vector<can::Frame> received_id(proto::MessageId id) const {
    std::vector<can::Frame> out;
    for (const auto& f : received)
      if (f.id() == static_cast<std::uint32_t>(id)) out.push_back(f);
    return out;
  }
};

// Waits (polling the executor) until `pred` holds; the limit only keeps a broken test from hanging.
inline asio::awaitable<bool> eventually(std::function<bool()> pred, int limit = 3000) {
  for (int i = 0; i < limit; ++i) {
    if (pred()) co_return true;
    co_await core::sleep_for(1ms);
  }
  co_return pred();
}

}  // namespace axon::blmc::host::testing
