// Shared by the socketcand tests: running coroutines with a watchdog, and a plain text peer that
// speaks the protocol byte by byte (to check exactly what the other side writes).
#pragma once

#include "axon/can/socketcand_codec.hpp"

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
#include <exception>
#include <functional>
#include <string>

namespace axon::can::testing {

namespace asio = boost::asio;
using tcp = asio::ip::tcp;

// Runs `body` on `io` until it and everything it left behind have finished. `after` runs when the
// body is done (e.g. stopping a server so the io_context runs out of work). A watchdog fails the
// test instead of hanging when something never completes.
inline void run_test(asio::io_context& io, std::function<asio::awaitable<void>()> body,
                     std::function<void()> after = {}, std::chrono::seconds limit = std::chrono::seconds(30)) {
  bool done = false, watchdog_fired = false;
  std::exception_ptr failure;
  asio::steady_timer watchdog(io, limit);
  watchdog.async_wait([&](const boost::system::error_code& ec) {
    if (ec) return;
    watchdog_fired = true;
    io.stop();
  });
  asio::co_spawn(io, std::move(body), [&](std::exception_ptr e) {
    done = true;
    failure = e;
    if (after) after();
    watchdog.cancel();
  });
  io.run();
  io.restart();
  ASSERT_FALSE(watchdog_fired) << "the test did not finish within " << limit.count() << " s (body done: " << done << ")";
  if (failure) std::rethrow_exception(failure);
}

// One end of a TCP connection speaking socketcand text, without any protocol logic.
class TextPeer {
 public:
  explicit TextPeer(tcp::socket socket) : socket_(std::move(socket)) {}

  static asio::awaitable<TextPeer> connect(asio::any_io_executor ex, std::uint16_t port) {
    tcp::socket s(ex);
    co_await s.async_connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), port), asio::use_awaitable);
    s.set_option(tcp::no_delay(true));
    co_return TextPeer(std::move(s));
  }

  // Whatever one read returns (at least one byte); empty at end of stream.
  asio::awaitable<std::string> read_some() {
    std::array<char, 4096> buf{};
    boost::system::error_code ec;
    const std::size_t n = co_await socket_.async_read_some(asio::buffer(buf), asio::redirect_error(asio::use_awaitable, ec));
    if (ec) co_return std::string{};
    raw_.append(buf.data(), n);
    co_return std::string(buf.data(), n);
  }

  // The next complete message ("< ... >"); empty at end of stream. Framing errors fail the test.
  asio::awaitable<std::string> next() {
    for (;;) {
      if (auto r = tokenizer_.next()) {
        EXPECT_TRUE(*r) << r->error().message();
        if (*r) co_return r->value();
        continue;
      }
      std::array<char, 4096> buf{};
      boost::system::error_code ec;
      const std::size_t n = co_await socket_.async_read_some(asio::buffer(buf), asio::redirect_error(asio::use_awaitable, ec));
      if (ec) co_return std::string{};
      raw_.append(buf.data(), n);
      tokenizer_.feed(std::string_view(buf.data(), n));
    }
  }

  asio::awaitable<void> write(std::string text) {
    co_await asio::async_write(socket_, asio::buffer(text), asio::use_awaitable);
  }

  // Everything read so far, separators included.
  [[nodiscard]] const std::string& raw() const noexcept { return raw_; }
  tcp::socket& socket() noexcept { return socket_; }
  void close() {
    boost::system::error_code ec;
    socket_.close(ec);
  }

 private:
  tcp::socket socket_;
  socketcand::Tokenizer tokenizer_;
  std::string raw_;
};

// A listening socket on 127.0.0.1 with an ephemeral port, for fake servers.
inline tcp::acceptor loopback_acceptor(asio::any_io_executor ex) {
  return tcp::acceptor(ex, tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0));
}

}  // namespace axon::can::testing
