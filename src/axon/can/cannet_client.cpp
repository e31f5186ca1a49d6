#include "axon/can/cannet_client.hpp"

#include "axon/core/wakeup.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/connect.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/redirect_error.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/use_awaitable.hpp>
#include <boost/asio/write.hpp>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <deque>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <optional>

namespace axon::can {

using namespace cannet;

namespace {

using tcp = asio::ip::tcp;

// Bytes of frames queued for the socket before send() waits for the writer to catch up.
constexpr std::size_t kOutputHighWater = 64 * 1024;

std::string host_port(const net::Endpoint& ep) {
  if (ep.host.find(':') != std::string::npos) return fmt::format("[{}]:{}", ep.host, ep.port);
  return fmt::format("{}:{}", ep.host, ep.port);
}

long long millis(core::Duration d) { return std::chrono::duration_cast<std::chrono::milliseconds>(d).count(); }

class CanNetBus;

}  // namespace

struct CanNetGateway::Impl : std::enable_shared_from_this<CanNetGateway::Impl> {
  struct Channel {
    CanNetBus* bus = nullptr;  // the open bus, if any
    BusState state = BusState::active;  // as the gateway last reported it
  };
  struct PendingReply {
    explicit PendingReply(const asio::any_io_executor& ex) : waiter(ex) {}
    core::Wakeup waiter;
    std::optional<Line> reply;
  };

  Impl(asio::any_io_executor ex, net::Endpoint ep, std::vector<int> chans, CanNetOptions opts)
      : executor(std::move(ex)),
        endpoint(std::move(ep)),
        where(fmt::format("CAN@net gateway {}", host_port(endpoint))),
        channels(std::move(chans)),
        options(opts),
        socket(executor) {}

  asio::any_io_executor executor;
  net::Endpoint endpoint;
  std::string where;  // for messages: "CAN@net gateway host:port"
  std::vector<int> channels;
  CanNetOptions options;
  tcp::socket socket;
  bool connected = false;
  std::uint64_t generation = 0;  // of the connection; a reader or writer of an older one ends
  bool host_closed = false;      // close() was called: no reconnection any more
  bool reconnecting = false;
  DisconnectKind down_kind = DisconnectKind::by_host;
  Error down_error{CanErrc::closed, "not connected"};
  CanNetGatewayStats stats;
  bool protocol_error_logged = false;
  std::array<Channel, kMaxChannel + 1> chan{};  // indexed by channel number

  // A frame line whose sender waits for room in `out` (more than kOutputHighWater queued). The
  // writer moves waiting lines into `out` itself, oldest first, as room appears, and new frames
  // queue behind waiting ones: frames go out in the order send() was called, always.
  struct SpaceWaiter {
    explicit SpaceWaiter(const asio::any_io_executor& ex, std::string_view l) : wake(ex), line(l) {}
    core::Wakeup wake;
    std::string line;
    bool queued = false;
  };

  std::string out;                  // lines waiting for the writer
  core::Wakeup* writer_idle = nullptr;    // the writer, when it has nothing to write
  std::deque<SpaceWaiter*> space_waiters;  // in order of their send() calls

  bool command_busy = false;        // a command is in flight (or being sent)
  std::deque<core::Wakeup*> command_queue;
  PendingReply* pending = nullptr;  // the command in flight

  // ---- connection ----

  asio::awaitable<Result<void>> open();
  void start();
  static asio::awaitable<void> run_reader(std::shared_ptr<Impl> self);
  static asio::awaitable<void> run_writer(std::shared_ptr<Impl> self);
  void connection_down(Error why, DisconnectKind kind);
  void set_keepalive();
  void close_buses();

  // ---- output ----

  void queue_line(std::string_view line) {
    out.append(line);
    out.push_back('\n');
    ++stats.lines_out;
    if (writer_idle) writer_idle->notify();
  }
  // A frame line can go straight into `out`: nothing waits for room and there is room.
  [[nodiscard]] bool room_now() const noexcept { return space_waiters.empty() && out.size() < kOutputHighWater; }
  // Waits (in turn) until the writer has moved the line into `out`.
  asio::awaitable<Result<void>> queue_in_turn(std::string_view line);
  // After a write: moves waiting lines into `out` while there is room, oldest first.
  void admit_waiters() {
    while (!space_waiters.empty() && out.size() < kOutputHighWater) {
      SpaceWaiter* w = space_waiters.front();
      space_waiters.pop_front();
      queue_line(w->line);
      w->queued = true;
      w->wake.notify();
    }
  }
  // Lines queued or being written (0 once the writer is idle with nothing queued).
  [[nodiscard]] std::size_t output_pending() const noexcept {
    const auto lines = static_cast<std::size_t>(std::count(out.begin(), out.end(), '\n')) + space_waiters.size();
    return connected && writer_idle == nullptr ? lines + 1 : lines;
  }

