// Where the PLC keeps what: coils (relays) and input registers (sensors), and how raw register
// values become engineering units. The default map is documented in docs/fps-plc.md; a site
// whose PLC program differs gives its own in YAML:
//
//   unit_id: 1
//   coils:
//     positioner_power: [0, 1, 2, 3, 4, 5]    # 24 V to the robots of sextants 1..6
//     gateway_power: [8, 9, 10, 11, 12, 13]   # the Ethernet-CAN gateway of sextants 1..6
//     sync_line: 16
//   input_registers:
//     temperatures:                           # signed, 0.1 degC unless `scale` says otherwise
//       - {name: fps_plate, address: 0}
//     humidity: {address: 16, scale: 0.1}     # unsigned, % RH
//     pressure: {address: 17, scale: 0.1}     # unsigned, hPa
//     coolant_flow: {address: 18, scale: 0.01}  # unsigned, l/min
//
// A register holding the "no reading" value (0x8000 signed, 0xFFFF unsigned) means the sensor is
// disconnected or faulty; it reads as no value, never as a temperature of -3276.8 degC.
#pragma once

#include "axon/core/config.hpp"
#include "axon/core/error.hpp"

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace axon::fps::plc {

inline constexpr int kSextants = 6;

enum class RelayKind : std::uint8_t { positioner_power, gateway_power, sync_line };
[[nodiscard]] std::string_view relay_kind_name(RelayKind k) noexcept;

struct Relay {
  RelayKind kind = RelayKind::sync_line;
  int sextant = 0;  // 1..6 for power relays, 0 for the sync line
  bool operator==(const Relay&) const = default;
  [[nodiscard]] std::string to_string() const;  // "positioner power 3", "sync line"
};

struct AnalogInput {
  std::string name;
  std::uint16_t address = 0;
  double scale = 0.1;      // engineering units per count
  bool is_signed = false;  // int16 (temperatures) or uint16
  std::string unit;

  // nullopt for the "no reading" value.
  [[nodiscard]] std::optional<double> decode(std::uint16_t raw) const noexcept;
  // Clamped to the register's range; nullopt encodes "no reading".
  [[nodiscard]] std::uint16_t encode(std::optional<double> value) const noexcept;
};

struct SensorReading {
  std::string name;
  std::optional<double> value;  // engineering units; nullopt: sensor fault
  std::string unit;
};

struct RegisterMap {
  int unit_id = 1;
  std::array<std::uint16_t, kSextants> positioner_power{0, 1, 2, 3, 4, 5};
  std::array<std::uint16_t, kSextants> gateway_power{8, 9, 10, 11, 12, 13};
  std::uint16_t sync_line = 16;
  std::vector<AnalogInput> temperatures = default_temperatures();
  AnalogInput humidity{"humidity", 16, 0.1, false, "%RH"};
  AnalogInput pressure{"pressure", 17, 0.1, false, "hPa"};
  AnalogInput coolant_flow{"coolant_flow", 18, 0.01, false, "l/min"};

  static std::vector<AnalogInput> default_temperatures();
  // Keys absent from the file keep the defaults above. Errors located by file:line:col.
  static Result<RegisterMap> from_config(const core::ConfigNode& node);

  // Distinct addresses, names, sane scales (PlcErrc::bad_map).
  [[nodiscard]] Result<void> validate() const;
  [[nodiscard]] std::uint16_t coil_of(Relay r) const noexcept;  // r must be valid (sextant 1..6)
  [[nodiscard]] std::optional<Relay> relay_at(std::uint16_t coil) const noexcept;
  [[nodiscard]] std::vector<Relay> relays() const;  // every relay, power by sextant, then the sync line
  // One past the highest address used.
  [[nodiscard]] std::uint16_t coil_span() const noexcept;
  [[nodiscard]] std::uint16_t input_register_span() const noexcept;
  // Every analogue input: temperatures, then humidity, pressure, coolant flow.
  [[nodiscard]] std::vector<const AnalogInput*> inputs() const;
  [[nodiscard]] const AnalogInput* input(std::string_view name) const noexcept;
};

}  // namespace axon::fps::plc
