// Internal to the blmc blocking APIs (MotorBoard, sim::SimulatedBoard): runs a coroutine on a
// core::LoopThread and waits for its result on the caller's thread, with a time limit. Includes
// Asio: never include it from a public blocking header. (core::LoopThread has call() for plain
// functions; this is its awaitable counterpart, local to blmc.)
#pragma once

#include "axon/core/clock.hpp"
#include "axon/core/error.hpp"
#include "axon/core/loop_thread.hpp"

#include <boost/asio/awaitable.hpp>
#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>

#include <chrono>
#include <functional>
#include <future>
#include <memory>
#include <type_traits>

namespace axon::blmc::detail {

// Runs make() on the loop's thread (make returns an asio::awaitable<T>; it and what it captures
// live until the coroutine ends) and returns its value or rethrows its exception. When `timeout`
// passes first, `on_timeout` runs on the caller's thread (e.g. to interrupt the wait) and the
// result gets `grace` more; after that the call throws axon::Exception(`late`) and the coroutine
// goes on alone (the objects it uses must outlive it: the loop's owner stops the loop first).
template <class T, class Make>
T await_on(core::LoopThread& loop, Make make, core::Duration timeout, const std::function<void()>& on_timeout,
           const Error& late, core::Duration grace = std::chrono::seconds(1)) {
  auto done = std::make_shared<std::promise<T>>();
  auto result = done->get_future();
  boost::asio::co_spawn(
      loop.executor(),
      [make = std::move(make), done]() -> boost::asio::awaitable<void> {
        try {
          if constexpr (std::is_void_v<T>) {
            co_await make();
            done->set_value();
          } else {
            auto value = co_await make();
            done->set_value(std::move(value));
          }
        } catch (...) {
          done->set_exception(std::current_exception());
        }
      },
      boost::asio::detached);
  if (result.wait_for(timeout) == std::future_status::timeout) {
    if (on_timeout) on_timeout();
    if (result.wait_for(grace) == std::future_status::timeout) throw Exception(late);
  }
  return result.get();
}

}  // namespace axon::blmc::detail
