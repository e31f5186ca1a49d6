// Test rig: an io_context, one virtual bus with the host's node, and a way to run a test body as a
// coroutine and then stop everything that keeps the io_context busy (client readers, fakes).
#pragma once

#include "axon/can/virtual_bus.hpp"
#include "axon/core/wakeup.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/io_context.hpp>
#include <gtest/gtest.h>

#include <chrono>
#include <functional>
#include <memory>
#include <vector>

namespace axon::fps::host::testing {

namespace asio = boost::asio;

using namespace std::chrono_literals;

// Waits (polling the io_context) until `pred` holds; gives up after `limit` polls. Not a timing
// assertion: the limit only keeps a broken test from hanging.
inline asio::awaitable<bool> eventually(std::function<bool()> pred, int limit = 5000) {
  for (int i = 0; i < limit; ++i) {
    if (pred()) co_return true;
    co_await core::sleep_for(1ms);
  }
  co_return pred();
}

// Runs `a` and hands its result to `f` (co_spawn needs default-constructible results; Result<T>
// is not).
template <class T, class F>
asio::awaitable<void> then(asio::awaitable<T> a, F f) {
  f(co_await std::move(a));
}
template <class T, class F>
void spawn(asio::io_context& io, asio::awaitable<T> a, F f) {
  asio::co_spawn(io, then(std::move(a), std::move(f)), [](std::exception_ptr e) {
    if (e) std::rethrow_exception(e);
  });
}

class Runner {
 public:
  asio::io_context io;

  // Runs `body`, then every registered stopper; fails the test if it does not finish.
  void run(std::function<asio::awaitable<void>()> body) {
    bool finished = false;
    std::exception_ptr failure;
    asio::co_spawn(
        io,
        [&]() -> asio::awaitable<void> {
          try {
            co_await body();
          } catch (...) {
            failure = std::current_exception();
          }
          for (auto& s : stoppers_) co_await s();
          finished = true;
        },
        [](std::exception_ptr e) {
          if (e) std::rethrow_exception(e);
        });
    io.run_for(std::chrono::seconds(120));
    EXPECT_TRUE(finished) << "test body did not finish";
    if (!finished) {
      for (auto& s : stoppers_) asio::co_spawn(io, s(), [](std::exception_ptr) {});
      io.restart();
      io.run_for(std::chrono::seconds(5));
    }
    io.restart();
    if (failure) std::rethrow_exception(failure);
  }

  void on_stop(std::function<asio::awaitable<void>()> s) { stoppers_.push_back(std::move(s)); }

 private:
  std::vector<std::function<asio::awaitable<void>()>> stoppers_;
};

}  // namespace axon::fps::host::testing
