// The only file that sees Beast: the HTTP sessions, the WebSocket clients and the push loop, all on
// the server's own io_context thread (no locks: everything below runs there).
#include <utility>  // before Asio (Boost 1.74's awaitable.hpp uses std::exchange)

#include "axon/web/server.hpp"

#include "axon/core/error.hpp"
#include "axon/core/log.hpp"
#include "axon/net/endpoint.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/redirect_error.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/use_awaitable.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <deque>
#include <future>
#include <map>
#include <set>
#include <sstream>
#include <thread>

namespace axon::web {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
using boost::system::error_code;
using Request = http::request<http::string_body>;
using Response = http::response<http::string_body>;

constexpr auto kAwait = asio::use_awaitable;
constexpr std::size_t kMaxClientMessage = 4096;  // what a page may send on /ws (nothing is expected)

std::string_view view(beast::string_view s) { return {s.data(), s.size()}; }

void limit(http::request_parser<http::string_body>& parser, std::size_t max_bytes) {
  parser.header_limit(static_cast<std::uint32_t>(std::min<std::size_t>(max_bytes, UINT32_MAX)));
  parser.body_limit(max_bytes);
  parser.eager(true);
}

// Malformed input (as opposed to a connection that closed or timed out).
bool is_parse_error(const error_code& ec) {
  return ec.category() == http::make_error_code(http::error::bad_method).category() && ec != http::error::end_of_stream;
}

Response to_beast(HttpResponse r, unsigned version, bool keep_alive) {
  Response res{static_cast<http::status>(r.status), version};
  res.set(http::field::server, "axon");
  res.set(http::field::content_type, r.content_type);
  res.set(http::field::cache_control, "no-store");
  res.keep_alive(keep_alive);
  res.body() = std::move(r.body);
  res.prepare_payload();
  return res;
}

Response bad_request(const error_code& ec, ServerStats& stats) {
  ++stats.requests;
  ++stats.bad_requests;
  return to_beast({400, "text/plain; charset=utf-8", fmt::format("bad request: {}\n", ec.message())}, 11, false);
}

Response route(const Router& router, const Request& req, ServerStats& stats) {
  ++stats.requests;
  auto r = router.handle({view(req.method_string()), view(req.target())}, stats);
  if (r.status == 404) ++stats.not_found;
  return to_beast(std::move(r), req.version(), req.keep_alive());
}

std::string serialize(const Response& res) {
  std::ostringstream out;
  out << res;
  return std::move(out).str();
}

// One WebSocket client: its stream and its bounded queue of messages (shared: one message string
// serves every client).
struct WsClient {
  explicit WsClient(beast::tcp_stream&& stream) : ws(std::move(stream)), wake(ws.get_executor()) {}

  void close() {
    if (closed) return;
    closed = true;
    error_code ec;
    beast::get_lowest_layer(ws).socket().close(ec);
    wake.cancel();
  }

  websocket::stream<beast::tcp_stream> ws;
  asio::steady_timer wake;  // the writer waits on it while the queue is empty
  std::deque<std::shared_ptr<const std::string>> queue;  // the front one is being written
  std::string filter;                                    // one source's name, or empty: all
  std::map<std::string, std::uint64_t, std::less<>> queued_sequence;  // per source
  bool closed = false;
};

}  // namespace

std::string answer_raw_request(const Router& router, std::string_view bytes, ServerStats& stats,
                               std::size_t max_request_bytes) {
  http::request_parser<http::string_body> parser;
  limit(parser, max_request_bytes);
  error_code ec;
  parser.put(asio::buffer(bytes.data(), bytes.size()), ec);
  if (ec == http::error::need_more) ec = {};
  // The end of the input: a request cut short is malformed (Beast's put_eof() takes no input at all
  // for a complete message, so that case is told apart first).
  if (!ec && !parser.is_header_done()) ec = http::error::partial_message;
  if (!ec && !parser.is_done()) parser.put_eof(ec);
  if (!ec && !parser.is_done()) ec = http::error::partial_message;
  if (ec) return serialize(bad_request(ec, stats));
  return serialize(route(router, parser.get(), stats));
}

