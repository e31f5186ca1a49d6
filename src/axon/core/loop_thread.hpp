// An io_context running on a thread of its own. The blocking APIs own one each (their event loop
// runs there while the caller's thread waits for results), and a simulator that shares a process
// with its host runs on one so each side's loop carries only its own work, as on two machines.
// Whatever lives on the loop is touched through call() and run() only, never from the loop's own
// thread (both would wait for themselves).
#pragma once

#include <utility>  // before Asio (Boost 1.74's awaitable.hpp uses std::exchange)

#include "axon/core/error.hpp"

#include <boost/asio/awaitable.hpp>
#include <boost/asio/co_spawn.hpp>
#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>

#include <chrono>
#include <exception>
#include <fmt/format.h>
#include <functional>
#include <future>
#include <memory>
#include <thread>
#include <type_traits>

namespace axon::core {

class LoopThread {
 public:
  LoopThread() : work_(io_.get_executor()), thread_([this] { io_.run(); }) {}
  LoopThread(const LoopThread&) = delete;
  LoopThread& operator=(const LoopThread&) = delete;
  ~LoopThread() { stop(); }

  [[nodiscard]] boost::asio::io_context::executor_type executor() noexcept { return io_.get_executor(); }

  // Runs f() on the thread, waits for it and returns its result (exceptions included).
  template <class F>
  auto call(F f) -> decltype(f()) {
    std::packaged_task<decltype(f())()> task(std::move(f));
    auto result = task.get_future();
    boost::asio::post(io_, [&task] { task(); });
    return result.get();
  }

  // Runs the coroutine that make() returns on the loop and waits for its result (its exception is
  // rethrown here). When it has not ended after `timeout`, on_timeout() runs on the loop: it must
  // make the coroutine end soon (stop the devices, cancel, close), because run() then waits for
  // that end before it throws axon::Exception (CoreErrc::timeout): the coroutine may refer to
  // what the caller holds, so it never outlives the call.
  template <class F>
  auto run(F make, std::chrono::steady_clock::duration timeout, std::function<void()> on_timeout = {}) ->
      typename std::invoke_result_t<F&>::value_type {
    using T = typename std::invoke_result_t<F&>::value_type;
    auto done = std::make_shared<std::promise<T>>();
    auto result = done->get_future();
    if constexpr (std::is_void_v<T>) {
      boost::asio::co_spawn(io_, std::move(make), [done](std::exception_ptr e) {
        if (e) done->set_exception(e);
        else done->set_value();
      });
    } else {
      boost::asio::co_spawn(io_, std::move(make), [done](std::exception_ptr e, T value) {
        if (e) done->set_exception(e);
        else done->set_value(std::move(value));
      });
    }
    if (result.wait_for(timeout) == std::future_status::ready) return take(result);
    if (on_timeout) boost::asio::post(io_, std::move(on_timeout));
    result.wait();
    throw Exception(Error(CoreErrc::timeout, fmt::format("not done after {:.3g} s",
                                                         std::chrono::duration<double>(timeout).count())));
  }

  // Ends the loop (what is still queued is dropped) and joins the thread. Idempotent.
  void stop() {
    if (!thread_.joinable()) return;
    work_.reset();
    io_.stop();
    thread_.join();
  }

 private:
  // The coroutine's result, or its exception rethrown here after one turn of the loop. The
  // coroutine's frame, which holds the exception too, is destroyed on the loop's thread just after
  // the result is handed over, and the exception object is freed by whichever thread lets go of it
  // last, through a reference count inside the C++ runtime that ThreadSanitizer cannot see (it
  // reported the caller's read of the exception and the loop's free as a race). Waiting for that
  // turn leaves the caller the only owner. Bounded: a loop that does not turn within a second is
  // not waited for.
  template <class T>
  T take(std::future<T>& result) {
    try {
      return result.get();
    } catch (...) {
      auto turned = std::make_shared<std::promise<void>>();
      auto done = turned->get_future();
      boost::asio::post(io_, [turned] { turned->set_value(); });
      (void)done.wait_for(std::chrono::seconds(1));
      throw;
    }
  }

  boost::asio::io_context io_;
  boost::asio::executor_work_guard<boost::asio::io_context::executor_type> work_;
  std::thread thread_;
};

}  // namespace axon::core
