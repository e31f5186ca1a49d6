// core::LoopThread: functions and coroutines run on its thread, results and exceptions come back,
// and a coroutine that overruns its timeout is told to end, waited for, and reported as a timeout.
#include "axon/core/loop_thread.hpp"

#include <boost/asio/redirect_error.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/this_coro.hpp>
#include <boost/asio/use_awaitable.hpp>
#include <gtest/gtest.h>

#include <chrono>
#include <stdexcept>
#include <thread>

namespace axon::core {
namespace {

namespace asio = boost::asio;

TEST(LoopThread, CallRunsOnTheLoopThread) {
  LoopThread loop;
  const auto id = loop.call([] { return std::this_thread::get_id(); });
  EXPECT_NE(id, std::this_thread::get_id());
}

TEST(LoopThread, RunReturnsTheCoroutinesResult) {
  LoopThread loop;
  const int v = loop.run([]() -> asio::awaitable<int> { co_return 42; }, std::chrono::seconds(10));
  EXPECT_EQ(v, 42);
}

TEST(LoopThread, RunRethrowsTheCoroutinesException) {
  LoopThread loop;
  EXPECT_THROW(loop.run([]() -> asio::awaitable<void> {
                 throw std::runtime_error("inside");
                 co_return;
               }, std::chrono::seconds(10)),
               std::runtime_error);
}

TEST(LoopThread, AnOverrunEndsTheCoroutineThroughOnTimeoutThenThrowsTimeout) {
  LoopThread loop;
  bool ended = false;
  asio::steady_timer* waiting = nullptr;  // the coroutine's timer, cancelled by on_timeout
  try {
    loop.run(
        [&]() -> asio::awaitable<void> {
          asio::steady_timer t(co_await asio::this_coro::executor, std::chrono::hours(1));
          waiting = &t;
          boost::system::error_code ec;
          co_await t.async_wait(asio::redirect_error(asio::use_awaitable, ec));
          waiting = nullptr;
          ended = true;
        },
        std::chrono::milliseconds(50), [&] {
          if (waiting) waiting->cancel();
        });
    FAIL() << "no timeout";
  } catch (const Exception& e) {
    EXPECT_EQ(e.code(), CoreErrc::timeout);
  }
  EXPECT_TRUE(ended);  // run() returned only after the coroutine ended
}

}  // namespace
}  // namespace axon::core