struct Server::Impl {
  explicit Impl(ServerOptions o)
      : options(std::move(o)), router(options.assets_dir.empty() ? default_assets_dir() : options.assets_dir),
        acceptor(io), push_timer(io) {}

  void listen();
  asio::awaitable<void> accept_loop();
  asio::awaitable<void> session(tcp::socket socket);
  asio::awaitable<void> websocket_session(beast::tcp_stream stream, Request req);
  asio::awaitable<void> read_until_closed(std::shared_ptr<WsClient> client);
  asio::awaitable<void> write_queue(std::shared_ptr<WsClient> client);
  asio::awaitable<void> push_loop();
  void refresh_messages();
  void queue_new(WsClient& client);
  void shutdown();

  asio::io_context io;  // first member: destroyed last
  ServerOptions options;
  Router router;
  tcp::acceptor acceptor;
  asio::steady_timer push_timer;
  std::string address;
  std::uint16_t port = 0;
  std::thread thread;
  bool joined = false;
  // Server thread only.
  ServerStats stats;
  bool stopping = false;
  std::size_t connections = 0;
  std::set<beast::tcp_stream*> http_streams;     // closed by shutdown()
  std::set<std::shared_ptr<WsClient>> clients;
  struct Message {
    std::uint64_t sequence = 0;
    std::shared_ptr<const std::string> text;
  };
  std::map<std::string, Message, std::less<>> messages;  // the latest per source
};

void Server::Impl::listen() {
  error_code ec;
  tcp::resolver resolver(io);
  const auto found = resolver.resolve(options.address, std::to_string(options.port), tcp::resolver::passive, ec);
  if (ec || found.empty())
    throw Exception(Error(CoreErrc::invalid_argument, fmt::format("web: address '{}': {}", options.address, ec.message())));
  const tcp::endpoint ep = found.begin()->endpoint();
  acceptor.open(ep.protocol(), ec);
  if (!ec) acceptor.set_option(asio::socket_base::reuse_address(true), ec);
  if (!ec) acceptor.bind(ep, ec);
  if (!ec) acceptor.listen(asio::socket_base::max_listen_connections, ec);
  if (ec)
    throw Exception(Error(CoreErrc::io, fmt::format("web: cannot listen on {}:{}: {}", options.address, options.port, ec.message())));
  const auto local = acceptor.local_endpoint();
  address = local.address().to_string();
  port = local.port();
}

asio::awaitable<void> Server::Impl::accept_loop() {
  for (;;) {
    error_code ec;
    tcp::socket socket = co_await acceptor.async_accept(asio::redirect_error(kAwait, ec));
    if (stopping || ec == asio::error::operation_aborted) co_return;
    if (ec) {
      // Out of descriptors and the like: wait a little rather than spin.
      spdlog::warn("web: accept failed: {}", ec.message());
      asio::steady_timer pause(io, std::chrono::milliseconds(100));
      co_await pause.async_wait(asio::redirect_error(kAwait, ec));
      continue;
    }
    asio::co_spawn(io, session(std::move(socket)), asio::detached);
  }
}

