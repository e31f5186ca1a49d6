// Configuration of one simulated positioner: identity, mechanics, state at power-up, timings,
// readings and where it sits on the focal plane.
//
// Angles are degrees at the arm; the physical frame of an arm has 0 at its datum (the zero found
// at the lower hard stop) and the hard stops at -hard_stop_lower_deg and 360 + hard_stop_upper_deg
// (interface document 2.2: each between 5 and 10 degrees). Durations are simulated time.
#pragma once

#include "axon/core/config.hpp"
#include "axon/core/error.hpp"
#include "axon/fps/layout/arm_lengths.hpp"
#include "axon/fps/protocol/commands.hpp"
#include "axon/fps/protocol/firmware_gates.hpp"
#include "axon/fps/protocol/firmware_version.hpp"
#include "axon/fps/sim/sim_time.hpp"

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

namespace axon::fps::sim {

using namespace std::chrono_literals;

// START_TRAJECTORY (or the sync line) while no trajectory is loaded. The interface document says
// only that the command starts a loaded trajectory (5.3.8, 6, 7.2). Robots in service answer
// COMMAND_ACCEPTED and stay where they are, which host software in service relies on when it moves
// a subset of the plane with one broadcast (it waits for every robot's acceptance).
enum class EmptyStart : std::uint8_t {
  accept,  // code 0, nothing moves (robots in service; the default)
  refuse,  // code 2 INVALID_TRAJECTORY (the simulator's behaviour before issue 14)
};

// The version gates (which commands a version has, the oldest modelled status layout) are the
// host's too: protocol/firmware_gates.hpp.
using protocol::FirmwareHistory;
using protocol::firmware_takes;
using protocol::kOldestModelledFirmware;

struct PositionerConfig {
  // Identity.
  std::uint16_t id = 1;                                    // 1..2047
  protocol::FirmwareVersion firmware{4, 1, 13};            // main application at power-up
  protocol::FirmwareVersion bootloader{3, 80, 1};          // middle number 80
  protocol::DeviceOptions device_options{};                // firmware quirks (112 read as a get)
  FirmwareHistory firmware_history = FirmwareHistory::document;  // commands per version
  // How GET_FIRMWARE_VERSION's reply orders its bytes (firmware_version.hpp): the field's order,
  // or the document's prose order for firmware that really does it.
  protocol::VersionByteOrder version_byte_order = protocol::VersionByteOrder::field;
  EmptyStart start_without_trajectory = EmptyStart::accept;   // START_TRAJECTORY with nothing loaded

  // Mechanics.
  double gear_ratio = 1000.0;                              // motor turns per arm turn
  PerArm<double> hard_stop_lower_deg{{5.0, 5.0}};          // lower stop at -this
  PerArm<double> hard_stop_upper_deg{{5.0, 5.0}};          // upper stop at 360 + this
  std::uint32_t default_speed_rpm = 2000;                  // at the motor: 12 deg/s at 1000:1
  std::uint32_t min_speed_rpm = 1;                         // factory limits for SET_SPEED and trajectories
  std::uint32_t max_speed_rpm = 5000;
  std::uint32_t max_current_percent = 100;                 // factory limit for SET_CURRENT
  std::uint32_t default_drive_current_percent = 60;        // open-loop drive current until SET_CURRENT
  double precise_approach_deg = 0.9;                       // the open-loop approach of go-to moves
  double datum_backoff_deg = 5.0;                          // back-off between datum calibration hits
  double motor_calibration_turns = 3.0;                    // motor turns of the motor calibration sweep
  double datum_spread_motor_deg = 40.0;                    // spread of datum calibration hits (motor deg)
  // Closed-loop motor current while an arm turns (GET_CURRENTS and 54/55), in percent: a stiction
  // part plus a viscous part growing with the motor speed (interface document 9.4.2's model).
  PerArm<double> stiction_current_percent{{15.0, 15.0}};
  PerArm<double> viscous_current_percent_per_krpm{{5.0, 5.0}};

