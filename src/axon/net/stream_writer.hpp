// One writer per TCP stream: several coroutines queue text, a single coroutine writes it, so that
// messages are never interleaved and nobody waits for the socket unless it wants to.
//
// Lives on the socket's executor (single-threaded, like everything that touches the socket). The
// object that owns the socket and the writer passes a keep-alive pointer to write(); the writing
// coroutine holds it until the queue is empty, so the owner may drop its last reference at any time.
#pragma once

#include <utility>  // Boost 1.74's awaitable.hpp uses std::exchange without including it

#include <boost/asio/awaitable.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/system/error_code.hpp>

#include <cstddef>
#include <memory>
#include <string>
#include <string_view>
#include <utility>

namespace axon::net {

namespace asio = boost::asio;

class StreamWriter {
 public:
  using Socket = asio::ip::tcp::socket;

  explicit StreamWriter(Socket& socket);
  StreamWriter(const StreamWriter&) = delete;
  StreamWriter& operator=(const StreamWriter&) = delete;

  // Queues `text`, which holds `units` messages (for pending_units()), and starts writing if idle.
  // After a failure or stop() the text is dropped.
  void write(std::string_view text, std::size_t units, std::shared_ptr<void> keep_alive);

  // Bytes and messages queued or being written.
  [[nodiscard]] std::size_t pending_bytes() const noexcept { return queued_.size() + in_flight_.size(); }
  [[nodiscard]] std::size_t pending_units() const noexcept { return queued_units_ + in_flight_units_; }
  [[nodiscard]] bool idle() const noexcept { return !running_; }

  // The first write error (or operation_aborted after stop()); nothing is written after it.
  [[nodiscard]] bool failed() const noexcept { return static_cast<bool>(error_); }
  [[nodiscard]] const boost::system::error_code& error() const noexcept { return error_; }

  // Completes once at most `bytes` are pending, or the writer failed or was stopped.
  // The caller keeps the writer alive while waiting.
  asio::awaitable<void> wait_until_at_most(std::size_t bytes);

  // Stops writing: queued text is dropped, waiters wake up. Does not close the socket.
  void stop();

 private:
  asio::awaitable<void> run(std::shared_ptr<void> keep_alive);

  Socket& socket_;
  std::string queued_;
  std::string in_flight_;
  std::size_t queued_units_ = 0;
  std::size_t in_flight_units_ = 0;
  bool running_ = false;
  boost::system::error_code error_;
  asio::steady_timer progress_;  // never expires; cancel() wakes the waiters
};

}  // namespace axon::net
