// A CAN bus reached through a socketcand daemon (or `axon can bridge`) over TCP, in raw mode.
//
// connect() opens the TCP connection, waits for `< hi >`, opens the channel, switches to raw mode
// and returns the bus. From then on every `< frame ... >` from the server is delivered with the
// server's timestamp, and send() writes `< send ... >` (`< sendrtr ... >` for remote frames).
//
// Bad input from the server (garbage, malformed or unexpected messages, `< error ... >` answers)
// is counted in stats().protocol_errors and logged; the connection is kept. Error frames reported
// by the server (`< error CLASS TIME >`) count in stats().error_frames. When the server closes the
// connection or the socket fails, the bus becomes closed.
#pragma once

#include "axon/can/bus.hpp"
#include "axon/can/bus_spec.hpp"
#include "axon/net/endpoint.hpp"

#include <boost/asio/awaitable.hpp>

#include <chrono>
#include <memory>
#include <string>

namespace axon::can {

class SocketcandBus final : public Bus {
 public:
  static constexpr std::uint16_t kDefaultPort = kSocketcandPort;  // 29536

  // Connects and performs the handshake, all within `timeout`. Errors: connect_failed (resolve or
  // TCP connect failed), timeout, device_error (the server refused the channel or raw mode, with its
  // text), protocol_error (the server said something unexpected), closed (it hung up).
  static asio::awaitable<Result<std::unique_ptr<SocketcandBus>>> connect(
      asio::any_io_executor ex, net::Endpoint server, std::string channel, BusOptions options = {},
      core::Duration timeout = std::chrono::seconds(5));

  ~SocketcandBus() override;

  // Queues the frame for the socket. Errors: closed; tx_overflow when options().tx_capacity frames
  // are already waiting for the socket.
  asio::awaitable<Result<void>> send(const Frame& frame) override;
  [[nodiscard]] std::size_t tx_pending() const noexcept override;
  void close() override;

  [[nodiscard]] const net::Endpoint& server() const noexcept { return server_; }
  [[nodiscard]] const std::string& channel() const noexcept { return channel_; }
  // The text of the last `< error ... >` answer the server sent while in raw mode (empty if none).
  [[nodiscard]] const std::string& last_server_error() const noexcept { return last_server_error_; }

  struct Connection;  // socket, tokenizer, writer; shared with the reading coroutine

 private:
  SocketcandBus(asio::any_io_executor ex, net::Endpoint server, std::string channel, BusOptions options,
                std::shared_ptr<Connection> conn);
  void start_reading();
  void on_text(const std::string& text);
  void protocol_error(const std::string& what);
  void connection_lost(const std::string& why);

  net::Endpoint server_;
  std::string channel_;
  std::shared_ptr<Connection> conn_;
  std::string last_server_error_;
};

}  // namespace axon::can
