#include "axon/fps/plc/emulator.hpp"

#include "axon/fps/plc/error.hpp"

#include <boost/asio/post.hpp>
#include <fmt/format.h>
#include <modbus/modbus.h>
#include <spdlog/spdlog.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <mutex>
#include <thread>
#include <vector>

namespace axon::fps::plc {

class PlcEmulator::Impl {
 public:
  explicit Impl(EmulatorOptions o) : options(std::move(o)) {}
  ~Impl() { shutdown(); }

  Result<void> open();
  void shutdown() noexcept;
  void loop();
  void serve(int fd, std::vector<int>& clients, fd_set& all);
  // "HOST:PORT" of a client socket.
  static std::string peer_of(int fd) {
    sockaddr_in addr{};
    socklen_t len = sizeof addr;
    if (getpeername(fd, reinterpret_cast<sockaddr*>(&addr), &len) != 0) return "?";
    char text[INET_ADDRSTRLEN] = {};
    inet_ntop(AF_INET, &addr.sin_addr, text, sizeof text);
    return fmt::format("{}:{}", text, ntohs(addr.sin_port));
  }
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
  listen_fd = modbus_tcp_listen(ctx, 8);
  if (listen_fd == -1)
    return Error(PlcErrc::server_failed,
                 fmt::format("PLC emulator: listen on {}:{}: {}", host, options.port, modbus_strerror(errno)));
  sockaddr_in addr{};
  socklen_t len = sizeof addr;
  if (getsockname(listen_fd, reinterpret_cast<sockaddr*>(&addr), &len) == 0) port = ntohs(addr.sin_port);
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

void PlcEmulator::Impl::serve(int fd, std::vector<int>& clients, fd_set& all) {
  std::vector<std::uint8_t> query(MODBUS_TCP_MAX_ADU_LENGTH);
  modbus_set_socket(ctx, fd);
  const int rc = modbus_receive(ctx, query.data());
  if (rc == 0) return;  // not for this server (another unit id): ignored, as the PLC does
  if (rc < 0) {
    // The client left, or sent what is not a Modbus TCP request (libmodbus cannot resync the
    // stream, so the connection ends). Either way nothing in the map changed.
    if (errno != ECONNRESET) {
      std::lock_guard lock(mu);
      ++counters.bad_requests;
      spdlog::warn("plc emulator: client {}: {}; connection closed", peer_of(fd), modbus_strerror(errno));
    }
    ::close(fd);
    FD_CLR(fd, &all);
    clients.erase(std::remove(clients.begin(), clients.end(), fd), clients.end());
    return;
  }
  std::vector<RelayEvent> events;
  {
    std::lock_guard lock(mu);
    apply_script_locked();
    const auto span = options.map.coil_span();
    std::vector<std::uint8_t> before(mapping->tab_bits, mapping->tab_bits + span);
    modbus_reply(ctx, query.data(), rc, mapping);
    ++counters.requests;
    for (std::uint16_t a = 0; a < span; ++a) {
      if ((before[a] != 0) == (mapping->tab_bits[a] != 0)) continue;
      if (auto r = options.map.relay_at(a)) {
        events.push_back(RelayEvent{*r, mapping->tab_bits[a] != 0, a});
        ++counters.relay_changes;
      }
    }
  }
  // Any client may switch the relays (Modbus has no sessions): say who did, so that a change
  // nobody expected can be traced.
  for (const auto& e : events) {
    const bool sync = e.relay.kind == RelayKind::sync_line;
    spdlog::info("plc emulator: client {} switched {} {}", peer_of(fd), e.relay.to_string(),
                 sync ? (e.on ? "high" : "low") : (e.on ? "on" : "off"));
  }
  dispatch(events);
}

void PlcEmulator::Impl::loop() {
  fd_set all;
  FD_ZERO(&all);
  FD_SET(listen_fd, &all);
  FD_SET(wake[0], &all);
  std::vector<int> clients;
  for (;;) {
    fd_set rd = all;
    int maxfd = std::max(listen_fd, wake[0]);
    for (int c : clients) maxfd = std::max(maxfd, c);
    timeval tv{0, 50000};
    const int n = select(maxfd + 1, &rd, nullptr, nullptr, &tv);
    if (n < 0) {
      if (errno == EINTR) continue;
      spdlog::error("plc emulator: select: {}", std::strerror(errno));
      break;
    }
    {
      std::lock_guard lock(mu);
      apply_script_locked();
    }
    if (n == 0) continue;
    if (FD_ISSET(wake[0], &rd)) break;
    if (FD_ISSET(listen_fd, &rd)) {
      const int fd = accept(listen_fd, nullptr, nullptr);
      if (fd >= 0) {
        if (fd >= FD_SETSIZE) {
          ::close(fd);
        } else {
          FD_SET(fd, &all);
          clients.push_back(fd);
          std::lock_guard lock(mu);
          ++counters.connections;
        }
      }
    }
    const std::vector<int> ready = clients;
    for (int fd : ready)
      if (FD_ISSET(fd, &rd)) serve(fd, clients, all);
  }
  for (int fd : clients) ::close(fd);
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
    events.push_back(RelayEvent{r, on, a});
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
