// A socketcand-compatible TCP server: serves the channels of a BusProvider (virtual buses, or any
// other transport) to socketcand clients such as python-can, Kayak or axon's own SocketcandBus.
//
// Every connection starts with `< hi >`. `< open NAME >` opens a NEW endpoint on the provider's
// channel for this connection alone (so clients see each other's frames, as with the daemon's raw
// sockets; a client does not see its own). The connection is then in BCM mode, where it may send
// frames; `< rawmode >` forwards every bus frame to the client as `< frame ... >` with a wall-clock
// timestamp (the frame's own if it has one, else the time of forwarding). `< controlmode >` and
// `< statistics MS >` report this connection's counters as `< stat ... >` every MS milliseconds.
// `< echo >` is answered in every mode. The broadcast-manager commands and ISO-TP are not supported.
//
// Bad input never ends a connection: malformed or out-of-place messages are answered with
// `< error ... >` and counted. The one exception, as with the daemon, is `< open >` of a channel
// the provider does not have: the server answers `< error ... >` and hangs up.
//
// Hostile peers (docs/reliability.md): what is queued for one client is bounded by
// client_backlog (bus frames wait in its endpoint's receive queue, BusOptions::rx_capacity frames,
// and are dropped there; a client that sends requests without reading their answers is no longer
// read from until it has read), a partial message by socketcand::kMaxMessageLength, and the
// number of clients by max_clients. A connection that has not opened a channel within
// handshake_timeout is closed, so that silent connections cannot keep the places. Refusals,
// timeouts and each client's first bad message are logged at warning level, once (the next
// refusals of the same burst and the client's further bad messages at debug level).
//
// Wire format, chosen for python-can 4.1 (see docs/can-socketcand.md): handshake answers are sent
// alone and unterminated; once raw mode is confirmed, every message is preceded by '\n' and frames
// start only `raw_start_delay` after the `< ok >`.
//
// Threading: the server, its sessions and the provider's buses share one executor.
#pragma once

#include "axon/can/bus.hpp"
#include "axon/can/provider.hpp"
#include "axon/net/endpoint.hpp"

#include <chrono>
#include <cstdint>
#include <memory>

namespace axon::can {

struct SocketcandServerOptions {
  BusOptions bus{};  // options of each connection's endpoint (its receive queue is the backlog)
  // Pause between the `< ok >` that confirms raw mode and the first frame sent, so that clients
  // which read the handshake answer with one recv() (python-can) get it alone. Frames that arrive
  // meanwhile wait in the endpoint's queue; none is lost.
  core::Duration raw_start_delay = std::chrono::milliseconds(50);
  // Once in raw mode, put '\n' before every message. The daemon writes messages back to back;
  // python-can 4.1 drops one character after the last complete message of each read, which then
  // is this separator instead of the '<' of a message cut by the read (that frame would be lost).
  // Before rather than after: a read that ends with a message then leaves nothing behind for
  // python-can to warn about. Other clients skip whatever is between messages.
  bool separate_messages = true;
  std::size_t max_clients = 64;
  // Bytes queued for one client's socket before the server stops taking frames from its endpoint
  // (a slow reader then loses frames in the endpoint's receive queue, counted in its rx_dropped).
  std::size_t client_backlog = 256 * 1024;
  // A connection must open a channel within this time, else it is closed (0: no limit).
  core::Duration handshake_timeout = std::chrono::seconds(10);
};

struct SocketcandServerStats {
  std::uint64_t clients_accepted = 0;
  std::uint64_t clients_rejected = 0;  // refused because max_clients were connected
  std::uint64_t clients_active = 0;
  std::uint64_t frames_in = 0;         // frames clients sent onto the bus
  std::uint64_t frames_out = 0;        // frames sent to clients (once per client)
  std::uint64_t errors = 0;            // malformed or out-of-place client messages, failed opens
  std::uint64_t send_failures = 0;     // frames the bus refused (queue full, bus closed)
  std::uint64_t handshake_timeouts = 0;  // connections closed: no channel opened within handshake_timeout
  std::uint64_t output_high_water = 0;   // most bytes ever queued for one client's socket
};

class SocketcandServer {
 public:
  // Listens on `listen` (port 0: an ephemeral port, see local_endpoint()) and starts accepting.
  // CanErrc::io if the address cannot be resolved or bound.
  static Result<std::unique_ptr<SocketcandServer>> create(asio::any_io_executor ex, BusProvider& provider,
                                                          net::Endpoint listen, SocketcandServerOptions options = {});
  // The same; throws axon::Exception with that error instead.
  SocketcandServer(asio::any_io_executor ex, BusProvider& provider, net::Endpoint listen,
                   SocketcandServerOptions options = {});
  ~SocketcandServer();
  SocketcandServer(const SocketcandServer&) = delete;
  SocketcandServer& operator=(const SocketcandServer&) = delete;

  // The address actually bound (with the real port when 0 was asked for).
  [[nodiscard]] net::Endpoint local_endpoint() const;
  // Stops accepting and closes every connection. Safe to call twice; the destructor calls it.
  void stop();
  [[nodiscard]] const SocketcandServerStats& stats() const noexcept;

  struct Impl;

 private:
  struct Unbound {};
  SocketcandServer(Unbound, asio::any_io_executor ex, BusProvider& provider, SocketcandServerOptions options);
  Result<void> listen(const net::Endpoint& where);

  std::shared_ptr<Impl> impl_;
};

}  // namespace axon::can
