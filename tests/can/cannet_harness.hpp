// Test support for the CAN@net tests: running a test coroutine on an io_context with a time limit,
// and a bare line-based TCP client that speaks to the emulator the way a test wants to (exact
// lines, no interpretation).
#pragma once

#include "axon/can/cannet_codec.hpp"
#include "axon/net/endpoint.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/connect.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/redirect_error.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/use_awaitable.hpp>
#include <boost/asio/write.hpp>
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <functional>
#include <optional>
#include <string>

namespace axon::can::test {

namespace asio = boost::asio;
using tcp = asio::ip::tcp;
using namespace std::chrono_literals;

// Inside a test coroutine: fail and leave when the condition does not hold (ASSERT_* cannot
// co_return).
#define CO_ASSERT_TRUE(cond)                             \
  do {                                                   \
    if (!(cond)) {                                       \
      ADD_FAILURE() << "assertion failed: " #cond;       \
      co_return;                                         \
    }                                                    \
  } while (0)

// Runs `body` on `io` until it finishes, then stops `io` (servers and readers stay suspended and
// are destroyed with their owners). Fails the test if the body does not finish within `limit`.
inline void run(asio::io_context& io, std::function<asio::awaitable<void>()> body,
                std::chrono::seconds limit = std::chrono::seconds(30)) {
  bool done = false;
  std::exception_ptr error;
  asio::co_spawn(io, std::move(body), [&](std::exception_ptr e) {
    done = true;
    error = e;
    io.stop();
  });
  io.run_for(limit);
  io.restart();
  if (error) std::rethrow_exception(error);
  EXPECT_TRUE(done) << "the test coroutine did not finish within " << limit.count() << " s";
}

// A plain TCP client exchanging text lines.
class LineClient {
 public:
  explicit LineClient(asio::any_io_executor ex) : socket_(ex), timer_(ex) {}

  asio::awaitable<bool> connect(const net::Endpoint& ep) {
    boost::system::error_code ec;
    co_await socket_.async_connect(tcp::endpoint(asio::ip::make_address(ep.host), ep.port),
                                   asio::redirect_error(asio::use_awaitable, ec));
    if (!ec) socket_.set_option(tcp::no_delay(true), ec);
    co_return !ec;
  }

  asio::awaitable<bool> send(std::string line) {
    line.push_back('\n');
    boost::system::error_code ec;
    co_await asio::async_write(socket_, asio::buffer(line), asio::redirect_error(asio::use_awaitable, ec));
    co_return !ec;
  }

  // The next line, or nothing on timeout, end of stream or error (see closed()).
  asio::awaitable<std::optional<std::string>> read_line(std::chrono::milliseconds timeout = 5000ms) {
    for (;;) {
      if (auto piece = lines_.next()) co_return piece->text;
      if (closed_) co_return std::nullopt;
      const std::uint64_t gen = ++generation_;
      timer_.expires_after(timeout);
      timer_.async_wait([this, gen](const boost::system::error_code& ec) {
        if (!ec && gen == generation_) socket_.cancel();
      });
      boost::system::error_code ec;
      const std::size_t n = co_await socket_.async_read_some(asio::buffer(buf_), asio::redirect_error(asio::use_awaitable, ec));
      ++generation_;
      timer_.cancel();
      if (ec == asio::error::operation_aborted) co_return std::nullopt;  // timed out
      if (ec) {
        closed_ = true;
        co_return std::nullopt;
      }
      lines_.append(std::string_view(buf_.data(), n));
    }
  }

  // Sends a command and returns the next line (its reply, when nothing else is in flight).
  asio::awaitable<std::string> ask(std::string line) {
    co_await send(std::move(line));
    auto reply = co_await read_line();
    co_return reply ? *reply : std::string("<no reply>");
  }

  [[nodiscard]] bool closed() const noexcept { return closed_; }
  // "HOST:PORT" of this end of the connection.
  [[nodiscard]] std::string local() const {
    boost::system::error_code ec;
    const auto ep = socket_.local_endpoint(ec);
    return ec ? std::string("?") : net::Endpoint{ep.address().to_string(), ep.port()}.to_string();
  }
  void close() {
    boost::system::error_code ignored;
    socket_.close(ignored);
  }

 private:
  tcp::socket socket_;
  asio::steady_timer timer_;
  std::array<char, 4096> buf_{};
  cannet::LineSplitter lines_;
  std::uint64_t generation_ = 0;
  bool closed_ = false;
};

}  // namespace axon::can::test
