#include "axon/can/socketcand_server.hpp"

#include "axon/can/socketcand_codec.hpp"
#include "axon/net/stream_writer.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/redirect_error.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/use_awaitable.hpp>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <vector>

namespace axon::can {

namespace sc = socketcand;
using tcp = asio::ip::tcp;

namespace {

// Frame ids never have bit 29 set, so this filter lets nothing through: what an endpoint gets
// while its connection is not in raw mode (the daemon has no raw socket open then either).
Filter nothing_passes() { return Filter{1u << 29, 1u << 29, Filter::Format::any}; }

core::WallTime wall_now() { return core::SteadyClock::instance().wall(); }

std::string describe(const tcp::endpoint& ep) {
  return net::Endpoint{ep.address().to_string(), ep.port()}.to_string();
}

}  // namespace

struct SocketcandSession;

struct SocketcandServer::Impl {
  Impl(asio::any_io_executor e, BusProvider& p, SocketcandServerOptions o)
      : ex(std::move(e)), provider(p), options(o), acceptor(ex) {}

  asio::any_io_executor ex;
  BusProvider& provider;
  SocketcandServerOptions options;
  tcp::acceptor acceptor;
  net::Endpoint bound;
  SocketcandServerStats stats;
  std::vector<SocketcandSession*> sessions;
  bool stopped = false;
  bool refusing = false;  // a refusal was logged at warning level; reset by the next client accepted
};

namespace {

using Impl = SocketcandServer::Impl;

}  // namespace

// One client connection and its state machine (no bus -> BCM <-> raw / control).
struct SocketcandSession : std::enable_shared_from_this<SocketcandSession> {
  enum class State : std::uint8_t { no_bus, bcm, raw, control };

  SocketcandSession(std::shared_ptr<Impl> srv, tcp::socket s)
      : server(std::move(srv)),
        socket(std::move(s)),
        writer(socket),
        raw_pause(socket.get_executor()),
        stats_timer(socket.get_executor()),
        handshake_timer(socket.get_executor()) {
    boost::system::error_code ec;
    peer = describe(socket.remote_endpoint(ec));
  }

  std::shared_ptr<Impl> server;
  tcp::socket socket;
  net::StreamWriter writer;
  sc::Tokenizer tokenizer;
  std::string peer;
  std::string channel;
  std::shared_ptr<Bus> bus;  // the forwarding coroutine holds its own reference
  State state = State::no_bus;
  bool separate = false;     // put '\n' before every message (set once raw mode is confirmed)
  bool hang_up = false;      // close once the queued answers are written
  bool ended = false;
  std::uint64_t errors = 0;
  std::string scratch;
  asio::steady_timer raw_pause;  // raw_start_delay before forwarding; cancelled when the session ends
  // `< statistics >`: interval, the loop's generation, and this connection's counters.
  asio::steady_timer stats_timer;
  std::uint32_t stats_interval_ms = 0;
  std::uint64_t stats_generation = 0;
  sc::Stat counters;
  asio::steady_timer handshake_timer;  // until the first `< open >`

  void start() {
    server->sessions.push_back(this);
    ++server->stats.clients_accepted;
    ++server->stats.clients_active;
    spdlog::debug("socketcand: {} connected", peer);
    reply(sc::Hi{});
    asio::co_spawn(socket.get_executor(), read_loop(shared_from_this()), asio::detached);
    if (server->options.handshake_timeout > core::Duration::zero())
      asio::co_spawn(socket.get_executor(), handshake_watch(shared_from_this()), asio::detached);
  }

  // Closes the connection if no channel is open when the handshake time is up.
  static asio::awaitable<void> handshake_watch(std::shared_ptr<SocketcandSession> self) {
    self->handshake_timer.expires_after(self->server->options.handshake_timeout);
    boost::system::error_code ec;
    co_await self->handshake_timer.async_wait(asio::redirect_error(asio::use_awaitable, ec));
    if (self->ended || self->state != State::no_bus) co_return;
    ++self->server->stats.handshake_timeouts;
    spdlog::warn("socketcand: {}: no channel opened within {} ms; connection closed", self->peer,
                 std::chrono::duration_cast<std::chrono::milliseconds>(self->server->options.handshake_timeout).count());
    self->shut_down();
  }

