#include "axon/fps/plc/emulator.hpp"

#include "axon/fps/plc/error.hpp"
#include "axon/fps/plc/request_framer.hpp"

#include <boost/asio/post.hpp>
#include <fmt/format.h>
#include <modbus/modbus.h>
#include <spdlog/spdlog.h>

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <mutex>
#include <span>
#include <thread>
#include <vector>

namespace axon::fps::plc {

namespace {

using SteadyTime = std::chrono::steady_clock::time_point;

// "HOST:PORT" of a client socket.
std::string peer_of(int fd) {
  sockaddr_in addr{};
  socklen_t len = sizeof addr;
  if (getpeername(fd, reinterpret_cast<sockaddr*>(&addr), &len) != 0) return "?";
  char text[INET_ADDRSTRLEN] = {};
  inet_ntop(AF_INET, &addr.sin_addr, text, sizeof text);
  return fmt::format("{}:{}", text, ntohs(addr.sin_port));
}

bool set_nonblocking(int fd) {
  const int flags = fcntl(fd, F_GETFL, 0);
  return flags >= 0 && fcntl(fd, F_SETFL, flags | O_NONBLOCK) == 0;
}

}  // namespace

class PlcEmulator::Impl {
 public:
  // One client connection (server thread only).
  struct Conn {
    int fd = -1;
    std::string peer;
    RequestFramer framer;
    std::optional<SteadyTime> partial_since;  // when the request held in the framer began
  };

  explicit Impl(EmulatorOptions o) : options(std::move(o)) {}
  ~Impl() { shutdown(); }

  Result<void> open();
  Result<void> listen();
  void shutdown() noexcept;
  void loop();
  void accept_all(std::vector<Conn>& conns);
  // Reads what the client sent and answers its complete requests; false: the connection ends.
  bool serve(Conn& c);
  // Answers one request; false when the answer could not be sent whole.
  bool answer(Conn& c, std::span<const std::uint8_t> adu);
  void close_conn(Conn& c) noexcept;
  // Counts under the lock and logs: `what` happened to the connection, which is then closed.
  void reject(Conn& c, std::uint64_t EmulatorCounters::*counter, std::string_view what);
  // Under the lock.
  void apply_script_locked();
  void write_input_locked(const AnalogInput& in, std::optional<double> v) {
    mapping->tab_input_registers[in.address] = in.encode(v);
  }
  void dispatch(const std::vector<RelayEvent>& events);
  Result<const AnalogInput*> input(std::string_view name) const {
    const auto* in = options.map.input(name);
    if (!in) return Error(PlcErrc::invalid_argument, fmt::format("the register map has no sensor '{}'", name));
    return in;
  }

