#include "axon/can/cannet_server.hpp"

#include "axon/core/wakeup.hpp"

#include <boost/asio/redirect_error.hpp>
#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/write.hpp>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <optional>

namespace axon::can {

using namespace cannet;

namespace {

using tcp = asio::ip::tcp;

// The emulator's R ERR numbers (the device's own list is not public beyond "1 invalid baudrate").
enum ErrNo : int {
  kErrBaudrate = 1,     // INIT with a rate the device does not offer
  kErrPort = 2,         // a channel with no bus behind it
  kErrSyntax = 3,       // a line that does not parse
  kErrNotCommand = 4,   // a line a host does not send (R ..., E ...)
  kErrState = 5,        // START before INIT
  kErrFilterFull = 6,   // more than kMaxFilters entries
};
constexpr std::size_t kMaxFilters = 64;
constexpr std::size_t kMaxErrorText = 160;

// Error text as it may go on the wire: printable ASCII, one line, bounded.
std::string wire_text(std::string_view text) {
  std::string out;
  for (const char c : text.substr(0, kMaxErrorText)) {
    const auto u = static_cast<unsigned char>(c);
    out.push_back(u < 0x20 || u >= 0x7F ? '?' : c);
  }
  while (!out.empty() && out.back() == ' ') out.pop_back();
  return out;
}

bool filter_passes(const std::vector<CanFilterAdd>& filters, const Frame& f) {
  bool any_of_format = false;
  for (const auto& e : filters) {
    if (e.format != f.format()) continue;
    any_of_format = true;
    if (((e.id ^ f.id()) & e.mask) == 0) return true;
  }
  return !any_of_format;
}

}  // namespace

struct CanNetGatewayEmulator::Impl : std::enable_shared_from_this<CanNetGatewayEmulator::Impl> {
  struct Connection {
    Connection(tcp::socket s, std::uint64_t n, std::string p) : socket(std::move(s)), id(n), peer(std::move(p)) {}
    tcp::socket socket;
    std::uint64_t id;
    std::string peer;               // the client's address, for the log
    bool open = true;
    bool spoke = false;             // it sent at least one line
    std::uint64_t errors = 0;       // R ERR answers it got
    std::string out;                // lines waiting for the writer
    std::size_t in_flight = 0;      // bytes the writer is writing now
    core::Wakeup* writer_idle = nullptr;  // the writer, when it has nothing to write
    core::Wakeup* reader_blocked = nullptr;  // the reader, while too much waits for the client

    [[nodiscard]] std::size_t pending() const noexcept { return out.size() + in_flight; }
  };
  struct Channel {
    std::string name;               // provider channel; empty: not fitted
    std::unique_ptr<Bus> endpoint;  // opened by start()
    bool initialized = false;       // INIT seen since the connection began
    bool running = false;           // START seen (and no STOP/INIT since)
    bool bus_off = false;
    bool error_warning = false;
    bool overrun = false;           // frames for the client were lost
    std::vector<CanFilterAdd> filters;

    void reset() {
      initialized = running = bus_off = error_warning = overrun = false;
      filters.clear();
    }
  };

  Impl(asio::any_io_executor ex, BusProvider& p, CanNetEmulatorOptions opts)
      : executor(std::move(ex)), provider(&p), options(std::move(opts)), acceptor(executor) {}

  asio::any_io_executor executor;
  BusProvider* provider;
  CanNetEmulatorOptions options;
  std::array<Channel, kMaxChannel + 1> chan{};  // indexed by channel number
  tcp::acceptor acceptor;
  std::shared_ptr<Connection> client;
  std::uint64_t next_connection = 1;
  CanNetEmulatorStats stats;
  bool started = false;
  bool stopped = false;

  Result<void> start();
  void stop(bool reset = false);
  // "HOST:PORT" where it listens, for log lines.
  [[nodiscard]] std::string local_text() const {
    boost::system::error_code ec;
    const auto ep = acceptor.local_endpoint(ec);
    return ec ? options.bind_address : net::Endpoint{ep.address().to_string(), ep.port()}.to_string();
  }