  // ---- input ----

  void handle_line(std::string_view text);
  void handle_reply(Line line);
  void handle_event(const Event& e);
  void protocol_error(std::string_view what);

  // ---- commands ----

  asio::awaitable<Result<Line>> transact(const Line& command);
  asio::awaitable<Result<void>> set_up(int channel);
  Result<void> check_open() const {
    if (!connected) return down_error;
    return ok();
  }
};

namespace {

class CanNetBus final : public Bus {
 public:
  CanNetBus(std::shared_ptr<CanNetGateway> gateway, CanNetGateway::Impl& impl, int channel, BusOptions options,
            std::string name)
      : Bus(impl.executor, std::move(name), options), gateway_(std::move(gateway)), impl_(&impl), channel_(channel) {}
  ~CanNetBus() override { unregister(); }

  asio::awaitable<Result<void>> send(const Frame& f) override {
    const Frame frame = f;
    if (!impl_->connected) co_return impl_->down_error;  // io when lost, closed when closed by the host
    if (!is_open()) co_return Error(CanErrc::closed, name());
    if (state() == BusState::bus_off)
      co_return Error(CanErrc::bus_off, fmt::format("{}: the channel is bus-off; restart it first", name()));
    cannet::FrameLineBuffer text;
    const std::string_view line = format_frame_to(text, channel_, frame);
    if (impl_->room_now()) {
      impl_->queue_line(line);
    } else {
      const auto waiters = this->waiters();  // the bus may be destroyed while the line waits
      auto r = co_await impl_->queue_in_turn(line);
      if (waiters->bus_gone) co_return Error(CanErrc::closed, "the bus was destroyed while a send() waited");
      if (!r) co_return r.error();
    }
    count_sent(frame);
    co_return ok();
  }

  void close() override {
    unregister();
    Bus::close();
  }

  // Lines of this gateway connection not yet handed to the socket (shared by its channels).
  [[nodiscard]] std::size_t tx_pending() const noexcept override { return impl_->output_pending(); }

  // Gateway side.
  void on_frame(Frame f) { deliver(std::move(f)); }
  void on_state(BusState s) { set_state(s); }
  void on_tx_dropped(std::uint32_t n) { mutable_stats().tx_dropped += n; }
  void on_protocol_error() { ++mutable_stats().protocol_errors; }
  void on_connection_down() { Bus::close(); }

 private:
  void unregister() noexcept {
    auto& slot = impl_->chan[static_cast<std::size_t>(channel_)];
    if (slot.bus == this) slot.bus = nullptr;
  }