  EmulatorOptions options;
  modbus_t* ctx = nullptr;
  modbus_mapping_t* mapping = nullptr;
  int listen_fd = -1;
  int wake[2] = {-1, -1};
  bool refusing = false;        // a refusal was logged at warning level; the next accepted client resets it
  SteadyTime accept_paused_until{};  // after accept() failed for want of descriptors
  std::uint16_t port = 0;
  std::thread thread;
  mutable std::mutex mu;
  std::vector<RelayHandler> handlers;
  EmulatorCounters counters;
  std::chrono::steady_clock::time_point started = std::chrono::steady_clock::now();
};

Result<void> PlcEmulator::Impl::open() {
  AXON_TRY(options.map.validate());
  for (const auto& name : options.script.sensors()) {
    AXON_TRY(input(name));
  }
  std::string host = options.bind_address == "localhost" ? "127.0.0.1" : options.bind_address;
  in_addr probe{};
  if (inet_pton(AF_INET, host.c_str(), &probe) != 1)
    return Error(PlcErrc::server_failed, fmt::format("PLC emulator: '{}' is not an IPv4 address", options.bind_address));
  ctx = modbus_new_tcp(host.c_str(), options.port);
  if (!ctx) return Error(PlcErrc::server_failed, fmt::format("PLC emulator: {}", modbus_strerror(errno)));
  // libmodbus sleeps this long before some exception answers (to flush a serial line): as short
  // as it allows, so that a client sending bad requests holds up nobody.
  modbus_set_response_timeout(ctx, 0, 1);
  AXON_TRY(listen());
  mapping = modbus_mapping_new_start_address(0, options.map.coil_span(), 0, 0, 0, 0, 0, options.map.input_register_span());
  if (!mapping) return Error(PlcErrc::server_failed, fmt::format("PLC emulator: {}", modbus_strerror(errno)));
  if (pipe(wake) != 0) return Error(PlcErrc::server_failed, fmt::format("PLC emulator: pipe: {}", std::strerror(errno)));
  const auto& m = options.map;
  for (int s = 1; s <= kSextants; ++s) {
    mapping->tab_bits[m.coil_of({RelayKind::positioner_power, s})] = options.power_on_at_start ? 1 : 0;
    mapping->tab_bits[m.coil_of({RelayKind::gateway_power, s})] = options.power_on_at_start ? 1 : 0;
  }
  for (const auto& t : m.temperatures) write_input_locked(t, options.initial_temperature_c);
  write_input_locked(m.humidity, options.initial_humidity);
  write_input_locked(m.pressure, options.initial_pressure_hpa);
  write_input_locked(m.coolant_flow, options.initial_coolant_flow);
  apply_script_locked();
  thread = std::thread([this] { loop(); });
  return ok();
}

Result<void> PlcEmulator::Impl::listen() {
  listen_fd = modbus_tcp_listen(ctx, SOMAXCONN);  // a burst of connections waits in the backlog
  if (listen_fd == -1 || !set_nonblocking(listen_fd))
    return Error(PlcErrc::server_failed, fmt::format("PLC emulator: listen on {}:{}: {}", options.bind_address,
                                                     options.port, modbus_strerror(errno)));
  sockaddr_in addr{};
  socklen_t len = sizeof addr;
  if (getsockname(listen_fd, reinterpret_cast<sockaddr*>(&addr), &len) == 0) port = ntohs(addr.sin_port);
  return ok();
}

void PlcEmulator::Impl::shutdown() noexcept {
  if (thread.joinable()) {
    const char c = 'x';
    [[maybe_unused]] auto n = write(wake[1], &c, 1);
    thread.join();
  }
  for (int& fd : wake) {
    if (fd >= 0) ::close(fd);
    fd = -1;
  }
  if (listen_fd >= 0) ::close(listen_fd);
  listen_fd = -1;
  if (mapping) modbus_mapping_free(mapping);
  mapping = nullptr;
  if (ctx) modbus_free(ctx);
  ctx = nullptr;
}

void PlcEmulator::Impl::apply_script_locked() {
  if (options.script.empty()) return;
  const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count() * options.time_scale;
  for (const auto& [name, value] : options.script.values_at(t))
    if (const auto* in = options.map.input(name)) write_input_locked(*in, value);
}

void PlcEmulator::Impl::dispatch(const std::vector<RelayEvent>& events) {
  if (events.empty()) return;
  std::vector<RelayHandler> hs;
  {
    std::lock_guard lock(mu);
    hs = handlers;
  }
  for (const auto& e : events) {
    spdlog::debug("plc emulator: {} {}", e.relay.to_string(), e.on ? "on" : "off");
    for (const auto& h : hs) {
      if (options.hook_executor) boost::asio::post(*options.hook_executor, [h, e] { h(e); });
      else h(e);
    }
  }
}

void PlcEmulator::Impl::close_conn(Conn& c) noexcept {
  if (c.fd < 0) return;
  ::close(c.fd);
  c.fd = -1;
  std::lock_guard lock(mu);
  --counters.clients;
}

void PlcEmulator::Impl::reject(Conn& c, std::uint64_t EmulatorCounters::*counter, std::string_view what) {
  // Logged before it is counted: whoever sees the count (a monitor, a test) finds the line in the log.
  spdlog::warn("plc emulator: client {}: {}; connection closed", c.peer, what);
  {
    std::lock_guard lock(mu);
    ++(counters.*counter);
  }
  close_conn(c);
}

bool PlcEmulator::Impl::answer(Conn& c, std::span<const std::uint8_t> adu) {
  // libmodbus reads a request's data by its quantity fields, not by its length: a buffer of the
  // largest request keeps it inside memory whatever the request claims.
  std::array<std::uint8_t, kMaxRequestSize> query{};
  std::copy(adu.begin(), adu.end(), query.begin());
  std::vector<RelayEvent> events;
  int rc = 0;
  int error = 0;
  {
    std::lock_guard lock(mu);
    apply_script_locked();
    const auto span = options.map.coil_span();
    std::vector<std::uint8_t> before(mapping->tab_bits, mapping->tab_bits + span);
    modbus_set_socket(ctx, c.fd);
    const auto at = core::steady_now();  // before the answer: a client that waits on it comes later
    rc = modbus_reply(ctx, query.data(), static_cast<int>(adu.size()), mapping);
    error = errno;
    ++counters.requests;
    for (std::uint16_t a = 0; a < span; ++a) {
      if ((before[a] != 0) == (mapping->tab_bits[a] != 0)) continue;
      if (auto r = options.map.relay_at(a)) {
        events.push_back(RelayEvent{*r, mapping->tab_bits[a] != 0, a, at});
        ++counters.relay_changes;
      }
    }
  }
  // Any client may switch the relays (Modbus has no sessions): say who did, so that a change
  // nobody expected can be traced.
  for (const auto& e : events) {
    const bool sync = e.relay.kind == RelayKind::sync_line;
    spdlog::info("plc emulator: client {} switched {} {}", c.peer, e.relay.to_string(),
                 sync ? (e.on ? "high" : "low") : (e.on ? "on" : "off"));
  }
  dispatch(events);
  if (rc >= 0) return true;
  // The socket does not block: a full send buffer (EAGAIN, or a partial send libmodbus reports
  // as bad data) means the client has not been reading its answers.
  if (error == EAGAIN || error == EWOULDBLOCK || error == EMBBADDATA)
    reject(c, &EmulatorCounters::slow_readers, "does not read its answers (send buffer full)");
  else
    close_conn(c);  // the client left
  return false;
}

bool PlcEmulator::Impl::serve(Conn& c) {
  std::array<std::uint8_t, 4096> buf{};
  const ssize_t n = ::recv(c.fd, buf.data(), buf.size(), 0);
  if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) return true;
  if (n <= 0) {  // the client left (a partial request with it changes nothing)
    close_conn(c);
    return false;
  }
  c.framer.feed(std::span<const std::uint8_t>(buf.data(), static_cast<std::size_t>(n)));
  bool answered = false;
  while (auto r = c.framer.next()) {
    if (!*r) {
      // Not Modbus TCP: there is no finding the next request in the stream.
      reject(c, &EmulatorCounters::bad_requests, r->error().detail);
      return false;
    }
    if (!answer(c, r->value())) return false;
    answered = true;
  }
  if (c.framer.buffered() == 0) c.partial_since.reset();
  else if (answered || !c.partial_since) c.partial_since = std::chrono::steady_clock::now();
  return true;
}