  // Queues text for the client and keeps the high-water mark of its queue.
  void queue(std::string_view text, std::size_t units) {
    writer.write(text, units, shared_from_this());
    auto& high = server->stats.output_high_water;
    high = std::max<std::uint64_t>(high, writer.pending_bytes());
  }

  // Closes the connection now (server stop, read error).
  void shut_down() {
    boost::system::error_code ignored;
    socket.close(ignored);
    end();
  }

  void end() {
    if (ended) return;
    ended = true;
    state = State::no_bus;
    ++stats_generation;
    stats_timer.cancel();
    raw_pause.cancel();
    handshake_timer.cancel();
    if (bus) bus->close();
    bus.reset();
    writer.stop();
    boost::system::error_code ignored;
    socket.close(ignored);
    auto& list = server->sessions;
    list.erase(std::remove(list.begin(), list.end(), this), list.end());
    --server->stats.clients_active;
    spdlog::debug("socketcand: {} disconnected", peer);
  }

  void reply(const sc::Message& m) {
    scratch.clear();
    if (separate) scratch += '\n';
    sc::append(scratch, m);
    queue(scratch, 1);
  }

  // A client message the server rejects: answered, counted, logged (the first at warning level).
  void client_error(const std::string& why) {
    ++server->stats.errors;
    ++errors;
    if (errors == 1)
      spdlog::warn("socketcand: {}: {} (further errors from this client are logged at debug level)", peer, why);
    else
      spdlog::debug("socketcand: {}: {}", peer, why);
    reply(sc::ErrorText{why});
  }

  static asio::awaitable<void> read_loop(std::shared_ptr<SocketcandSession> self) {
    std::array<char, 4096> buf{};
    while (!self->ended) {
      while (auto r = self->tokenizer.next()) {
        // A client that does not read its answers is not served (nor read from: its requests
        // wait in the kernel) until it has, so that what is queued for it stays within the backlog.
        if (self->writer.pending_bytes() > self->server->options.client_backlog)
          co_await self->writer.wait_until_at_most(self->server->options.client_backlog);
        if (self->ended || self->hang_up || self->writer.failed()) break;
        if (*r)
          co_await self->handle(r->value());
        else
          self->client_error(r->error().detail);
      }
      if (self->ended) break;
      if (self->hang_up) {
        co_await self->writer.wait_until_at_most(0);
        break;
      }
      if (self->writer.failed()) break;
      boost::system::error_code ec;
      const std::size_t n =
          co_await self->socket.async_read_some(asio::buffer(buf), asio::redirect_error(asio::use_awaitable, ec));
      if (ec) break;
      self->tokenizer.feed(std::string_view(buf.data(), n));
    }
    self->end();
  }

  asio::awaitable<void> handle(const std::string& text) {
    auto parsed = sc::parse_terse(text);
    if (!parsed) {
      client_error(parsed.error().detail);
      co_return;
    }
    const sc::Message& m = parsed.value();
    if (std::holds_alternative<sc::Echo>(m)) {
      reply(sc::Echo{});
      co_return;
    }
    if (state == State::no_bus) {
      if (const auto* open = std::get_if<sc::Open>(&m))
        do_open(open->channel);
      else
        client_error(fmt::format("no channel open: '{}' needs '< open CHANNEL >' first", sc::keyword(m)));
      co_return;
    }
    if (const auto* mode = std::get_if<sc::Mode>(&m)) {
      switch_mode(mode->kind);
    } else if (const auto* send = std::get_if<sc::Send>(&m)) {
      if (state == State::control)
        client_error("frames cannot be sent in control mode");
      else
        co_await do_send(send->frame);
    } else if (const auto* st = std::get_if<sc::Statistics>(&m)) {
      if (state != State::control)
        client_error("'statistics' is only available in control mode");
      else
        set_statistics(st->interval_ms);
    } else if (std::holds_alternative<sc::Open>(m)) {
      client_error(fmt::format("channel {} is already open", channel));
    } else {
      client_error(fmt::format("'{}' is not a client command", sc::keyword(m)));
    }
  }

  Result<std::shared_ptr<Bus>> open_endpoint() {
    auto b = server->provider.open(channel, server->options.bus);
    if (!b) return b.error();
    std::shared_ptr<Bus> shared(std::move(b.value()));
    shared->set_filters({nothing_passes()});
    return shared;
  }