  static asio::awaitable<void> run_acceptor(std::shared_ptr<Impl> self);
  static asio::awaitable<void> run_reader(std::shared_ptr<Impl> self, std::shared_ptr<Connection> conn);
  static asio::awaitable<void> run_writer(std::shared_ptr<Impl> self, std::shared_ptr<Connection> conn);
  static asio::awaitable<void> run_pump(std::shared_ptr<Impl> self, int channel);

  void attach(tcp::socket socket);
  // reset: abort the connection (RST) instead of closing it in order (FIN).
  void drop(std::shared_ptr<Connection> conn, std::string_view why, bool reset = false);
  void send(Connection& conn, std::string_view line) {
    if (!conn.open) return;
    conn.out.append(line);
    conn.out.push_back('\n');
    stats.output_high_water = std::max<std::uint64_t>(stats.output_high_water, conn.pending());
    if (conn.writer_idle) conn.writer_idle->notify();
  }
  // An R ERR for the client: counted, and logged once per connection at warning level.
  void send_error(Connection& conn, int code, std::string_view text) {
    ++stats.error_replies;
    if (++conn.errors == 1)
      spdlog::warn("CAN@net emulator: client {}: R ERR {} {} (further errors of this client at debug level)", conn.peer,
                   code, wire_text(text));
    else
      spdlog::debug("CAN@net emulator: client {}: R ERR {} {}", conn.peer, code, wire_text(text));
    send(conn, refuse(code, text));
  }
  // Waits while more than max_output_bytes wait for the client (it does not read).
  asio::awaitable<void> wait_for_room(const std::shared_ptr<Connection>& conn) {
    while (conn->open && conn->pending() > options.max_output_bytes) {
      core::Wakeup drained(executor);
      conn->reader_blocked = &drained;
      core::OnExit clear{[&conn] { conn->reader_blocked = nullptr; }};
      co_await drained.wait();
    }
  }
  void send(Connection& conn, const Line& line) { send(conn, std::string_view(format_line(line))); }
  void send_to_client(const Line& line) {
    if (client) send(*client, line);
  }

  // Handles a command line (answering it) or a bad one; returns the frame of a frame line for the
  // reader to forward (the only kind of line that may have to wait).
  std::optional<FrameMessage> handle_line(Connection& conn, std::string_view text);
  // Forwarding a client frame to its channel's bus: whether the channel takes frames now (else
  // the frame is discarded and counted), and the bookkeeping once the bus has answered.
  bool accepts_frames(int channel);
  void sent_to_bus(Connection& conn, int channel, const Result<void>& sent);
  Line answer(const Line& command);
  ReplyStatus status(int channel) const;
  [[nodiscard]] bool fitted(int channel) const { return chan[static_cast<std::size_t>(channel)].endpoint != nullptr; }
  static Line refuse(int code, std::string_view text) { return ReplyError{code, wire_text(text)}; }
};

// ---- life cycle ----

Result<void> CanNetGatewayEmulator::Impl::start() {
  if (started) return ok();
  if (options.tx_fifo == 0 || options.tx_fifo > kTxFifoCapacity)
    return Error(CanErrc::bad_spec, fmt::format("CAN@net emulator: tx_fifo {} is not 1..{}", options.tx_fifo, kTxFifoCapacity));
  for (int ch = kMinChannel; ch <= kMaxChannel; ++ch) {
    auto& c = chan[static_cast<std::size_t>(ch)];
    if (c.name.empty()) continue;
    BusOptions bo;
    bo.rx_capacity = options.rx_capacity;
    bo.tx_capacity = options.tx_fifo;
    auto endpoint = provider->open(c.name, bo);
    if (!endpoint) return endpoint.error();
    c.endpoint = std::move(endpoint).value();
  }
  boost::system::error_code ec;
  const auto address = asio::ip::make_address(options.bind_address, ec);
  if (ec) return Error(CanErrc::io, fmt::format("CAN@net emulator: bind address '{}': {}", options.bind_address, ec.message()));
  const tcp::endpoint where(address, options.port);
  acceptor.open(where.protocol(), ec);
  if (!ec) acceptor.set_option(tcp::acceptor::reuse_address(true), ec);
  if (!ec) acceptor.bind(where, ec);
  if (!ec) acceptor.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) {
    boost::system::error_code ignored;
    acceptor.close(ignored);
    return Error(CanErrc::io, fmt::format("CAN@net emulator: listen on {}:{}: {}", options.bind_address, options.port, ec.message()));
  }
  started = true;
  asio::co_spawn(executor, run_acceptor(shared_from_this()), asio::detached);
  for (int ch = kMinChannel; ch <= kMaxChannel; ++ch)
    if (fitted(ch)) asio::co_spawn(executor, run_pump(shared_from_this(), ch), asio::detached);
  const auto local = acceptor.local_endpoint(ec);
  spdlog::info("CAN@net emulator listening on {}:{}", local.address().to_string(), local.port());
  return ok();
}

