#include "axon/web/router.hpp"

#include "axon/core/error.hpp"
#include "axon/web/json_text.hpp"
#include "axon/web/metrics_text.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <system_error>

namespace axon::web {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kMaxFilePath = 200;

HttpResponse text_response(int status, std::string body) {
  HttpResponse r;
  r.status = status;
  r.body = std::move(body);
  return r;
}

HttpResponse json_response(std::string body) {
  HttpResponse r;
  r.content_type = "application/json";
  r.body = std::move(body);
  return r;
}

std::string html_escape(std::string_view text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

bool safe_segment_char(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '_' || c == '-';
}

// "/js/fps.js" -> "js/fps.js"; empty when any segment is empty, starts with a dot or has another character.
std::string safe_relative_path(std::string_view path) {
  if (path.size() < 2 || path.size() > kMaxFilePath || path.front() != '/') return {};
  const std::string_view rel = path.substr(1);
  bool segment_start = true;
  for (char c : rel) {
    if (c == '/') {
      if (segment_start) return {};
      segment_start = true;
      continue;
    }
    if (!safe_segment_char(c) || (segment_start && c == '.')) return {};
    segment_start = false;
  }
  if (segment_start) return {};
  return std::string(rel);
}

std::string content_type_of(std::string_view path) {
  struct Type {
    std::string_view ext;
    std::string_view type;
  };
  static constexpr std::array<Type, 8> kTypes{{{".html", "text/html; charset=utf-8"},
                                               {".js", "text/javascript; charset=utf-8"},
                                               {".mjs", "text/javascript; charset=utf-8"},
                                               {".css", "text/css; charset=utf-8"},
                                               {".svg", "image/svg+xml"},
                                               {".png", "image/png"},
                                               {".json", "application/json"},
                                               {".txt", "text/plain; charset=utf-8"}}};
  for (const auto& t : kTypes)
    if (path.ends_with(t.ext)) return std::string(t.type);
  return "application/octet-stream";
}

void write_server_metrics(MetricsText& m, const ServerStats& s) {
  m.family("axon_web_http_requests_total", MetricType::counter, "HTTP requests answered (any status)").sample(s.requests);
  m.family("axon_web_http_bad_requests_total", MetricType::counter,
           "Malformed or oversized HTTP requests, answered 400 and closed").sample(s.bad_requests);
  m.family("axon_web_http_not_found_total", MetricType::counter, "HTTP requests answered 404").sample(s.not_found);
  m.family("axon_web_connections_refused_total", MetricType::counter,
           "Connections refused because too many were open (answered 503)").sample(s.refused);
  m.family("axon_web_connections", MetricType::gauge, "Connections open now (HTTP and WebSocket)").sample(s.connections);
  m.family("axon_web_connections_idle_closed_total", MetricType::counter,
           "HTTP connections closed because no complete request came within the idle timeout").sample(s.idle_closed);
  m.family("axon_web_websocket_clients", MetricType::gauge, "WebSocket clients connected now").sample(s.ws_open);
  m.family("axon_web_websocket_accepted_total", MetricType::counter, "WebSocket clients accepted").sample(s.ws_accepted);
  m.family("axon_web_websocket_dropped_total", MetricType::counter,
           "WebSocket clients dropped by the server because their send queue was full (slow or dead)")
      .sample(s.ws_dropped_slow);
  m.family("axon_web_websocket_protocol_errors_total", MetricType::counter,
           "WebSocket clients closed because their input broke the protocol").sample(s.ws_bad_frames);
  m.family("axon_web_websocket_messages_total", MetricType::counter, "WebSocket messages written to clients")
      .sample(s.ws_messages);
  m.family("axon_web_websocket_sent_bytes_total", MetricType::counter, "Payload bytes of those messages, in bytes")
      .sample(s.ws_bytes);
}

}  // namespace

std::string json_quote(std::string_view text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      out += fmt::format("\\u{:04x}", static_cast<unsigned>(c));
    } else {
      out += c;
    }
  }
  return out + "\"";
}

Router::Router(std::string assets_dir, std::string javascript_dir)
    : assets_dir_(std::move(assets_dir)), javascript_dir_(std::move(javascript_dir)) {}

void Router::add(std::shared_ptr<Source> source) {
  std::lock_guard lock(mutex_);
  for (const auto& s : sources_)
    if (s->name() == source->name())
      throw Exception(Error(CoreErrc::invalid_argument, fmt::format("web source '{}' added twice", source->name())));
  sources_.push_back(std::move(source));
}

std::vector<std::shared_ptr<Source>> Router::sources() const {
  std::lock_guard lock(mutex_);
  return sources_;
}

std::shared_ptr<Source> Router::find(std::string_view name) const {
  std::lock_guard lock(mutex_);
  for (const auto& s : sources_)
    if (s->name() == name) return s;
  return nullptr;
}

HttpResponse Router::handle(const HttpRequest& request, const ServerStats& stats) const {
  if (request.method != "GET") return text_response(405, "only GET is served\n");
  const std::string_view path = target_path(request.target);
  if (path == "/") return index();
  if (path == "/metrics") {
    HttpResponse r;
    r.content_type = "text/plain; version=0.0.4; charset=utf-8";
    r.body = metrics(stats);
    return r;
  }
  if (path == "/ws") return text_response(426, "/ws is a WebSocket: connect with a WebSocket client\n");
  if (path == "/api" || path.starts_with("/api/")) return api(path);
  constexpr std::string_view kJavascript = "/javascript";
  if (path.starts_with("/javascript/")) return file(javascript_dir_, path.substr(kJavascript.size()));
  return file(assets_dir_, path);
}

