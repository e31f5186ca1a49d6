// PlcEmulator: a Modbus TCP server (libmodbus) that behaves like the instrument electronics box's
// PLC for the register map it is given: relays as coils the host writes, sensors as input
// registers the host reads. Several clients may be connected at once.
//
// Hooks, for `axon sim fps` and tests:
// Any client may write the coils, as on the real PLC (Modbus has no sessions): every change a
// client makes is logged at info level with its address. Requests libmodbus answers with an
// exception (unknown function, address out of the map) keep the connection; a frame that is not
// Modbus TCP at all (request_framer.hpp) is counted (bad_requests), logged and ends that
// connection only.
//
// Hostile peers (docs/reliability.md): no client can hold up the others. Sockets are non-blocking
// and requests are framed per connection, so a client that sends half a request and goes silent
// only loses its own connection after request_timeout (stalled_requests); a client that does not
// read its answers is disconnected once the kernel's send buffer for it is full (slow_readers),
// never waited for; beyond max_clients connections a new one is closed at once (refused). Each
// of these is counted and logged once per connection (refusals: once per burst, then at debug).
// Per connection the emulator holds at most one partial request (kMaxRequestSize bytes).
//
//   - on_relay_change(handler): called once per coil that a client's write changed, with the
//     relay, its new state (sync line: on = high; a rising edge is on == true) and the time of the
//     change (so a handler posted later still knows how long a relay was closed). Handlers run on
//     the server thread, or, when EmulatorOptions::hook_executor is set, are posted to that
//     executor (e.g. the simulator's io_context: then a handler may call Simulator::power_off(),
//     power_on(), set_sync_line() directly). Writes that do not change a coil fire nothing.
//   - set_sensor(name, value) / set_sensor_fault(name): what the next read returns.
//   - a SensorScript (sensor_script.hpp): scripted values over time, applied before every request
//     and at least every 50 ms.
//   - relay(r) / set_relay(r, on): the state, and local changes (e.g. a test powering a sextant
//     down as an operator would at the box); local changes fire the hooks too.
//
// Threading: the server runs on its own thread; every public member is thread-safe. stop() (or
// the destructor) ends the thread and closes every connection.
#pragma once

#include "axon/core/clock.hpp"
#include "axon/core/error.hpp"
#include "axon/fps/plc/register_map.hpp"
#include "axon/fps/plc/sensor_script.hpp"
#include "axon/net/endpoint.hpp"

#include <boost/asio/any_io_executor.hpp>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace axon::fps::plc {

struct RelayEvent {
  Relay relay;
  bool on = false;
  std::uint16_t coil = 0;
  core::TimePoint at{};  // when the emulator applied the write (steady clock), before answering it
};

struct EmulatorOptions {
  std::string bind_address = "127.0.0.1";
  std::uint16_t port = 0;  // 0: any free port (see PlcEmulator::port())
  RegisterMap map;
  SensorScript script;
  double time_scale = 1.0;          // script seconds per real second
  bool power_on_at_start = true;    // every positioner and gateway relay closed, sync line low
  double initial_temperature_c = 15.0;
  double initial_humidity = 35.0;
  double initial_pressure_hpa = 780.0;
  double initial_coolant_flow = 4.0;
  std::optional<boost::asio::any_io_executor> hook_executor;
  std::size_t max_clients = 64;  // connections served at once; more are refused
  std::chrono::milliseconds request_timeout{1000};  // to complete a request once its first byte came
};

struct EmulatorCounters {
  std::uint64_t connections = 0;
  std::uint64_t requests = 0;
  std::uint64_t relay_changes = 0;
  std::uint64_t bad_requests = 0;   // frames that are not Modbus TCP requests (the connection is closed)
  std::uint64_t refused = 0;        // connections closed at once: max_clients were connected
  std::uint64_t stalled_requests = 0;  // connections closed: a request not completed within request_timeout
  std::uint64_t slow_readers = 0;   // connections closed: the client did not read its answers
  std::uint64_t clients = 0;        // connected now
};

class PlcEmulator {
 public:
  // Binds, listens and starts the server thread. PlcErrc::server_failed (with the OS message),
  // PlcErrc::bad_map.
  static Result<std::unique_ptr<PlcEmulator>> start(EmulatorOptions options);
  PlcEmulator(const PlcEmulator&) = delete;
  PlcEmulator& operator=(const PlcEmulator&) = delete;
  ~PlcEmulator();
  void stop() noexcept;

  [[nodiscard]] std::uint16_t port() const noexcept;
  [[nodiscard]] net::Endpoint endpoint() const;
  [[nodiscard]] const RegisterMap& map() const noexcept;

  using RelayHandler = std::function<void(const RelayEvent&)>;
  void on_relay_change(RelayHandler handler);

  [[nodiscard]] bool relay(Relay r) const;
  void set_relay(Relay r, bool on);
  // PlcErrc::invalid_argument for a name the map does not have.
  Result<void> set_sensor(std::string_view name, double value);
  Result<void> set_sensor_fault(std::string_view name);
  [[nodiscard]] Result<std::optional<double>> sensor(std::string_view name) const;
  // PlcErrc::invalid_argument when the script names a sensor the map does not have.
  Result<void> set_script(SensorScript script);

  [[nodiscard]] EmulatorCounters counters() const;

  class Impl;

 private:
  explicit PlcEmulator(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace axon::fps::plc