void CanNetGatewayEmulator::Impl::stop(bool reset) {
  if (stopped) return;
  stopped = true;
  boost::system::error_code ignored;
  acceptor.close(ignored);
  if (client) drop(client, reset ? "power lost" : "emulator stopped", reset);
  for (auto& c : chan)
    if (c.endpoint) c.endpoint->close();
}

asio::awaitable<void> CanNetGatewayEmulator::Impl::run_acceptor(std::shared_ptr<Impl> self) {
  Impl& s = *self;
  while (!s.stopped) {
    boost::system::error_code ec;
    tcp::socket socket = co_await s.acceptor.async_accept(asio::redirect_error(asio::use_awaitable, ec));
    if (s.stopped) co_return;
    if (ec) {
      // Out of descriptors and the like: say so and retry a little later rather than spin.
      spdlog::warn("CAN@net emulator: accept failed: {}", ec.message());
      asio::steady_timer pause(s.executor, std::chrono::milliseconds(100));
      co_await pause.async_wait(asio::redirect_error(asio::use_awaitable, ec));
      continue;
    }
    s.attach(std::move(socket));
  }
}

void CanNetGatewayEmulator::Impl::attach(tcp::socket socket) {
  boost::system::error_code ignored;
  socket.set_option(tcp::no_delay(true), ignored);
  const auto remote = socket.remote_endpoint(ignored);
  const std::string peer = net::Endpoint{remote.address().to_string(), remote.port()}.to_string();
  if (client) {
    // As the device does: the newest connection wins. Its ASCII protocol has no message for this,
    // so the old client only sees its connection closed; the log says who took over.
    ++stats.replaced;
    if (client->spoke)
      spdlog::warn("CAN@net emulator {}: client {} takes over from client {}, whose connection is closed",
                   local_text(), peer, client->peer);
    else
      spdlog::debug("CAN@net emulator {}: client {} takes over from client {}, which had said nothing", local_text(),
                    peer, client->peer);
    drop(client, fmt::format("replaced by a newer connection from {}", peer));
  }
  for (auto& c : chan) c.reset();
  auto conn = std::make_shared<Connection>(std::move(socket), next_connection++, peer);
  client = conn;
  ++stats.connections;
  spdlog::debug("CAN@net emulator {}: client {} connected", local_text(), peer);
  asio::co_spawn(executor, run_reader(shared_from_this(), conn), asio::detached);
  asio::co_spawn(executor, run_writer(shared_from_this(), conn), asio::detached);
}