  void do_open(const std::string& name) {
    channel = name;
    auto b = open_endpoint();
    if (!b) {
      // As the daemon does: refuse and hang up.
      client_error(fmt::format("could not open bus {}", name));
      spdlog::info("socketcand: {}: open {} refused: {}", peer, name, b.error().message());
      hang_up = true;
      return;
    }
    bus = b.value();
    state = State::bcm;
    spdlog::debug("socketcand: {} opened {}", peer, name);
    reply(sc::Ok{});
  }

  void switch_mode(sc::Mode::Kind kind) {
    using K = sc::Mode::Kind;
    if (kind == K::isotp) return client_error("ISO-TP mode is not supported");
    const State target = kind == K::raw ? State::raw : kind == K::bcm ? State::bcm : State::control;
    if (target == state) return reply(sc::Ok{});
    if (state == State::raw) {
      // Leaving raw mode closes the endpoint (its forwarder ends) and opens a quiet one.
      raw_pause.cancel();
      bus->close();
      auto b = open_endpoint();
      if (!b) {
        client_error(fmt::format("could not reopen bus {}", channel));
        hang_up = true;
        return;
      }
      bus = b.value();
    }
    if (state == State::control) {
      ++stats_generation;
      stats_timer.cancel();
    }
    state = target;
    reply(sc::Ok{});
    if (target == State::raw) {
      bus->set_filters({});
      if (server->options.separate_messages) separate = true;
      asio::co_spawn(socket.get_executor(), forward(shared_from_this(), bus), asio::detached);
    } else if (target == State::control && stats_interval_ms > 0) {
      start_statistics();
    }
  }

  asio::awaitable<void> do_send(const Frame& frame) {
    auto endpoint = bus;  // the mode may change while we wait
    auto r = co_await endpoint->send(frame);
    if (!r) {
      ++server->stats.send_failures;
      client_error(fmt::format("could not send {}: {}", frame.to_string(), r.error().message()));
      co_return;
    }
    ++server->stats.frames_in;
    ++counters.tx_frames;
    counters.tx_bytes += frame.payload().size();
  }

  // Raw mode: every frame of the endpoint goes to the client until the endpoint is closed.
  static asio::awaitable<void> forward(std::shared_ptr<SocketcandSession> self, std::shared_ptr<Bus> endpoint) {
    const auto delay = self->server->options.raw_start_delay;
    if (delay > core::Duration::zero()) {
      self->raw_pause.expires_after(delay);
      boost::system::error_code ec;
      co_await self->raw_pause.async_wait(asio::redirect_error(asio::use_awaitable, ec));
    }
    std::string text;
    for (;;) {
      co_await self->writer.wait_until_at_most(self->server->options.client_backlog);
      if (self->ended || self->bus != endpoint || self->writer.failed()) co_return;
      auto f = co_await endpoint->receive();
      if (!f || self->ended || self->bus != endpoint) co_return;
      // Take whatever else is already queued too: one write for the batch.
      text.clear();
      std::size_t n = 0;
      for (std::optional<Frame> next = f.value(); next; next = endpoint->try_receive()) {
        Frame frame = *next;
        if (frame.timestamp() == core::WallTime::zero()) frame.set_timestamp(wall_now());
        if (self->separate) text += '\n';
        sc::append(text, sc::FrameMessage{frame});
        ++n;
        self->counters.rx_bytes += frame.payload().size();
        if (text.size() >= 16 * 1024) break;
      }
      self->counters.rx_frames += n;
      self->server->stats.frames_out += n;
      self->queue(text, n);
    }
  }

  void set_statistics(std::uint32_t interval_ms) {
    stats_interval_ms = interval_ms;
    ++stats_generation;
    stats_timer.cancel();
    if (interval_ms > 0) start_statistics();
  }

  void start_statistics() {
    asio::co_spawn(socket.get_executor(), statistics_loop(shared_from_this(), stats_generation), asio::detached);
  }