  // State at power-up (what the flash holds when the simulation starts).
  bool motors_calibrated = true;
  bool datums_calibrated = true;
  bool cogging_calibrated = true;
  bool datums_initialized = true;                          // a position was saved at the last power-down
  PerArm<double> start_position_deg{{0.0, 180.0}};         // physical; folded by default
  bool sync_line_low_at_power_on = false;                  // start in the bootloader

  // Communication.
  std::size_t receive_buffer = 16;                         // frames waiting to be processed

  // Durations (simulated time).
  SimDuration boot_time = 50ms;                            // silent after power-on
  SimDuration bootloader_timeout = 10s;                    // bootloader waits this long for commands
  SimDuration watchdog_timeout = 30s;                      // a firmware that does not boot is replaced after this
  SimDuration hall_wake_up = 5s;                           // SWITCH_ON_HALL until the sensors work
  SimDuration led_blink = 2s;                              // the LED blinks this long after power-up
  SimDuration motor_calibration_time = 20s;
  SimDuration cogging_calibration_time = 40min;            // after the drive to the hard stop
  // The sync line (interface document 6): after a rising edge the firmware waits this long and
  // looks at the line again; only a line still high starts the trajectory. The document says "a
  // few milliseconds" without a figure; hosts in service hold the line about 0.5 s.
  SimDuration sync_recheck = 5ms;

  // Storage and readings.
  std::uint32_t max_firmware_size = 256 * 1024;            // START_FIRMWARE_UPGRADE above: code 1
  std::uint32_t cogging_vector_length = 1024;
  std::uint32_t raw_temperature = 2100;                    // raw sensor reading, idle

  // Focal-plane geometry for the neighbour collision check (millimetres, degrees). A simulator
  // given a plane's geometry (SimulatorConfig::geometry, a layout's) takes that for the robots it
  // lists instead; a plane simulated from a layout fills these with the layout's figures.
  double x_mm = 0;
  double y_mm = 0;
  double orientation_deg = 0;                              // direction of alpha = 0 on the plane
  ArmLengths arms;                                         // the collision segment: beta_collision_mm
  double collision_buffer_mm = 2.0;                        // capsule radius around that segment

  // Seed of the deterministic "noise" (datum hits, calibration errors, cogging tables).
  std::uint64_t seed = 1;

  // Checks ranges; errors name the field (CoreErrc::invalid_argument).
  [[nodiscard]] Result<void> validate() const;

  // Reads the keys present in `node` on top of `base` (unknown keys are errors). Keys: id, firmware
  // ("04.01.13"), bootloader, get_holding_current_on_112, firmware_history (document | field),
  // version_byte_order (field | document),
  // start_without_trajectory (accept | refuse), gear_ratio, hard_stop_lower_deg and
  // hard_stop_upper_deg ([alpha, beta] or one number), default_speed_rpm, min_speed_rpm,
  // max_speed_rpm, max_current_percent, default_drive_current_percent, stiction_current_percent and
  // viscous_current_percent_per_krpm ([alpha, beta] or one number), precise_approach_deg,
  // datum_backoff_deg, motor_calibration_turns, datum_spread_motor_deg, motors_calibrated,
  // datums_calibrated, cogging_calibrated, datums_initialized, start_position_deg ([alpha, beta]),
  // sync_line_low_at_power_on, receive_buffer, boot_time_s, bootloader_timeout_s,
  // watchdog_timeout_s, hall_wake_up_s, led_blink_s, motor_calibration_time_s,
  // cogging_calibration_time_s, sync_recheck_s, max_firmware_size, cogging_vector_length,
  // raw_temperature, x_mm, y_mm, orientation_deg, alpha_arm_mm (arms.alpha_length_mm), beta_arm_mm
  // (arms.beta_collision_mm), collision_buffer_mm, seed.
  // `also_allowed` names keys the caller reads itself (e.g. "bus" in a simulator's robot list).
  static Result<PositionerConfig> from_config(const core::ConfigNode& node, const PositionerConfig& base,
                                              std::span<const std::string_view> also_allowed = {});
  static Result<PositionerConfig> from_config(const core::ConfigNode& node);
};

}  // namespace axon::fps::sim
