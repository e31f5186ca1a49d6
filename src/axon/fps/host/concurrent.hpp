// Running one coroutine per item at the same time and waiting for all of them: how the array
// talks to many robots (and many buses) at once from one thread.
#pragma once

#include "axon/core/wakeup.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/this_coro.hpp>

#include <cstddef>

namespace axon::fps::host {

namespace detail {
template <class F>
asio::awaitable<void> run_one(F* f, std::size_t i, std::size_t* left, core::Wakeup* done) {
  co_await (*f)(i);
  if (--*left == 0) done->notify();
}
}  // namespace detail

// Calls f(0) .. f(n-1) (each returns asio::awaitable<void>) concurrently on the current executor
// and returns when all have finished. `f` must not throw.
template <class F>
asio::awaitable<void> for_each_concurrently(std::size_t n, F f) {
  if (n == 0) co_return;
  auto ex = co_await asio::this_coro::executor;
  core::Wakeup done(ex);
  std::size_t left = n;
  for (std::size_t i = 0; i < n; ++i) asio::co_spawn(ex, detail::run_one(&f, i, &left, &done), asio::detached);
  co_await done.wait_until(core::TimePoint::max());
}

}  // namespace axon::fps::host
