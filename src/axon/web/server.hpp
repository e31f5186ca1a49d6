// web::Server: the HTTP + WebSocket server a long-running axon process opens with --http HOST:PORT
// (docs/dashboard.md): pages, /api/state, /metrics and /ws (router.hpp lists the routes).
//
// It runs on an event loop of its own thread (never a real-time one): the sources (source.hpp)
// publish from their owners' threads and the server only reads their latest snapshot. Every
// push_period it sends each WebSocket client the snapshots published since its last message. A
// client has a send queue of at most max_queued_messages: a client that falls that far behind
// (slow, or dead with its TCP window full) is dropped and counted, never buffered without bound.
// Malformed requests are answered 400 and counted; requests are limited in size; connections
// that say nothing are closed after idle_timeout.
//
// Threading: add() from any thread; stats() and stop() from the thread that owns the server.
// Errors: the constructor throws axon::Exception (CoreErrc::invalid_argument for an address that
// does not parse, CoreErrc::io when it cannot listen). The destructor stops the server and never throws.
#pragma once

#include "axon/web/router.hpp"
#include "axon/web/source.hpp"

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

namespace axon::web {

struct ServerOptions {
  std::string address = "127.0.0.1";        // where to listen; 0.0.0.0 to serve other machines
  std::uint16_t port = 0;                    // 0: any free port (port() tells which)
  std::string assets_dir;                    // the page files; empty: default_assets_dir()
  std::chrono::milliseconds push_period{100};  // WebSocket updates: at most this often (10 Hz)
  std::size_t max_queued_messages = 8;       // per WebSocket client; one more and it is dropped
  std::size_t max_connections = 128;         // HTTP and WebSocket together; more are answered 503
  std::size_t max_request_bytes = 16 * 1024; // request line, headers and body
  std::chrono::seconds idle_timeout{30};     // an HTTP connection with no complete request
};

// The options for --http's HOST:PORT (PORT alone: 127.0.0.1; port 0: any free port); throws
// axon::Exception when it does not parse.
[[nodiscard]] ServerOptions server_address(const std::string& host_port);

class Server {
 public:
  explicit Server(ServerOptions options = {});
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  // Any thread, any time (a page appears in the index once added).
  void add(std::shared_ptr<Source> source);

  [[nodiscard]] const std::string& address() const noexcept;
  [[nodiscard]] std::uint16_t port() const noexcept;
  [[nodiscard]] std::string url() const;  // http://ADDRESS:PORT/
  [[nodiscard]] const std::string& assets_dir() const noexcept;
  // A copy of the counters (taken on the server's thread).
  [[nodiscard]] ServerStats stats() const;

  // Closes every connection and ends the thread. Idempotent.
  void stop() noexcept;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

// Parses `bytes` as one HTTP request the way the server does (same limits) and returns the bytes of
// the server's answer: the route's response, or 400 when the request is malformed or incomplete.
// Counts in `stats` as the server would. For the fuzz target and the tests.
[[nodiscard]] std::string answer_raw_request(const Router& router, std::string_view bytes, ServerStats& stats,
                                             std::size_t max_request_bytes = ServerOptions{}.max_request_bytes);

}  // namespace axon::web
