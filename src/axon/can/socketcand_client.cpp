#include "axon/can/socketcand_client.hpp"

#include "axon/can/socketcand_codec.hpp"
#include "axon/net/stream_writer.hpp"

#include <boost/asio/connect.hpp>
#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/redirect_error.hpp>
#include <boost/asio/use_awaitable.hpp>
#include <boost/asio/write.hpp>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <array>

namespace axon::can {

namespace sc = socketcand;
using tcp = asio::ip::tcp;

struct SocketcandBus::Connection {
  explicit Connection(const asio::any_io_executor& ex) : socket(ex), writer(socket) {}
  tcp::socket socket;
  net::StreamWriter writer;
  sc::Tokenizer tokenizer;
  SocketcandBus* owner = nullptr;  // null once the bus is gone
  std::string scratch;             // formatting buffer for send()
};

namespace {

std::string server_name(const net::Endpoint& ep, const std::string& channel) {
  return fmt::format("socketcand://{}/{}", ep.to_string(), channel);
}

// The next complete message from the server, read as far as needed.
asio::awaitable<Result<sc::Message>> read_message(tcp::socket& socket, sc::Tokenizer& tokenizer) {
  std::array<char, 1024> buf{};
  for (;;) {
    if (auto r = tokenizer.next()) {
      if (!*r) co_return Error(CanErrc::protocol_error, r->error().detail);
      auto m = sc::parse(r->value());
      if (!m) co_return Error(CanErrc::protocol_error, m.error().detail);
      co_return m.value();
    }
    boost::system::error_code ec;
    const std::size_t n = co_await socket.async_read_some(asio::buffer(buf), asio::redirect_error(asio::use_awaitable, ec));
    if (ec == asio::error::eof) co_return Error(CanErrc::closed, "the server closed the connection");
    if (ec) co_return Error(CanErrc::io, ec.message());
    tokenizer.feed(std::string_view(buf.data(), n));
  }
}

// Sends a command during the handshake and reads the answer; `< ok >` is success.
// (Called with named messages: GCC 12 destroys aggregate temporaries in co_await expressions twice.)
asio::awaitable<Result<void>> command(tcp::socket& socket, sc::Tokenizer& tokenizer, sc::Message cmd) {
  const std::string text = sc::format(cmd);
  boost::system::error_code ec;
  co_await asio::async_write(socket, asio::buffer(text), asio::redirect_error(asio::use_awaitable, ec));
  if (ec) co_return Error(CanErrc::io, fmt::format("sending {}: {}", text, ec.message()));
  auto answer = co_await read_message(socket, tokenizer);
  if (!answer) co_return answer.error();
  if (std::holds_alternative<sc::Ok>(answer.value())) co_return ok();
  if (const auto* e = std::get_if<sc::ErrorText>(&answer.value()))
    co_return Error(CanErrc::device_error, fmt::format("the server refused {}: {}", text, e->text));
  co_return Error(CanErrc::protocol_error,
                  fmt::format("expected < ok > after {}, got {}", text, sc::format(answer.value())));
}

}  // namespace

asio::awaitable<Result<std::unique_ptr<SocketcandBus>>> SocketcandBus::connect(asio::any_io_executor ex,
                                                                              net::Endpoint server,
                                                                              std::string channel,
                                                                              BusOptions options,
                                                                              core::Duration timeout) {
  const std::string where = server_name(server, channel);
  auto conn = std::make_shared<Connection>(ex);
  auto resolver = std::make_shared<tcp::resolver>(ex);
  auto timed_out = std::make_shared<bool>(false);

  // One deadline for the whole handshake: when it passes, everything in progress is cancelled.
  asio::steady_timer deadline(ex, timeout);
  deadline.async_wait([conn, resolver, timed_out](const boost::system::error_code& ec) {
    if (ec) return;
    *timed_out = true;
    resolver->cancel();
    boost::system::error_code ignored;
    conn->socket.close(ignored);
  });
  auto fail = [&](Error e) -> Error {
    deadline.cancel();
    if (*timed_out)
      return Error(CanErrc::timeout, fmt::format("{}: no complete handshake within {} ms", where,
                                                 std::chrono::duration_cast<std::chrono::milliseconds>(timeout).count()));
    return Error(e.code, fmt::format("{}: {}", where, e.detail));
  };

  boost::system::error_code ec;
  const auto endpoints = co_await resolver->async_resolve(server.host, std::to_string(server.port),
                                                         asio::redirect_error(asio::use_awaitable, ec));
  if (ec) co_return fail(Error(CanErrc::connect_failed, fmt::format("resolving {}: {}", server.host, ec.message())));
  co_await asio::async_connect(conn->socket, endpoints, asio::redirect_error(asio::use_awaitable, ec));
  if (ec) co_return fail(Error(CanErrc::connect_failed, ec.message()));
  conn->socket.set_option(tcp::no_delay(true), ec);

  auto hi = co_await read_message(conn->socket, conn->tokenizer);
  if (!hi) co_return fail(hi.error());
  if (!std::holds_alternative<sc::Hi>(hi.value()))
    co_return fail(Error(CanErrc::protocol_error, fmt::format("expected < hi >, got {}", sc::format(hi.value()))));
  const sc::Message open_cmd = sc::Open{channel};
  auto opened = co_await command(conn->socket, conn->tokenizer, open_cmd);
  if (!opened) co_return fail(opened.error());
  const sc::Message raw_cmd = sc::Mode{sc::Mode::Kind::raw};
  auto raw = co_await command(conn->socket, conn->tokenizer, raw_cmd);
  if (!raw) co_return fail(raw.error());
  deadline.cancel();
  if (*timed_out) co_return fail(Error(CanErrc::timeout, ""));

  std::unique_ptr<SocketcandBus> bus(new SocketcandBus(ex, std::move(server), std::move(channel), options, conn));
  bus->start_reading();
  spdlog::debug("{}: connected, raw mode", bus->name());
  co_return bus;
}

SocketcandBus::SocketcandBus(asio::any_io_executor ex, net::Endpoint server, std::string channel, BusOptions options,
                             std::shared_ptr<Connection> conn)
    : Bus(std::move(ex), server_name(server, channel), options),
      server_(std::move(server)),
      channel_(std::move(channel)),
      conn_(std::move(conn)) {
  conn_->owner = this;
}

SocketcandBus::~SocketcandBus() {
  conn_->owner = nullptr;
  conn_->writer.stop();
  boost::system::error_code ignored;
  conn_->socket.close(ignored);
}

void SocketcandBus::start_reading() {
  asio::co_spawn(
      get_executor(),
      [](std::shared_ptr<Connection> c) -> asio::awaitable<void> {
        std::array<char, 4096> buf{};
        for (;;) {
          // Bytes that arrived with the handshake's last answer are handled first.
          while (auto r = c->tokenizer.next()) {
            if (!c->owner) co_return;
            if (*r)
              c->owner->on_text(r->value());
            else
              c->owner->protocol_error(r->error().detail);
          }
          boost::system::error_code ec;
          const std::size_t n =
              co_await c->socket.async_read_some(asio::buffer(buf), asio::redirect_error(asio::use_awaitable, ec));
          if (!c->owner) co_return;
          if (ec) {
            c->owner->connection_lost(ec == asio::error::eof ? std::string("the server closed the connection")
                                                             : ec.message());
            co_return;
          }
          c->tokenizer.feed(std::string_view(buf.data(), n));
        }
      }(conn_),
      asio::detached);
}

void SocketcandBus::on_text(const std::string& text) {
  auto m = sc::parse(text);
  if (!m) return protocol_error(m.error().detail);
  if (auto* f = std::get_if<sc::FrameMessage>(&m.value())) return deliver(f->frame);
  if (std::holds_alternative<sc::ErrorFrame>(m.value())) {
    ++mutable_stats().error_frames;
    spdlog::debug("{}: error frame {}", name(), text);
    return;
  }
  if (auto* e = std::get_if<sc::ErrorText>(&m.value())) {
    last_server_error_ = e->text;
    return protocol_error(fmt::format("the server answered with an error: {}", e->text));
  }
  protocol_error(fmt::format("unexpected message in raw mode: {}", text));
}

void SocketcandBus::protocol_error(const std::string& what) {
  auto& n = mutable_stats().protocol_errors;
  ++n;
  // The first one is worth a warning; a flood of them only at debug level.
  if (n == 1)
    spdlog::warn("{}: {} (further protocol errors are counted and logged at debug level)", name(), what);
  else
    spdlog::debug("{}: {}", name(), what);
}

void SocketcandBus::connection_lost(const std::string& why) {
  if (!is_open()) return;
  spdlog::warn("{}: connection lost: {}", name(), why);
  close();
}

void SocketcandBus::close() {
  Bus::close();
  conn_->writer.stop();
  boost::system::error_code ignored;
  conn_->socket.close(ignored);
}

std::size_t SocketcandBus::tx_pending() const noexcept { return conn_->writer.pending_units(); }

asio::awaitable<Result<void>> SocketcandBus::send(const Frame& frame) {
  if (!is_open() || conn_->writer.failed()) co_return Error(CanErrc::closed, name());
  if (conn_->writer.pending_units() >= options().tx_capacity) {
    ++mutable_stats().tx_dropped;
    co_return Error(CanErrc::tx_overflow,
                    fmt::format("{}: {} frames already waiting for the socket", name(), conn_->writer.pending_units()));
  }
  conn_->scratch.clear();
  sc::append(conn_->scratch, sc::Send{frame});
  conn_->writer.write(conn_->scratch, 1, conn_);
  count_sent(frame);
  co_return ok();
}

}  // namespace axon::can