  static asio::awaitable<void> statistics_loop(std::shared_ptr<SocketcandSession> self, std::uint64_t generation) {
    for (;;) {
      // The daemon polls every 10 ms; shorter intervals make no sense.
      self->stats_timer.expires_after(std::chrono::milliseconds(std::max<std::uint32_t>(self->stats_interval_ms, 10)));
      boost::system::error_code ec;
      co_await self->stats_timer.async_wait(asio::redirect_error(asio::use_awaitable, ec));
      if (self->ended || generation != self->stats_generation || self->state != State::control) co_return;
      self->reply(self->counters);
    }
  }
};

SocketcandServer::SocketcandServer(Unbound, asio::any_io_executor ex, BusProvider& provider,
                                   SocketcandServerOptions options)
    : impl_(std::make_shared<Impl>(std::move(ex), provider, options)) {}

SocketcandServer::SocketcandServer(asio::any_io_executor ex, BusProvider& provider, net::Endpoint listen_on,
                                   SocketcandServerOptions options)
    : SocketcandServer(Unbound{}, std::move(ex), provider, options) {
  if (auto r = listen(listen_on); !r) throw Exception(r.error());
}

Result<std::unique_ptr<SocketcandServer>> SocketcandServer::create(asio::any_io_executor ex, BusProvider& provider,
                                                                   net::Endpoint listen_on,
                                                                   SocketcandServerOptions options) {
  std::unique_ptr<SocketcandServer> server(new SocketcandServer(Unbound{}, std::move(ex), provider, options));
  AXON_TRY(server->listen(listen_on));
  return server;
}

Result<void> SocketcandServer::listen(const net::Endpoint& where) {
  auto fail = [&](const std::string& what, const boost::system::error_code& ec) {
    return Error(CanErrc::io, fmt::format("socketcand server on {}: {}: {}", where.to_string(), what, ec.message()));
  };
  boost::system::error_code ec;
  tcp::resolver resolver(impl_->ex);
  const auto results = resolver.resolve(where.host, std::to_string(where.port), tcp::resolver::passive, ec);
  if (ec || results.empty()) return fail("resolving the address", ec);
  const tcp::endpoint ep = results.begin()->endpoint();
  auto& acc = impl_->acceptor;
  acc.open(ep.protocol(), ec);
  if (ec) return fail("opening the socket", ec);
  acc.set_option(asio::socket_base::reuse_address(true), ec);
  acc.bind(ep, ec);
  if (ec) return fail("binding", ec);
  acc.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) return fail("listening", ec);
  const auto local = acc.local_endpoint(ec);
  if (ec) return fail("reading the bound address", ec);
  impl_->bound = net::Endpoint{local.address().to_string(), local.port()};

  asio::co_spawn(
      impl_->ex,
      [](std::shared_ptr<Impl> impl) -> asio::awaitable<void> {
        for (;;) {
          tcp::socket socket(impl->ex);
          boost::system::error_code ec;
          co_await impl->acceptor.async_accept(socket, asio::redirect_error(asio::use_awaitable, ec));
          if (impl->stopped) co_return;
          if (ec) {
            // Out of descriptors and the like: log, breathe, retry.
            spdlog::warn("socketcand server: accept failed: {}", ec.message());
            asio::steady_timer pause(impl->ex, std::chrono::milliseconds(100));
            co_await pause.async_wait(asio::redirect_error(asio::use_awaitable, ec));
            if (impl->stopped) co_return;
            continue;
          }
          if (impl->sessions.size() >= impl->options.max_clients) {
            ++impl->stats.clients_rejected;
            if (!impl->refusing)
              spdlog::warn("socketcand server: refusing a client: {} already connected (further refusals logged at "
                           "debug level until one is accepted)", impl->sessions.size());
            else
              spdlog::debug("socketcand server: refusing a client: {} already connected", impl->sessions.size());
            impl->refusing = true;
            socket.close(ec);
            continue;
          }
          impl->refusing = false;
          socket.set_option(tcp::no_delay(true), ec);
          std::make_shared<SocketcandSession>(impl, std::move(socket))->start();
        }
      }(impl_),
      asio::detached);
  return ok();
}

SocketcandServer::~SocketcandServer() { stop(); }

net::Endpoint SocketcandServer::local_endpoint() const { return impl_->bound; }

const SocketcandServerStats& SocketcandServer::stats() const noexcept { return impl_->stats; }

void SocketcandServer::stop() {
  if (impl_->stopped) return;
  impl_->stopped = true;
  boost::system::error_code ignored;
  impl_->acceptor.close(ignored);
  // shut_down() removes the session from the list.
  const auto sessions = impl_->sessions;
  for (SocketcandSession* s : sessions) s->shut_down();
}

}  // namespace axon::can