asio::awaitable<void> Server::Impl::session(tcp::socket socket) {
  struct Count {
    std::size_t& n;
    explicit Count(std::size_t& c) : n(++c) {}
    ~Count() { --n; }
  } count(connections);
  beast::tcp_stream stream(std::move(socket));
  http_streams.insert(&stream);
  beast::flat_buffer buffer;
  error_code ec;
  if (connections > options.max_connections) {
    // Logged on the first refusal and every 100th after it: a flood stays one line in a hundred.
    if (core::first_or_every(++stats.refused, 100))
      spdlog::warn("web: {} connections open, the limit is {}: a new one answered 503 ({} so far)", connections - 1,
                   options.max_connections, stats.refused);
    Response res = to_beast({503, "text/plain; charset=utf-8", "too many connections\n"}, 11, false);
    stream.expires_after(std::chrono::seconds(5));
    co_await http::async_write(stream, res, asio::redirect_error(kAwait, ec));
    http_streams.erase(&stream);
    co_return;
  }
  for (;;) {
    http::request_parser<http::string_body> parser;
    limit(parser, options.max_request_bytes);
    stream.expires_after(options.idle_timeout);
    co_await http::async_read(stream, buffer, parser, asio::redirect_error(kAwait, ec));
    if (stopping) break;
    if (ec) {
      if (is_parse_error(ec)) {
        Response res = bad_request(ec, stats);
        co_await http::async_write(stream, res, asio::redirect_error(kAwait, ec));
      } else if (ec == beast::error::timeout) {
        ++stats.idle_closed;  // a browser's idle keep-alive connection as much as a slow or half-open peer: not logged
      }
      break;
    }
    Request req = parser.release();
    if (websocket::is_upgrade(req) && target_path(view(req.target())) == "/ws") {
      http_streams.erase(&stream);
      stream.expires_never();
      co_await websocket_session(std::move(stream), std::move(req));
      co_return;
    }
    const bool keep_alive = req.keep_alive();
    Response res = route(router, req, stats);
    co_await http::async_write(stream, res, asio::redirect_error(kAwait, ec));
    if (ec || !keep_alive) break;
  }
  http_streams.erase(&stream);
  stream.socket().shutdown(tcp::socket::shutdown_send, ec);
}

asio::awaitable<void> Server::Impl::websocket_session(beast::tcp_stream stream, Request req) {
  auto client = std::make_shared<WsClient>(std::move(stream));
  client->filter = query_param(view(req.target()), "source");
  websocket::stream_base::timeout timeouts{};
  timeouts.handshake_timeout = std::chrono::seconds(10);
  timeouts.idle_timeout = std::chrono::seconds(20);  // a ping at half of it; no answer at all: closed
  timeouts.keep_alive_pings = true;
  client->ws.set_option(timeouts);
  client->ws.read_message_max(kMaxClientMessage);
  clients.insert(client);  // from here shutdown() closes it
  error_code ec;
  co_await client->ws.async_accept(req, asio::redirect_error(kAwait, ec));
  if (ec || stopping) {
    ++stats.bad_requests;
    client->close();
    clients.erase(client);
    co_return;
  }
  ++stats.ws_accepted;
  ++stats.ws_open;
  refresh_messages();
  queue_new(*client);  // the current state at once
  asio::co_spawn(io, write_queue(client), asio::detached);
  co_await read_until_closed(client);
  client->close();
  clients.erase(client);
  --stats.ws_open;
}

asio::awaitable<void> Server::Impl::read_until_closed(std::shared_ptr<WsClient> client) {
  beast::flat_buffer buffer;
  const auto& ws_errors = websocket::make_error_code(websocket::error::closed).category();
  for (;;) {
    error_code ec;
    co_await client->ws.async_read(buffer, asio::redirect_error(kAwait, ec));
    if (ec) {
      // A frame that breaks the protocol: Beast answers with a close frame (1002) and ends here once
      // the peer closes too, or after the handshake timeout (10 s) for one that stays silent.
      if (!client->closed && ec.category() == ws_errors && ec != websocket::error::closed) {
        ++stats.ws_bad_frames;
        spdlog::warn("web: a WebSocket client broke the protocol ({}): closed", ec.message());
      }
      co_return;
    }
    buffer.consume(buffer.size());  // pages send nothing the server acts on
  }
}

asio::awaitable<void> Server::Impl::write_queue(std::shared_ptr<WsClient> client) {
  for (;;) {
    error_code ec;
    while (!client->closed && client->queue.empty()) {
      client->wake.expires_at(asio::steady_timer::time_point::max());
      co_await client->wake.async_wait(asio::redirect_error(kAwait, ec));
    }
    if (client->closed) co_return;
    const auto message = client->queue.front();
    client->ws.text(true);
    co_await client->ws.async_write(asio::buffer(*message), asio::redirect_error(kAwait, ec));
    if (ec) {
      client->close();
      co_return;
    }
    client->queue.pop_front();
    ++stats.ws_messages;
    stats.ws_bytes += message->size();
  }
}