void CanNetGatewayEmulator::Impl::drop(std::shared_ptr<Connection> conn, std::string_view why, bool reset) {
  if (!conn->open) return;
  conn->open = false;
  spdlog::debug("CAN@net emulator: connection {} ({}) closed: {}", conn->id, conn->peer, why);
  boost::system::error_code ignored;
  if (reset)
    conn->socket.set_option(asio::socket_base::linger(true, 0), ignored);  // close() then sends RST
  else
    conn->socket.shutdown(tcp::socket::shutdown_both, ignored);
  conn->socket.close(ignored);
  if (conn->writer_idle) conn->writer_idle->notify();
  if (conn->reader_blocked) conn->reader_blocked->notify();
  if (client == conn) client.reset();
}

// ---- connection ----

asio::awaitable<void> CanNetGatewayEmulator::Impl::run_reader(std::shared_ptr<Impl> self, std::shared_ptr<Connection> conn) {
  Impl& s = *self;
  std::array<char, 4096> buf{};
  LineSplitter lines;
  while (conn->open) {
    boost::system::error_code ec;
    const std::size_t n = co_await conn->socket.async_read_some(asio::buffer(buf), asio::redirect_error(asio::use_awaitable, ec));
    if (ec) {
      s.drop(conn, ec == asio::error::eof ? "client closed the connection" : ec.message());
      co_return;
    }
    lines.append(std::string_view(buf.data(), n));
    while (conn->open) {
      // A client that does not read its answers is not served until it has (nor read from: its
      // commands wait in the kernel), so that what waits for it stays bounded.
      if (conn->pending() > s.options.max_output_bytes) co_await s.wait_for_room(conn);
      if (!conn->open) break;
      auto piece = lines.next();
      if (!piece) break;
      conn->spoke = true;
      if (piece->overlong) {
        ++s.stats.commands;
        s.send_error(*conn, kErrSyntax, fmt::format("line longer than {} characters", kMaxLineLength));
        continue;
      }
      auto m = s.handle_line(*conn, piece->text);
      if (!m || !s.accepts_frames(m->channel)) continue;
      // The frame is forwarded here rather than in a coroutine of its own: one coroutine frame
      // less per frame, and the reader keeps the client's order by waiting for each.
      auto& c = s.chan[static_cast<std::size_t>(m->channel)];
      // A full FIFO: first let the medium take what it can right now (an unpaced bus empties it
      // at once; a paced one only as fast as its wire).
      if (c.endpoint->tx_pending() >= s.options.tx_fifo) co_await asio::post(s.executor, asio::use_awaitable);
      if (!c.endpoint) continue;
      const Frame frame = m->frame;
      auto sent = co_await c.endpoint->send(frame);
      s.sent_to_bus(*conn, m->channel, sent);
    }
  }
}

asio::awaitable<void> CanNetGatewayEmulator::Impl::run_writer(std::shared_ptr<Impl> self, std::shared_ptr<Connection> conn) {
  Impl& s = *self;
  std::string chunk;
  while (conn->open) {
    if (conn->out.empty()) {
      core::Wakeup idle(s.executor);
      conn->writer_idle = &idle;
      core::OnExit clear{[&conn] { conn->writer_idle = nullptr; }};
      co_await idle.wait();
      continue;
    }
    chunk.clear();
    chunk.swap(conn->out);
    conn->in_flight = chunk.size();
    boost::system::error_code ec;
    co_await asio::async_write(conn->socket, asio::buffer(chunk), asio::redirect_error(asio::use_awaitable, ec));
    conn->in_flight = 0;
    if (conn->reader_blocked) conn->reader_blocked->notify();
    if (ec) {
      s.drop(conn, fmt::format("write failed: {}", ec.message()));
      co_return;
    }
  }
}

