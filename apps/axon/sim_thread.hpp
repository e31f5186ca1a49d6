// An io_context on a thread of its own, for a simulator that shares a process with the host (the
// demo): each side's event loop carries only its own work, as on two machines, and both cores of
// a small machine are used. Whatever lives on it is touched through call() only.
#pragma once

#include <utility>  // before Asio (Boost 1.74's awaitable.hpp uses std::exchange)

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>

#include <future>
#include <thread>

namespace axon::app {

class SimThread {
 public:
  SimThread() : work_(io_.get_executor()), thread_([this] { io_.run(); }) {}
  SimThread(const SimThread&) = delete;
  SimThread& operator=(const SimThread&) = delete;
  ~SimThread() { stop(); }

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

}  // namespace axon::app