void PlcEmulator::Impl::accept_all(std::vector<Conn>& conns) {
  for (;;) {
    const int fd = ::accept4(listen_fd, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) {
      if (errno == EMFILE || errno == ENFILE || errno == ENOBUFS || errno == ENOMEM) {
        // The connection stays in the backlog: breathe rather than spin on it.
        spdlog::warn("plc emulator: accept: {}; accepting again in 100 ms", std::strerror(errno));
        accept_paused_until = std::chrono::steady_clock::now() + std::chrono::milliseconds(100);
      }
      return;  // EAGAIN: none left; others concern that one connection only
    }
    std::lock_guard lock(mu);
    if (conns.size() >= options.max_clients) {
      ++counters.refused;
      if (!refusing)
        spdlog::warn("plc emulator: refusing client {}: {} clients connected (further refusals logged at debug level)",
                     peer_of(fd), conns.size());
      else
        spdlog::debug("plc emulator: refusing client {}", peer_of(fd));
      refusing = true;
      ::close(fd);
      continue;
    }
    refusing = false;
    conns.push_back(Conn{fd, peer_of(fd), {}, {}});
    ++counters.connections;
    ++counters.clients;
  }
}

void PlcEmulator::Impl::loop() {
  std::vector<Conn> conns;
  std::vector<pollfd> fds;
  for (;;) {
    const auto now = std::chrono::steady_clock::now();
    const bool accepting = now >= accept_paused_until;
    fds.clear();
    fds.push_back({wake[0], POLLIN, 0});
    fds.push_back({accepting ? listen_fd : -1, POLLIN, 0});
    for (const auto& c : conns) fds.push_back({c.fd, POLLIN, 0});
    const int n = ::poll(fds.data(), fds.size(), 50);
    if (n < 0) {
      if (errno == EINTR) continue;
      spdlog::error("plc emulator: poll: {}", std::strerror(errno));
      break;
    }
    {
      std::lock_guard lock(mu);
      apply_script_locked();
    }
    if (fds[0].revents != 0) break;
    for (std::size_t i = 0; i < conns.size(); ++i)
      if (fds[i + 2].revents != 0) serve(conns[i]);
    const auto deadline = std::chrono::steady_clock::now() - options.request_timeout;
    for (auto& c : conns)
      if (c.fd >= 0 && c.partial_since && *c.partial_since < deadline)
        reject(c, &EmulatorCounters::stalled_requests,
               fmt::format("request not completed within {} ms ({} bytes of it came)", options.request_timeout.count(),
                           c.framer.buffered()));
    std::erase_if(conns, [](const Conn& c) { return c.fd < 0; });
    if (fds[1].revents != 0) accept_all(conns);
  }
  for (auto& c : conns) close_conn(c);
}