std::optional<FrameMessage> CanNetGatewayEmulator::Impl::handle_line(Connection& conn, std::string_view text) {
  if (std::all_of(text.begin(), text.end(), [](char c) { return c == ' ' || c == '\t' || c == '\r'; })) return std::nullopt;
  auto parsed = parse_line(text);
  if (!parsed) {
    ++stats.commands;
    send_error(conn, kErrSyntax, parsed.error().detail);
    return std::nullopt;
  }
  const Line& line = parsed.value();
  if (const auto* m = std::get_if<FrameMessage>(&line)) return *m;
  ++stats.commands;
  if (!is_host_command(line)) {
    send_error(conn, kErrNotCommand, fmt::format("'{}' is not a host command", format_line(line)));
    return std::nullopt;
  }
  Line reply = answer(line);
  if (const auto* e = std::get_if<ReplyError>(&reply)) send_error(conn, e->code, e->text);
  else send(conn, reply);
  return std::nullopt;
}

bool CanNetGatewayEmulator::Impl::accepts_frames(int channel) {
  const auto& c = chan[static_cast<std::size_t>(channel)];
  if (!c.endpoint || !c.running || c.bus_off) {  // the device discards these without a word
    ++stats.not_running_drops;
    return false;
  }
  return true;
}

void CanNetGatewayEmulator::Impl::sent_to_bus(Connection& conn, int channel, const Result<void>& sent) {
  if (sent) {
    ++stats.frames_to_bus;
    return;
  }
  if (sent.error() == CanErrc::tx_overflow) {
    ++stats.tx_overflow_drops;
    if (options.report_tx_overflow) send(conn, Line{Event{channel, EventKind::tx_overflow, true, 1}});
    return;
  }
  ++stats.not_running_drops;
  spdlog::debug("CAN@net emulator: channel {}: frame not sent: {}", channel, sent.error().message());
}

asio::awaitable<void> CanNetGatewayEmulator::Impl::run_pump(std::shared_ptr<Impl> self, int channel) {
  Impl& s = *self;
  auto& c = s.chan[static_cast<std::size_t>(channel)];
  for (;;) {
    auto frame = co_await c.endpoint->receive();
    if (!frame) co_return;  // endpoint closed: the emulator stops
    const auto& conn = s.client;
    if (!conn || !c.running || c.bus_off) {  // nobody to tell, or the channel is not on the bus
      ++s.stats.bus_frames_discarded;
      continue;
    }
    if (!filter_passes(c.filters, frame.value())) {
      ++s.stats.filtered;
      continue;
    }
    if (conn->pending() >= s.options.max_output_bytes) {
      ++s.stats.output_drops;
      c.overrun = true;
      continue;
    }
    FrameLineBuffer text;
    s.send(*conn, format_frame_to(text, channel, frame.value()));
    ++s.stats.frames_to_client;
  }
}

// ---- commands ----

ReplyStatus CanNetGatewayEmulator::Impl::status(int channel) const {
  const auto& c = chan[static_cast<std::size_t>(channel)];
  const std::size_t pending = c.endpoint ? c.endpoint->tx_pending() : 0;
  const std::uint32_t used = static_cast<std::uint32_t>(std::min<std::size_t>(pending, options.tx_fifo));
  StatusFlags f;
  f.bus_off = c.bus_off;
  f.error_warning = c.error_warning;
  f.data_overrun = c.overrun;
  f.tx_pending = pending > 0;
  f.stopped = !c.running;
  return ReplyStatus{channel, f, options.tx_fifo - used};
}

