// An io_context running on a thread of its own. The blocking APIs own one each (their event loop
// runs there while the caller's thread waits for results), and a simulator that shares a process
// with its host runs on one so each side's loop carries only its own work, as on two machines.
// Whatever lives on the loop is touched through call() only.
#pragma once

#include <utility>  // before Asio (Boost 1.74's awaitable.hpp uses std::exchange)

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>

#include <future>
#include <thread>

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

  // Ends the loop (what is still queued is dropped) and joins the thread. Idempotent.
  void stop() {
    if (!thread_.joinable()) return;
    work_.reset();
    io_.stop();
    thread_.join();
  }

 private:
  boost::asio::io_context io_;
  boost::asio::executor_work_guard<boost::asio::io_context::executor_type> work_;
  std::thread thread_;
};

}  // namespace axon::core