std::string Router::metrics(const ServerStats& stats) const {
  MetricsText m;
  write_server_metrics(m, stats);
  std::string out = m.take();
  for (const auto& s : sources())
    if (auto text = s->metrics()) out += *text;
  return out;
}

HttpResponse Router::index() const {
  std::string body =
      "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>axon</title>"
      "<link rel=\"stylesheet\" href=\"/axon.css\"></head><body>\n<h1>axon</h1>\n<h2>Pages</h2>\n<ul>\n";
  const auto all = sources();
  for (const auto& s : all) {
    const std::string name = html_escape(s->name());
    if (s->page().empty()) body += fmt::format("<li>{} ({})", html_escape(s->title()), name);
    else body += fmt::format("<li><a href=\"/{}.html\">{}</a> ({})", html_escape(s->page()), html_escape(s->title()), name);
    body += fmt::format(": <a href=\"/api/{0}/state\">state</a>, <a href=\"/api/{0}/info\">info</a></li>\n", name);
  }
  if (all.empty()) body += "<li>nothing yet</li>\n";
  body +=
      "</ul>\n<h2>Endpoints</h2>\n<ul>\n<li><a href=\"/api/state\">/api/state</a>: every source's state (JSON)</li>\n"
      "<li><a href=\"/api/sources\">/api/sources</a>: what is served (JSON)</li>\n"
      "<li><a href=\"/metrics\">/metrics</a>: counters in the Prometheus text format</li>\n"
      "<li>/ws: WebSocket of live state (?source=NAME for one source)</li>\n</ul>\n</body></html>\n";
  HttpResponse r;
  r.content_type = "text/html; charset=utf-8";
  r.body = std::move(body);
  return r;
}

HttpResponse Router::api(std::string_view path) const {
  if (path == "/api/sources") {
    std::string body = "[";
    for (const auto& s : sources())
      body += fmt::format("{}{{\"name\":{},\"title\":{},\"page\":{}}}", body.size() > 1 ? "," : "", json_quote(s->name()),
                          json_quote(s->title()), json_quote(s->page()));
    return json_response(body + "]");
  }
  if (path == "/api/state") {
    std::string body = "{";
    for (const auto& s : sources()) {
      const auto snap = s->latest();
      body += fmt::format("{}{}:{}", body.size() > 1 ? "," : "", json_quote(s->name()), snap ? snap->state : "null");
    }
    return json_response(body + "}");
  }
  // /api/<name>/state or /api/<name>/info
  if (path.starts_with("/api/")) {
    const std::string_view rest = path.substr(std::string_view("/api/").size());
    const auto slash = rest.find('/');
    const auto source = slash == std::string_view::npos ? nullptr : find(rest.substr(0, slash));
    const std::string_view what = source ? rest.substr(slash + 1) : std::string_view{};
    if (what == "info") return json_response(source->info());
    if (what == "state") {
      const auto snap = source->latest();
      return json_response(snap ? snap->state : "null");
    }
  }
  return text_response(404, fmt::format("no such endpoint: {}\n", path));
}

HttpResponse Router::file(const std::string& dir, std::string_view path) {
  const std::string rel = safe_relative_path(path);
  if (rel.empty()) return text_response(404, "not found\n");
  const fs::path full = fs::path(dir) / rel;
  std::error_code ec;
  if (!fs::is_regular_file(full, ec)) return text_response(404, fmt::format("not found: {}\n", rel));
  std::ifstream in(full, std::ios::binary);
  std::ostringstream body;
  body << in.rdbuf();
  if (!in) return text_response(500, fmt::format("cannot read {}\n", rel));
  HttpResponse r;
  r.content_type = content_type_of(rel);
  r.body = std::move(body).str();
  return r;
}

std::string_view target_path(std::string_view target) noexcept {
  const auto q = target.find_first_of("?#");
  return q == std::string_view::npos ? target : target.substr(0, q);
}

std::string query_param(std::string_view target, std::string_view key) {
  const auto q = target.find('?');
  if (q == std::string_view::npos) return {};
  std::string_view query = target.substr(q + 1);
  query = query.substr(0, query.find('#'));
  while (!query.empty()) {
    const auto amp = query.find('&');
    const std::string_view pair = query.substr(0, amp);
    const auto eq = pair.find('=');
    if (pair.substr(0, eq) == key) return eq == std::string_view::npos ? std::string{} : std::string(pair.substr(eq + 1));
    if (amp == std::string_view::npos) break;
    query.remove_prefix(amp + 1);
  }
  return {};
}

std::string ws_message(const Source& source, const Snapshot& snapshot) {
  return fmt::format("{{\"source\":{},\"seq\":{},\"state\":{}}}", json_quote(source.name()), snapshot.sequence,
                     snapshot.state);
}

std::string default_javascript_dir() {
  if (const char* env = std::getenv("AXON_JAVASCRIPT_DIR"); env != nullptr && *env != '\0') return env;
  return "/usr/share/javascript";
}

std::string default_assets_dir() {
  std::error_code ec;
  if (const char* env = std::getenv("AXON_WEB_DIR"); env != nullptr && *env != '\0') return env;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path installed = exe.parent_path().parent_path() / "share" / "axon" / "web";
    if (fs::is_directory(installed, ec)) return installed.string();
  }
#ifdef AXON_WEB_SOURCE_DIR
  if (fs::is_directory(AXON_WEB_SOURCE_DIR, ec)) return AXON_WEB_SOURCE_DIR;
#endif
#ifdef AXON_WEB_INSTALL_DIR
  return AXON_WEB_INSTALL_DIR;
#else
  return "web";
#endif
}

}  // namespace axon::web