  std::shared_ptr<CanNetGateway> gateway_;  // keeps the connection alive while the bus exists
  CanNetGateway::Impl* impl_;
  int channel_;
};

}  // namespace

// ---- connection ----

void CanNetGateway::Impl::close_buses() {
  for (auto& c : chan)
    if (c.bus) c.bus->on_connection_down();
}

asio::awaitable<Result<void>> CanNetGateway::Impl::open() {
  auto self = shared_from_this();
  auto resolver = std::make_shared<tcp::resolver>(executor);
  auto finished = std::make_shared<bool>(false);
  auto timed_out = std::make_shared<bool>(false);
  asio::steady_timer watchdog(executor);
  watchdog.expires_after(options.connect_timeout);
  watchdog.async_wait([self, resolver, finished, timed_out](const boost::system::error_code& ec) {
    if (ec || *finished) return;
    *timed_out = true;
    resolver->cancel();
    boost::system::error_code ignored;
    self->socket.close(ignored);
  });
  boost::system::error_code ec;
  auto results = co_await resolver->async_resolve(endpoint.host, std::to_string(endpoint.port),
                                                  asio::redirect_error(asio::use_awaitable, ec));
  if (!ec && !*timed_out) co_await asio::async_connect(socket, results, asio::redirect_error(asio::use_awaitable, ec));
  *finished = true;
  watchdog.cancel();
  if (*timed_out)
    co_return Error(CanErrc::connect_failed, fmt::format("{}: no connection within {} ms", where, millis(options.connect_timeout)));
  if (ec) co_return Error(CanErrc::connect_failed, fmt::format("{}: {}", where, ec.message()));
  boost::system::error_code ignored;
  socket.set_option(tcp::no_delay(true), ignored);
  set_keepalive();
  connected = true;
  co_return ok();
}

void CanNetGateway::Impl::set_keepalive() {
  const auto idle = std::chrono::duration_cast<std::chrono::seconds>(options.keepalive).count();
  if (options.keepalive <= core::Duration::zero()) return;
  boost::system::error_code ignored;
  socket.set_option(asio::socket_base::keep_alive(true), ignored);
  socket.set_option(asio::detail::socket_option::integer<IPPROTO_TCP, TCP_KEEPIDLE>(static_cast<int>(std::max<long long>(idle, 1))),
                    ignored);
  socket.set_option(asio::detail::socket_option::integer<IPPROTO_TCP, TCP_KEEPINTVL>(1), ignored);
  socket.set_option(asio::detail::socket_option::integer<IPPROTO_TCP, TCP_KEEPCNT>(3), ignored);
}

void CanNetGateway::Impl::start() {
  asio::co_spawn(executor, run_reader(shared_from_this()), asio::detached);
  asio::co_spawn(executor, run_writer(shared_from_this()), asio::detached);
}

asio::awaitable<void> CanNetGateway::Impl::run_reader(std::shared_ptr<Impl> self) {
  Impl& s = *self;
  const std::uint64_t generation = s.generation;
  std::array<char, 4096> buf{};
  LineSplitter lines;
  while (s.generation == generation) {
    boost::system::error_code ec;
    const std::size_t n = co_await s.socket.async_read_some(asio::buffer(buf), asio::redirect_error(asio::use_awaitable, ec));
    if (s.generation != generation) co_return;  // that connection is gone (and maybe replaced)
    if (ec == asio::error::eof) {
      // A reset that a write saw first leaves the read only an end-of-stream (the write took the
      // socket's error): let that write's completion, already queued, say so before calling this
      // an orderly close.
      co_await asio::post(s.executor, asio::use_awaitable);
      if (s.generation != generation) co_return;
    }
    if (ec) {
      // An orderly close from the gateway's side: it serves one client at a time and closes the
      // older connection when another client connects (its protocol has no line to say so).
      s.connection_down(Error(CanErrc::io, ec == asio::error::eof
                                               ? fmt::format("{}: the gateway closed the connection: another client "
                                                             "has probably taken the gateway over (it serves one client "
                                                             "at a time), or it restarted",
                                                             s.where)
                                               : fmt::format("{}: read failed: {}", s.where, ec.message())),
                        ec == asio::error::eof ? DisconnectKind::by_gateway : DisconnectKind::failed);
      co_return;
    }
    lines.append(std::string_view(buf.data(), n));
    while (s.generation == generation) {
      auto piece = lines.next();
      if (!piece) break;
      if (piece->overlong)
        s.protocol_error(fmt::format("line longer than {} characters", kMaxLineLength));
      else
        s.handle_line(piece->text);
    }
  }
}

asio::awaitable<void> CanNetGateway::Impl::run_writer(std::shared_ptr<Impl> self) {
  Impl& s = *self;
  const std::uint64_t generation = s.generation;
  std::string chunk;
  while (s.generation == generation) {
    if (s.out.empty()) {
      core::Wakeup idle(s.executor);
      s.writer_idle = &idle;
      core::OnExit clear{[&s, &idle] {
        if (s.writer_idle == &idle) s.writer_idle = nullptr;
      }};
      co_await idle.wait();
      continue;
    }
    chunk.clear();
    chunk.swap(s.out);
    boost::system::error_code ec;
    co_await asio::async_write(s.socket, asio::buffer(chunk), asio::redirect_error(asio::use_awaitable, ec));
    if (s.generation != generation) co_return;
    if (ec) {
      s.connection_down(Error(CanErrc::io, fmt::format("{}: write failed: {}", s.where, ec.message())),
                        DisconnectKind::failed);
      co_return;
    }
    s.admit_waiters();
  }
}

void CanNetGateway::Impl::connection_down(Error why, DisconnectKind kind) {
  if (kind == DisconnectKind::by_host) {
    host_closed = true;
    if (!connected) {  // down already (buses kept for a reconnection): now they close
      down_kind = kind;
      down_error = std::move(why);
      close_buses();
      return;
    }
  }
  if (!connected) return;
  connected = false;
  ++generation;
  down_kind = kind;
  if (why.code == CanErrc::closed)
    spdlog::debug("{}: connection closed", where);
  else
    spdlog::warn("{}: connection lost: {}", where, why.message());
  down_error = std::move(why);
  boost::system::error_code ignored;
  socket.shutdown(tcp::socket::shutdown_both, ignored);
  socket.close(ignored);
  // What was waiting for the wire goes with the connection: never sent on a later one.
  stats.stale_lines_dropped += static_cast<std::uint64_t>(std::count(out.begin(), out.end(), '\n'));
  out.clear();
  if (writer_idle) writer_idle->notify();
  for (auto* w : space_waiters) w->wake.abandon();
  for (auto* w : command_queue) w->abandon();  // woken without being granted the turn
  if (pending) pending->waiter.abandon();
  if (!options.reconnectable || kind == DisconnectKind::by_host) close_buses();
}

asio::awaitable<Result<void>> CanNetGateway::Impl::queue_in_turn(std::string_view line) {
  auto self = shared_from_this();
  SpaceWaiter w(executor, line);  // the line is copied before the first suspension
  space_waiters.push_back(&w);
  core::OnExit remove{[this, &w] {
    space_waiters.erase(std::remove(space_waiters.begin(), space_waiters.end(), &w), space_waiters.end());
  }};
  if (writer_idle) writer_idle->notify();  // let the writer make room (it normally is busy already)
  while (!w.queued && connected) (void)co_await w.wake.wait();
  if (!w.queued) co_return down_error;
  co_return ok();
}

// ---- input ----

void CanNetGateway::Impl::handle_line(std::string_view text) {
  ++stats.lines_in;
  // A blank line carries nothing (a terminal user pressing Enter, a "\r\n\r\n"): skipped.
  if (std::all_of(text.begin(), text.end(), [](char c) { return c == ' ' || c == '\t' || c == '\r'; })) return;
  auto parsed = parse_line(text);
  if (!parsed) {
    protocol_error(parsed.error().detail);
    return;
  }
  Line& line = parsed.value();
  if (auto* m = std::get_if<FrameMessage>(&line)) {
    auto& c = chan[static_cast<std::size_t>(m->channel)];
    if (!c.bus) {
      ++stats.unrouted_frames;
      return;
    }
    m->frame.set_timestamp(core::SteadyClock::instance().wall());
    c.bus->on_frame(m->frame);
    return;
  }
  if (auto* e = std::get_if<Event>(&line)) {
    handle_event(*e);
    return;
  }
  if (is_reply(line)) {
    handle_reply(std::move(line));
    return;
  }
  protocol_error(fmt::format("the gateway sent a host command: '{}'", format_line(line)));
}

void CanNetGateway::Impl::handle_reply(Line line) {
  if (!pending || pending->reply) {
    protocol_error(fmt::format("reply '{}' while no command was waiting for one", format_line(line)));
    return;
  }
  ++stats.commands;
  if (std::holds_alternative<ReplyError>(line)) ++stats.device_errors;
  pending->reply = std::move(line);
  pending->waiter.notify();
}

void CanNetGateway::Impl::handle_event(const Event& e) {
  auto& c = chan[static_cast<std::size_t>(e.channel)];
  switch (e.kind) {
    case EventKind::bus_off:
      spdlog::warn("{}: channel {} is bus-off", where, e.channel);
      c.state = BusState::bus_off;
      break;
    case EventKind::error_warning:
      if (e.set && c.state != BusState::bus_off) c.state = BusState::error_warning;
      if (!e.set && c.state == BusState::error_warning) c.state = BusState::active;
      break;
    case EventKind::tx_overflow:
      spdlog::debug("{}: channel {}: {} frames dropped, transmit FIFO full", where, e.channel, e.count);
      if (c.bus) c.bus->on_tx_dropped(e.count);
      return;
  }
  if (c.bus) c.bus->on_state(c.state);
}

void CanNetGateway::Impl::protocol_error(std::string_view what) {
  ++stats.protocol_errors;
  for (auto& c : chan)
    if (c.bus) c.bus->on_protocol_error();
  if (!protocol_error_logged) {
    protocol_error_logged = true;
    spdlog::warn("{}: {} (line skipped; further ones are logged at debug level)", where, what);
  } else {
    spdlog::debug("{}: {}", where, what);
  }
}

// ---- commands ----

asio::awaitable<Result<Line>> CanNetGateway::Impl::transact(const Line& command) {
  auto self = shared_from_this();
  const std::string text = format_line(command);
  AXON_CO_TRY(check_open());
  if (command_busy) {  // wait for our turn, in order
    core::Wakeup turn(executor);
    command_queue.push_back(&turn);
    core::OnExit remove{[this, &turn] { command_queue.erase(std::remove(command_queue.begin(), command_queue.end(), &turn), command_queue.end()); }};
    const bool granted = co_await turn.wait();
    if (!granted) co_return down_error;  // shut down while waiting; the turn never came
  }
  command_busy = true;  // ours now, until handed on below
  PendingReply reply(executor);
  core::OnExit release{[this] {
    pending = nullptr;
    if (command_queue.empty()) {
      command_busy = false;
    } else {
      core::Wakeup* next = command_queue.front();
      command_queue.pop_front();
      next->notify();
    }
  }};
  AXON_CO_TRY(check_open());
  pending = &reply;
  queue_line(text);
  (void)co_await reply.waiter.wait_until(std::chrono::steady_clock::now() + options.reply_timeout);
  if (reply.reply) co_return std::move(*reply.reply);
  if (!connected) co_return down_error;
  co_return Error(CanErrc::timeout, fmt::format("{}: no reply to '{}' within {} ms", where, text, millis(options.reply_timeout)));
}

asio::awaitable<Result<void>> CanNetGateway::Impl::set_up(int channel) {
  const std::array<Line, 5> steps = {
      CanStop{channel},
      CanInit{channel, options.bitrate_kbit * 1000},
      CanFilterClear{channel},
      CanFilterAdd{channel, IdFormat::extended, 0, 0},
      CanStart{channel},
  };
  for (std::size_t i = 0; i < steps.size(); ++i) {
    auto r = co_await transact(steps[i]);
    if (!r) co_return r.error();
    if (std::holds_alternative<ReplyOk>(r.value())) continue;
    if (const auto* e = std::get_if<ReplyError>(&r.value())) {
      if (std::holds_alternative<CanStop>(steps[i])) {
        spdlog::debug("{}: '{}' refused ({} {}); carrying on", where, format_line(steps[i]), e->code, e->text);
        continue;
      }
      co_return Error(CanErrc::device_error,
                      fmt::format("{}: '{}' refused: ERR {} {}", where, format_line(steps[i]), e->code, e->text));
    }
    co_return Error(CanErrc::protocol_error, fmt::format("{}: '{}' answered '{}' (expected 'R ok')", where,
                                                         format_line(steps[i]), format_line(r.value())));
  }
  chan[static_cast<std::size_t>(channel)].state = BusState::active;
  co_return ok();
}

// ---- CanNetGateway ----

CanNetGateway::CanNetGateway(std::shared_ptr<Impl> impl) : impl_(std::move(impl)) {}

CanNetGateway::~CanNetGateway() { close(); }

asio::awaitable<Result<std::shared_ptr<CanNetGateway>>> CanNetGateway::connect(asio::any_io_executor executor,
                                                                               net::Endpoint endpoint,
                                                                               std::vector<int> channels,
                                                                               CanNetOptions options) {
  const std::string where = fmt::format("CAN@net gateway {}", host_port(endpoint));
  if (channels.empty()) co_return Error(CanErrc::bad_spec, fmt::format("{}: no channels to set up", where));
  for (std::size_t i = 0; i < channels.size(); ++i) {
    if (channels[i] < kMinChannel || channels[i] > kMaxChannel)
      co_return Error(CanErrc::bad_spec, fmt::format("{}: channel {} is not {}..{}", where, channels[i], kMinChannel, kMaxChannel));
    if (std::find(channels.begin(), channels.begin() + static_cast<std::ptrdiff_t>(i), channels[i]) !=
        channels.begin() + static_cast<std::ptrdiff_t>(i))
      co_return Error(CanErrc::bad_spec, fmt::format("{}: channel {} listed twice", where, channels[i]));
  }
  if (options.bitrate_kbit == 0 || options.bitrate_kbit > 100'000)
    co_return Error(CanErrc::bad_spec, fmt::format("{}: bitrate {} kbit/s", where, options.bitrate_kbit));

  auto impl = std::make_shared<Impl>(std::move(executor), std::move(endpoint), std::move(channels), options);
  AXON_CO_TRY(co_await impl->open());
  impl->start();
  for (const int ch : impl->channels) {
    auto r = co_await impl->set_up(ch);
    if (!r) {
      impl->connection_down(Error(CanErrc::closed, "set-up failed"), DisconnectKind::by_host);
      co_return r.error();
    }
  }
  spdlog::info("{}: connected, channel(s) {} at {} kbit/s", impl->where, fmt::join(impl->channels, ", "),
               impl->options.bitrate_kbit);
  co_return std::shared_ptr<CanNetGateway>(new CanNetGateway(std::move(impl)));
}

Result<std::unique_ptr<Bus>> CanNetGateway::bus(int channel) {
  Impl& s = *impl_;
  if (std::find(s.channels.begin(), s.channels.end(), channel) == s.channels.end())
    return Error(CanErrc::bad_spec, fmt::format("{}: channel {} was not set up (set up: {})", s.where, channel,
                                                fmt::join(s.channels, ", ")));
  AXON_TRY(s.check_open());
  auto& c = s.chan[static_cast<std::size_t>(channel)];
  if (c.bus) return Error(CanErrc::bad_spec, fmt::format("{}: channel {} already has an open bus", s.where, channel));
  BusOptions opts = s.options.bus_options;
  opts.bitrate = s.options.bitrate_kbit * 1000;
  auto bus = std::make_unique<CanNetBus>(shared_from_this(), s, channel, opts,
                                         fmt::format("cannet://{}/{}", host_port(s.endpoint), channel));
  c.bus = bus.get();
  if (c.state != BusState::active) bus->on_state(c.state);
  return std::unique_ptr<Bus>(std::move(bus));
}

asio::awaitable<Result<Line>> CanNetGateway::command(const Line& line) {
  if (!is_host_command(line))
    co_return Error(CanErrc::bad_spec, fmt::format("{}: '{}' is not a host command", impl_->where, format_line(line)));
  auto impl = impl_;
  co_return co_await impl->transact(line);
}

asio::awaitable<Result<CanNetStatus>> CanNetGateway::status(int channel) {
  auto impl = impl_;
  if (channel < kMinChannel || channel > kMaxChannel)
    co_return Error(CanErrc::bad_spec, fmt::format("{}: channel {} is not {}..{}", impl->where, channel, kMinChannel, kMaxChannel));
  const Line request = CanStatusRequest{channel};
  AXON_CO_TRY(reply, co_await impl->transact(request));
  if (const auto* st = std::get_if<ReplyStatus>(&reply); st && st->channel == channel)
    co_return CanNetStatus{st->flags, st->free_tx};
  if (const auto* e = std::get_if<ReplyError>(&reply))
    co_return Error(CanErrc::device_error, fmt::format("{}: 'CAN {} STATUS' refused: ERR {} {}", impl->where, channel, e->code, e->text));
  co_return Error(CanErrc::protocol_error,
                  fmt::format("{}: 'CAN {} STATUS' answered '{}'", impl->where, channel, format_line(reply)));
}

namespace {
asio::awaitable<Result<std::string>> text_query(std::shared_ptr<CanNetGateway::Impl> impl, Line request) {
  AXON_CO_TRY(reply, co_await impl->transact(request));
  if (const auto* t = std::get_if<ReplyText>(&reply)) co_return t->text;
  if (const auto* e = std::get_if<ReplyError>(&reply))
    co_return Error(CanErrc::device_error,
                    fmt::format("{}: '{}' refused: ERR {} {}", impl->where, format_line(request), e->code, e->text));
  co_return Error(CanErrc::protocol_error,
                  fmt::format("{}: '{}' answered '{}'", impl->where, format_line(request), format_line(reply)));
}
}  // namespace

asio::awaitable<Result<std::string>> CanNetGateway::identify() { return text_query(impl_, DevIdentify{}); }
asio::awaitable<Result<std::string>> CanNetGateway::version() { return text_query(impl_, DevVersion{}); }

asio::awaitable<Result<void>> CanNetGateway::restart(int channel) {
  auto impl = impl_;
  if (std::find(impl->channels.begin(), impl->channels.end(), channel) == impl->channels.end())
    co_return Error(CanErrc::bad_spec, fmt::format("{}: channel {} was not set up", impl->where, channel));
  AXON_CO_TRY(stop_reply, co_await impl->transact(CanStop{channel}));
  (void)stop_reply;  // a refused STOP (already stopped) does not matter
  AXON_CO_TRY(reply, co_await impl->transact(CanStart{channel}));
  if (const auto* e = std::get_if<ReplyError>(&reply))
    co_return Error(CanErrc::device_error, fmt::format("{}: 'CAN {} START' refused: ERR {} {}", impl->where, channel, e->code, e->text));
  if (!std::holds_alternative<ReplyOk>(reply))
    co_return Error(CanErrc::protocol_error, fmt::format("{}: 'CAN {} START' answered '{}'", impl->where, channel, format_line(reply)));
  auto& c = impl->chan[static_cast<std::size_t>(channel)];
  c.state = BusState::active;
  if (c.bus) c.bus->on_state(BusState::active);
  co_return ok();
}

asio::awaitable<Result<void>> CanNetGateway::reconnect(std::optional<core::Duration> timeout) {
  auto impl = impl_;
  Impl& s = *impl;
  if (s.connected) co_return ok();
  if (s.host_closed) co_return Error(CanErrc::closed, fmt::format("{}: closed by the host", s.where));
  if (s.reconnecting) co_return Error(CanErrc::closed, fmt::format("{}: a reconnection is already under way", s.where));
  s.reconnecting = true;
  const core::Duration connect_timeout = s.options.connect_timeout;
  const core::Duration reply_timeout = s.options.reply_timeout;
  core::OnExit restore{[&s, connect_timeout, reply_timeout] {
    s.options.connect_timeout = connect_timeout;
    s.options.reply_timeout = reply_timeout;
    s.reconnecting = false;
  }};
  if (timeout) s.options.connect_timeout = s.options.reply_timeout = *timeout;
  AXON_CO_TRY(co_await s.open());
  if (s.host_closed) {  // close() came while connecting
    s.connection_down(Error(CanErrc::closed, fmt::format("{}: closed by the host", s.where)), DisconnectKind::by_host);
    co_return Error(CanErrc::closed, fmt::format("{}: closed by the host", s.where));
  }
  s.start();
  for (const int ch : s.channels) {
    auto r = co_await s.set_up(ch);
    if (!r) {
      s.connection_down(r.error(), DisconnectKind::failed);
      co_return r.error();
    }
  }
  for (auto& c : s.chan)
    if (c.bus) c.bus->on_state(c.state);
  ++s.stats.reconnections;
  spdlog::info("{}: reconnected, channel(s) {} set up again", s.where, fmt::join(s.channels, ", "));
  co_return ok();
}

const char* to_string(DisconnectKind k) noexcept {
  switch (k) {
    case DisconnectKind::connected: return "connected";
    case DisconnectKind::by_host: return "closed by the host";
    case DisconnectKind::by_gateway: return "closed by the gateway";
    case DisconnectKind::failed: return "failed";
  }
  return "?";
}

void CanNetGateway::close() {
  impl_->connection_down(Error(CanErrc::closed, fmt::format("{}: closed by the host", impl_->where)), DisconnectKind::by_host);
}
DisconnectKind CanNetGateway::disconnect_kind() const noexcept {
  return impl_->connected ? DisconnectKind::connected : impl_->down_kind;
}
bool CanNetGateway::is_connected() const noexcept { return impl_->connected; }
const Error& CanNetGateway::disconnect_reason() const noexcept { return impl_->down_error; }
const std::vector<int>& CanNetGateway::channels() const noexcept { return impl_->channels; }
const net::Endpoint& CanNetGateway::endpoint() const noexcept { return impl_->endpoint; }
const CanNetGatewayStats& CanNetGateway::stats() const noexcept { return impl_->stats; }

}  // namespace axon::can
