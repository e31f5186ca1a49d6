// web::Router: what the web server answers to each HTTP request, without the network (the server,
// the tests and the fuzz target call it with a parsed request).
//
// Routes (GET only; anything else is 405):
//   /                       index: what this process serves, with links
//   /api/sources            the sources as JSON: [{name, title, page}]
//   /api/state              every source's latest state: {"<name>": {...} or null}
//   /api/<name>/state       one source's latest state (404 for an unknown source)
//   /api/<name>/info        what does not change (Source::set_info)
//   /metrics                the server's own counters, then every source's metrics (Prometheus text)
//   /ws                     the WebSocket of live state (the server upgrades; a plain GET gets 426)
//   /<file>                 a page's file from the assets folder (html, js, css, svg, png, json)
//   /javascript/<file>      a script library from the system's javascript folder (Debian's
//                           libjs-* packages, e.g. /javascript/chart.js/chart.min.js), as Debian's
//                           web servers alias it; 404 when the package is not installed
// A query string is ignored except by /ws. File paths (in both folders) are refused (404) unless every segment is
// letters, digits, '.', '_' or '-' and none starts with a dot, so nothing outside the folder is read.
#pragma once

#include "axon/web/source.hpp"

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

namespace axon::web {

// What the server counts (read on its thread; Server::stats() copies it out).
struct ServerStats {
  std::uint64_t requests = 0;          // HTTP requests answered, any status
  std::uint64_t bad_requests = 0;      // malformed or oversized requests (answered 400, connection closed)
  std::uint64_t not_found = 0;         // answered 404
  std::uint64_t refused = 0;           // connections refused: too many at once (answered 503)
  std::uint64_t idle_closed = 0;       // HTTP connections closed for no complete request within idle_timeout
  std::uint64_t connections = 0;       // connections open now (HTTP and WebSocket, the refused ones until closed)
  std::uint64_t ws_accepted = 0;       // WebSocket clients accepted
  std::uint64_t ws_open = 0;           // WebSocket clients connected now
  std::uint64_t ws_dropped_slow = 0;   // clients dropped because their send queue was full
  std::uint64_t ws_messages = 0;       // messages written to clients
  std::uint64_t ws_bytes = 0;          // their payload bytes
  std::uint64_t ws_bad_frames = 0;     // clients whose input failed (protocol errors): closed
};

struct HttpRequest {
  std::string_view method;
  std::string_view target;  // path and query, as in the request line
};

struct HttpResponse {
  int status = 200;
  std::string content_type = "text/plain; charset=utf-8";
  std::string body;
};

// Where /javascript/ is read from: $AXON_JAVASCRIPT_DIR, else /usr/share/javascript.
[[nodiscard]] std::string default_javascript_dir();

class Router {
 public:
  explicit Router(std::string assets_dir, std::string javascript_dir = default_javascript_dir());

  // Thread-safe. A second source of the same name: CoreErrc::invalid_argument (axon::Exception).
  void add(std::shared_ptr<Source> source);
  [[nodiscard]] std::vector<std::shared_ptr<Source>> sources() const;
  [[nodiscard]] std::shared_ptr<Source> find(std::string_view name) const;
  [[nodiscard]] const std::string& assets_dir() const noexcept { return assets_dir_; }

  [[nodiscard]] HttpResponse handle(const HttpRequest& request, const ServerStats& stats) const;
  // The /metrics text: the server's counters, then each source's published metrics.
  [[nodiscard]] std::string metrics(const ServerStats& stats) const;

 private:
  [[nodiscard]] HttpResponse index() const;
  [[nodiscard]] HttpResponse api(std::string_view path) const;
  [[nodiscard]] static HttpResponse file(const std::string& dir, std::string_view path);

  std::string assets_dir_;
  std::string javascript_dir_;
  mutable std::mutex mutex_;
  std::vector<std::shared_ptr<Source>> sources_;
};

// The path of a request target ("/ws?source=fps" -> "/ws") and one query parameter's value ("" when absent).
[[nodiscard]] std::string_view target_path(std::string_view target) noexcept;
[[nodiscard]] std::string query_param(std::string_view target, std::string_view key);
// A WebSocket message carrying a snapshot: {"source":"fps","seq":N,"state":{...}}.
[[nodiscard]] std::string ws_message(const Source& source, const Snapshot& snapshot);
// Where the page files are when ServerOptions gives no folder: $AXON_WEB_DIR, else
// <executable>/../share/axon/web (an installed axon), else the source tree's web/ (a build tree),
// else the install prefix's share/axon/web.
[[nodiscard]] std::string default_assets_dir();

}  // namespace axon::web