Line CanNetGatewayEmulator::Impl::answer(const Line& command) {
  if (std::holds_alternative<DevIdentify>(command)) return ReplyText{wire_text(options.identify)};
  if (std::holds_alternative<DevVersion>(command)) return ReplyText{wire_text(options.version)};
  const int ch = std::visit(
      [](const auto& cmd) -> int {
        if constexpr (requires { cmd.channel; }) return cmd.channel;
        return 0;
      },
      command);
  if (!fitted(ch)) return refuse(kErrPort, fmt::format("port {} not available", ch));
  auto& c = chan[static_cast<std::size_t>(ch)];
  if (std::holds_alternative<CanStop>(command)) {
    c.running = false;
    return ReplyOk{};
  }
  if (std::holds_alternative<CanStart>(command)) {
    if (!c.initialized) return refuse(kErrState, "port not initialized");
    c.running = true;
    c.bus_off = false;
    return ReplyOk{};
  }
  if (const auto* init = std::get_if<CanInit>(&command)) {
    if (!is_standard_bitrate(init->bitrate)) return refuse(kErrBaudrate, "invalid baudrate");
    c.initialized = true;
    c.running = false;
    c.bus_off = c.error_warning = c.overrun = false;
    if (c.endpoint->options().bitrate != init->bitrate)
      spdlog::warn("CAN@net emulator: channel {} set to {} kbit/s, but its bus '{}' runs at {} kbit/s", ch,
                   format_kbit(init->bitrate), c.name, format_kbit(c.endpoint->options().bitrate));
    return ReplyOk{};
  }
  if (std::holds_alternative<CanFilterClear>(command)) {
    c.filters.clear();
    return ReplyOk{};
  }
  if (const auto* add = std::get_if<CanFilterAdd>(&command)) {
    if (c.filters.size() >= kMaxFilters) return refuse(kErrFilterFull, "filter table full");
    c.filters.push_back(*add);
    return ReplyOk{};
  }
  if (std::holds_alternative<CanStatusRequest>(command)) return status(ch);
  return refuse(kErrNotCommand, "unsupported command");
}

// ---- CanNetGatewayEmulator ----

CanNetGatewayEmulator::CanNetGatewayEmulator(asio::any_io_executor executor, BusProvider& provider,
                                             std::vector<std::string> channels, CanNetEmulatorOptions options)
    : impl_(std::make_shared<Impl>(std::move(executor), provider, std::move(options))) {
  if (channels.size() > static_cast<std::size_t>(kMaxChannel))
    throw Exception(Error(CanErrc::bad_spec, fmt::format("CAN@net emulator: {} channels given, the gateway has {}",
                                                         channels.size(), kMaxChannel)));
  for (std::size_t i = 0; i < channels.size(); ++i) impl_->chan[i + 1].name = std::move(channels[i]);
}

CanNetGatewayEmulator::~CanNetGatewayEmulator() { stop(); }

Result<void> CanNetGatewayEmulator::start() { return impl_->start(); }
void CanNetGatewayEmulator::stop() { impl_->stop(); }
void CanNetGatewayEmulator::power_off() { impl_->stop(true); }

net::Endpoint CanNetGatewayEmulator::local_endpoint() const {
  boost::system::error_code ec;
  const auto ep = impl_->acceptor.local_endpoint(ec);
  if (ec) return net::Endpoint{impl_->options.bind_address, 0};
  return net::Endpoint{ep.address().to_string(), ep.port()};
}

bool CanNetGatewayEmulator::has_client() const noexcept { return impl_->client != nullptr; }
const CanNetEmulatorStats& CanNetGatewayEmulator::stats() const noexcept { return impl_->stats; }

ReplyStatus CanNetGatewayEmulator::status(int channel) const {
  if (check_channel(channel).has_error()) throw Exception(check_channel(channel).error());
  return impl_->status(channel);
}

void CanNetGatewayEmulator::inject_bus_off(int channel) {
  if (check_channel(channel).has_error()) throw Exception(check_channel(channel).error());
  impl_->chan[static_cast<std::size_t>(channel)].bus_off = true;
  impl_->send_to_client(Event{channel, EventKind::bus_off, true, 0});
}

void CanNetGatewayEmulator::inject_error_warning(int channel, bool set) {
  if (check_channel(channel).has_error()) throw Exception(check_channel(channel).error());
  impl_->chan[static_cast<std::size_t>(channel)].error_warning = set;
  impl_->send_to_client(Event{channel, EventKind::error_warning, set, 0});
}

void CanNetGatewayEmulator::send_raw(std::string_view line) {
  if (impl_->client) impl_->send(*impl_->client, line);
}

}  // namespace axon::can
