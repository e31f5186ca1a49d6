// PlcClient: the host's side of the PLC (instrument electronics box) over Modbus TCP, through
// libmodbus.
//
// Calls are blocking, each bounded by the response timeout (a dead PLC costs one timeout, never a
// hang). A call finds the connection closed or broken, reconnects (up to `reconnect_attempts`
// times) and repeats itself: every PLC operation is idempotent (reads, and writes of a coil to a
// given state), so repeating one is safe. A Modbus exception from the PLC (a refused address) is
// final: no reconnect. Errors are PlcErrc with the operation, the address and libmodbus's message.
//
// Threading: one client per thread (libmodbus contexts are not thread-safe). From coroutine code,
// run the calls off the io_context thread (e.g. co_spawn on a one-thread pool with use_awaitable):
// a PLC timeout must not stall the CAN buses.
#pragma once

#include "axon/core/clock.hpp"
#include "axon/core/error.hpp"
#include "axon/fps/plc/register_map.hpp"
#include "axon/net/endpoint.hpp"

#include <array>
#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

struct _modbus;  // libmodbus's context (modbus_t)

namespace axon::fps::plc {

using namespace std::chrono_literals;

struct PlcClientOptions {
  core::Duration timeout = 1s;      // per request (and for connecting)
  unsigned reconnect_attempts = 1;  // after a broken connection, per call
};

struct PlcStatus {
  std::array<bool, kSextants> positioner_power{};
  std::array<bool, kSextants> gateway_power{};
  bool sync_line = false;
  std::vector<SensorReading> temperatures;
  SensorReading humidity;
  SensorReading pressure;
  SensorReading coolant_flow;

  [[nodiscard]] std::string to_text() const;
};

struct PlcCounters {
  std::uint64_t requests = 0;
  std::uint64_t errors = 0;
  std::uint64_t connects = 0;    // successful connections (the first one included)
  std::uint64_t reconnects = 0;  // connections made again after a failure
};

class PlcClient {
 public:
  explicit PlcClient(net::Endpoint endpoint, RegisterMap map = {}, PlcClientOptions options = {});
  PlcClient(const PlcClient&) = delete;
  PlcClient& operator=(const PlcClient&) = delete;
  ~PlcClient();

  // Connects now (calls also connect on demand). PlcErrc::connect_failed.
  Result<void> connect();
  void close() noexcept;
  [[nodiscard]] bool connected() const noexcept { return ctx_ != nullptr; }
  [[nodiscard]] const RegisterMap& map() const noexcept { return map_; }
  [[nodiscard]] const net::Endpoint& endpoint() const noexcept { return endpoint_; }
  [[nodiscard]] const PlcCounters& counters() const noexcept { return counters_; }

  // --- raw Modbus ---------------------------------------------------------------------------------
  Result<std::vector<bool>> read_coils(std::uint16_t address, std::uint16_t count);
  Result<void> write_coil(std::uint16_t address, bool on);
  Result<std::vector<std::uint16_t>> read_input_registers(std::uint16_t address, std::uint16_t count);

  // --- the instrument -----------------------------------------------------------------------------
  // Every relay and every sensor.
  Result<PlcStatus> status();
  Result<std::vector<SensorReading>> temperatures();
  Result<bool> relay(Relay r);
  // PlcErrc::invalid_argument for a sextant outside 1..6.
  Result<void> set_relay(Relay r, bool on);
  Result<void> set_positioner_power(int sextant, bool on) { return set_relay({RelayKind::positioner_power, sextant}, on); }
  Result<void> set_gateway_power(int sextant, bool on) { return set_relay({RelayKind::gateway_power, sextant}, on); }
  Result<void> set_sync_line(bool high) { return set_relay({RelayKind::sync_line, 0}, high); }
  // Sync line high for `hold` (robots start on a level held a few ms; hosts in service hold about
  // 0.5 s), then low again. The line is driven low even when the wait is interrupted by an error.
  Result<void> pulse_sync_line(core::Duration hold = 500ms);

 private:
  template <class F>
  auto call(const char* what, std::uint16_t address, F&& f) -> decltype(f());
  Error failure(const char* what, std::uint16_t address, int err) const;

  net::Endpoint endpoint_;
  RegisterMap map_;
  PlcClientOptions options_;
  _modbus* ctx_ = nullptr;
  bool ever_connected_ = false;
  PlcCounters counters_;
};

}  // namespace axon::fps::plc