asio::awaitable<void> Server::Impl::push_loop() {
  for (;;) {
    error_code ec;
    push_timer.expires_after(options.push_period);
    co_await push_timer.async_wait(asio::redirect_error(kAwait, ec));
    if (stopping) co_return;
    refresh_messages();
    for (const auto& c : clients) queue_new(*c);
  }
}

// One message string per new snapshot, shared by every client.
void Server::Impl::refresh_messages() {
  for (const auto& source : router.sources()) {
    const auto snap = source->latest();
    if (!snap) continue;
    auto& m = messages[source->name()];
    if (m.sequence == snap->sequence) continue;
    m.sequence = snap->sequence;
    m.text = std::make_shared<const std::string>(ws_message(*source, *snap));
  }
}

// Queues what the client has not had yet; a client whose queue is full is dropped.
void Server::Impl::queue_new(WsClient& client) {
  if (client.closed) return;
  for (const auto& [name, m] : messages) {
    if (!client.filter.empty() && client.filter != name) continue;
    auto& queued = client.queued_sequence[name];
    if (queued == m.sequence) continue;
    if (client.queue.size() >= options.max_queued_messages) {
      ++stats.ws_dropped_slow;
      spdlog::warn("web: a WebSocket client fell {} messages behind: dropped", client.queue.size());
      client.close();
      return;
    }
    queued = m.sequence;
    client.queue.push_back(m.text);
    if (client.queue.size() == 1) client.wake.cancel();
  }
}

void Server::Impl::shutdown() {
  stopping = true;
  error_code ec;
  acceptor.close(ec);
  push_timer.cancel();
  for (auto* s : http_streams) s->socket().close(ec);
  for (const auto& c : clients) c->close();
}

Server::Server(ServerOptions options) : impl_(std::make_unique<Impl>(std::move(options))) {
  impl_->listen();
  asio::co_spawn(impl_->io, impl_->accept_loop(), asio::detached);
  asio::co_spawn(impl_->io, impl_->push_loop(), asio::detached);
  impl_->thread = std::thread([impl = impl_.get()] { impl->io.run(); });
  spdlog::info("web: serving {} (pages from {})", url(), impl_->router.assets_dir());
}

Server::~Server() { stop(); }

void Server::add(std::shared_ptr<Source> source) { impl_->router.add(std::move(source)); }
const std::string& Server::address() const noexcept { return impl_->address; }
std::uint16_t Server::port() const noexcept { return impl_->port; }
const std::string& Server::assets_dir() const noexcept { return impl_->router.assets_dir(); }

std::string Server::url() const {
  const bool v6 = impl_->address.find(':') != std::string::npos;
  return fmt::format("http://{}{}{}:{}/", v6 ? "[" : "", impl_->address, v6 ? "]" : "", impl_->port);
}

ServerStats Server::stats() const {
  if (impl_->joined) return impl_->stats;
  std::promise<ServerStats> copy;
  auto result = copy.get_future();
  asio::post(impl_->io, [&copy, impl = impl_.get()] {
    ServerStats s = impl->stats;
    s.connections = impl->connections;
    copy.set_value(s);
  });
  return result.get();
}

void Server::stop() noexcept {
  if (!impl_ || impl_->joined) return;
  asio::post(impl_->io, [impl = impl_.get()] { impl->shutdown(); });
  // Every coroutine ends once its socket or timer is closed; then run() returns.
  if (impl_->thread.joinable()) impl_->thread.join();
  impl_->joined = true;
}

ServerOptions server_address(const std::string& host_port) {
  const bool port_only = !host_port.empty() && std::all_of(host_port.begin(), host_port.end(), [](char c) {
    return std::isdigit(static_cast<unsigned char>(c)) != 0;
  });
  auto ep = net::parse_endpoint(port_only ? "127.0.0.1:" + host_port : host_port);
  if (!ep) throw Exception(ep.error());
  ServerOptions so;
  so.address = ep.value().host;
  so.port = ep.value().port;
  return so;
}

}  // namespace axon::web