PlcEmulator::PlcEmulator(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
PlcEmulator::~PlcEmulator() { stop(); }

Result<std::unique_ptr<PlcEmulator>> PlcEmulator::start(EmulatorOptions options) {
  auto impl = std::make_unique<Impl>(std::move(options));
  AXON_TRY(impl->open());
  return std::unique_ptr<PlcEmulator>(new PlcEmulator(std::move(impl)));
}

void PlcEmulator::stop() noexcept {
  if (impl_) impl_->shutdown();
}

std::uint16_t PlcEmulator::port() const noexcept { return impl_->port; }

net::Endpoint PlcEmulator::endpoint() const {
  return net::Endpoint{impl_->options.bind_address == "localhost" ? "127.0.0.1" : impl_->options.bind_address, impl_->port};
}

const RegisterMap& PlcEmulator::map() const noexcept { return impl_->options.map; }

void PlcEmulator::on_relay_change(RelayHandler handler) {
  std::lock_guard lock(impl_->mu);
  impl_->handlers.push_back(std::move(handler));
}

bool PlcEmulator::relay(Relay r) const {
  std::lock_guard lock(impl_->mu);
  return impl_->mapping->tab_bits[impl_->options.map.coil_of(r)] != 0;
}

void PlcEmulator::set_relay(Relay r, bool on) {
  std::vector<RelayEvent> events;
  {
    std::lock_guard lock(impl_->mu);
    const auto a = impl_->options.map.coil_of(r);
    if ((impl_->mapping->tab_bits[a] != 0) == on) return;
    impl_->mapping->tab_bits[a] = on ? 1 : 0;
    ++impl_->counters.relay_changes;
    events.push_back(RelayEvent{r, on, a, core::steady_now()});
  }
  impl_->dispatch(events);
}

Result<void> PlcEmulator::set_sensor(std::string_view name, double value) {
  AXON_TRY(in, impl_->input(name));
  std::lock_guard lock(impl_->mu);
  impl_->write_input_locked(*in, value);
  return ok();
}

Result<void> PlcEmulator::set_sensor_fault(std::string_view name) {
  AXON_TRY(in, impl_->input(name));
  std::lock_guard lock(impl_->mu);
  impl_->write_input_locked(*in, std::nullopt);
  return ok();
}

Result<std::optional<double>> PlcEmulator::sensor(std::string_view name) const {
  AXON_TRY(in, impl_->input(name));
  std::lock_guard lock(impl_->mu);
  return in->decode(impl_->mapping->tab_input_registers[in->address]);
}

Result<void> PlcEmulator::set_script(SensorScript script) {
  for (const auto& name : script.sensors()) {
    AXON_TRY(impl_->input(name));
  }
  std::lock_guard lock(impl_->mu);
  impl_->options.script = std::move(script);
  impl_->started = std::chrono::steady_clock::now();
  impl_->apply_script_locked();
  return ok();
}

EmulatorCounters PlcEmulator::counters() const {
  std::lock_guard lock(impl_->mu);
  return impl_->counters;
}

}  // namespace axon::fps::plc
