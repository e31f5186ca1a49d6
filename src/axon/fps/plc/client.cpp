#include "axon/fps/plc/client.hpp"

#include "axon/fps/plc/error.hpp"

#include <fmt/format.h>
#include <modbus/modbus.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cerrno>
#include <map>
#include <thread>

namespace axon::fps::plc {
namespace {

// Modbus exceptions libmodbus reports as errno values from MODBUS_ENOBASE on.
bool is_modbus_exception(int err) { return err > MODBUS_ENOBASE && err < EMBXGTAR + 1; }

}  // namespace

std::string PlcStatus::to_text() const {
  std::string s = fmt::format("{:<16}", "sextant");
  for (int k = 1; k <= kSextants; ++k) s += fmt::format(" {:>3}", k);
  auto row = [&](const char* label, const std::array<bool, kSextants>& v) {
    s += fmt::format("\n{:<16}", label);
    for (bool b : v) s += fmt::format(" {:>3}", b ? "on" : "off");
  };
  row("positioner power", positioner_power);
  row("gateway power", gateway_power);
  s += fmt::format("\n{:<16} {}\n", "sync line", sync_line ? "high" : "low");
  auto line = [](const SensorReading& r) {
    return fmt::format("{:<20} {}\n", r.name, r.value ? fmt::format("{:.2f} {}", *r.value, r.unit) : std::string("FAULT"));
  };
  for (const auto& t : temperatures) s += line(t);
  s += line(humidity);
  s += line(pressure);
  s += line(coolant_flow);
  return s;
}

PlcClient::PlcClient(net::Endpoint endpoint, RegisterMap map, PlcClientOptions options)
    : endpoint_(std::move(endpoint)), map_(std::move(map)), options_(options) {}

PlcClient::~PlcClient() { close(); }

void PlcClient::close() noexcept {
  if (!ctx_) return;
  modbus_close(ctx_);
  modbus_free(ctx_);
  ctx_ = nullptr;
}

Result<void> PlcClient::connect() {
  if (ctx_) return ok();
  modbus_t* ctx = modbus_new_tcp_pi(endpoint_.host.c_str(), std::to_string(endpoint_.port).c_str());
  if (!ctx)
    return Error(PlcErrc::connect_failed, fmt::format("PLC {}: {}", endpoint_.to_string(), modbus_strerror(errno)));
  const auto us = std::chrono::duration_cast<std::chrono::microseconds>(options_.timeout).count();
  modbus_set_response_timeout(ctx, static_cast<std::uint32_t>(us / 1000000), static_cast<std::uint32_t>(us % 1000000));
  modbus_set_slave(ctx, map_.unit_id);
  if (modbus_connect(ctx) == -1) {
    const int err = errno;
    modbus_free(ctx);
    return Error(PlcErrc::connect_failed, fmt::format("PLC {}: {}", endpoint_.to_string(), modbus_strerror(err)));
  }
  ctx_ = ctx;
  ++counters_.connects;
  if (ever_connected_) ++counters_.reconnects;
  ever_connected_ = true;
  return ok();
}

Error PlcClient::failure(const char* what, std::uint16_t address, int err) const {
  PlcErrc code = PlcErrc::io;
  if (err == EMBXILADD) code = PlcErrc::bad_address;
  else if (is_modbus_exception(err)) code = PlcErrc::device_exception;
  else if (err == ETIMEDOUT) code = PlcErrc::timeout;
  return Error(code, fmt::format("PLC {}: {} at address {}: {}", endpoint_.to_string(), what, address, modbus_strerror(err)));
}

// Runs `f` (a libmodbus call returning -1 on failure, with errno set) with reconnects.
template <class F>
auto PlcClient::call(const char* what, std::uint16_t address, F&& f) -> decltype(f()) {
  Error last;
  for (unsigned attempt = 0; attempt <= options_.reconnect_attempts; ++attempt) {
    if (!ctx_) {
      if (auto c = connect(); !c) {
        last = c.error();
        continue;
      }
    }
    ++counters_.requests;
    auto r = f();
    if (r) return r;
    ++counters_.errors;
    last = r.error();
    // f() returns errors built by failure(); a Modbus exception means the PLC answered: final.
    if (r.error() == PlcErrc::bad_address || r.error() == PlcErrc::device_exception) return r;
    spdlog::debug("plc: {} failed ({}); reconnecting", what, r.error().message());
    close();
  }
  spdlog::debug("plc: {} at {} gave up after {} attempts", what, address, options_.reconnect_attempts + 1);
  return last;
}

Result<std::vector<bool>> PlcClient::read_coils(std::uint16_t address, std::uint16_t count) {
  return call("read coils", address, [&]() -> Result<std::vector<bool>> {
    std::vector<std::uint8_t> bits(count);
    if (modbus_read_bits(ctx_, address, count, bits.data()) == -1) return failure("read coils", address, errno);
    std::vector<bool> out;
    for (auto b : bits) out.push_back(b != 0);
    return out;
  });
}

Result<void> PlcClient::write_coil(std::uint16_t address, bool on) {
  return call("write coil", address, [&]() -> Result<void> {
    if (modbus_write_bit(ctx_, address, on ? 1 : 0) == -1) return failure("write coil", address, errno);
    return ok();
  });
}

Result<std::vector<std::uint16_t>> PlcClient::read_input_registers(std::uint16_t address, std::uint16_t count) {
  return call("read input registers", address, [&]() -> Result<std::vector<std::uint16_t>> {
    std::vector<std::uint16_t> regs(count);
    if (modbus_read_input_registers(ctx_, address, count, regs.data()) == -1)
      return failure("read input registers", address, errno);
    return regs;
  });
}

namespace {

// The registers at `addresses`, read in as few contiguous blocks as the protocol allows.
template <class T, class Read>
Result<std::map<std::uint16_t, T>> read_spread(std::vector<std::uint16_t> addresses, std::uint16_t max_block, Read read) {
  std::sort(addresses.begin(), addresses.end());
  std::map<std::uint16_t, T> out;
  std::size_t i = 0;
  while (i < addresses.size()) {
    const std::uint16_t lo = addresses[i];
    std::size_t j = i;
    while (j + 1 < addresses.size() && addresses[j + 1] - lo < max_block) ++j;
    const auto count = static_cast<std::uint16_t>(addresses[j] - lo + 1);
    AXON_TRY(values, read(lo, count));
    for (std::size_t k = i; k <= j; ++k) out[addresses[k]] = values[addresses[k] - lo];
    i = j + 1;
  }
  return out;
}

}  // namespace

Result<PlcStatus> PlcClient::status() {
  std::vector<std::uint16_t> coil_addresses;
  for (const auto& r : map_.relays()) coil_addresses.push_back(map_.coil_of(r));
  AXON_TRY(coils, read_spread<bool>(coil_addresses, MODBUS_MAX_READ_BITS,
                                    [this](std::uint16_t a, std::uint16_t n) { return read_coils(a, n); }));
  std::vector<std::uint16_t> reg_addresses;
  for (const auto* in : map_.inputs()) reg_addresses.push_back(in->address);
  AXON_TRY(regs, read_spread<std::uint16_t>(reg_addresses, MODBUS_MAX_READ_REGISTERS,
                                            [this](std::uint16_t a, std::uint16_t n) { return read_input_registers(a, n); }));
  PlcStatus s;
  for (int k = 0; k < kSextants; ++k) {
    s.positioner_power[static_cast<std::size_t>(k)] = coils.at(map_.coil_of({RelayKind::positioner_power, k + 1}));
    s.gateway_power[static_cast<std::size_t>(k)] = coils.at(map_.coil_of({RelayKind::gateway_power, k + 1}));
  }
  s.sync_line = coils.at(map_.sync_line);
  auto reading = [&](const AnalogInput& in) { return SensorReading{in.name, in.decode(regs.at(in.address)), in.unit}; };
  for (const auto& t : map_.temperatures) s.temperatures.push_back(reading(t));
  s.humidity = reading(map_.humidity);
  s.pressure = reading(map_.pressure);
  s.coolant_flow = reading(map_.coolant_flow);
  return s;
}

Result<std::vector<SensorReading>> PlcClient::temperatures() {
  std::vector<std::uint16_t> addresses;
  for (const auto& t : map_.temperatures) addresses.push_back(t.address);
  AXON_TRY(regs, read_spread<std::uint16_t>(addresses, MODBUS_MAX_READ_REGISTERS,
                                            [this](std::uint16_t a, std::uint16_t n) { return read_input_registers(a, n); }));
  std::vector<SensorReading> out;
  for (const auto& t : map_.temperatures) out.push_back(SensorReading{t.name, t.decode(regs.at(t.address)), t.unit});
  return out;
}

Result<bool> PlcClient::relay(Relay r) {
  if (r.kind != RelayKind::sync_line && (r.sextant < 1 || r.sextant > kSextants))
    return Error(PlcErrc::invalid_argument, fmt::format("sextant {} outside 1..6", r.sextant));
  AXON_TRY(bits, read_coils(map_.coil_of(r), 1));
  return bits.at(0);
}

Result<void> PlcClient::set_relay(Relay r, bool on) {
  if (r.kind != RelayKind::sync_line && (r.sextant < 1 || r.sextant > kSextants))
    return Error(PlcErrc::invalid_argument, fmt::format("sextant {} outside 1..6", r.sextant));
  return write_coil(map_.coil_of(r), on);
}

Result<void> PlcClient::pulse_sync_line(core::Duration hold) {
  AXON_TRY(set_sync_line(true));
  std::this_thread::sleep_for(hold);
  return set_sync_line(false);
}

}  // namespace axon::fps::plc
