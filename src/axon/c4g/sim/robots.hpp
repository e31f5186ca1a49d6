// Simulated robots: what the controller announces in its initialization packet, plus the physical
// data of each axis the simulator integrates (motor and reflected inertia, friction, torque constant,
// DSA loop gains).
//
// Units on the motor side follow the packet: positions in motor turns (calibrated, i.e. the
// calibration constant q0 included, as the packet's D1/D3), velocities in motor turns per second
// inside the model (the packet's "delta motor turns" per cycle at its edges), currents in A.
#pragma once

#include "axon/c4g/protocol/init_packet.hpp"
#include "axon/c4g/protocol/soft_switch.hpp"
#include "axon/core/error.hpp"

#include <array>
#include <string>
#include <string_view>
#include <vector>

namespace axon::c4g::sim {

// Physical data of one motor-side axis.
struct AxisParams {
  double motor_inertia = 1e-3;      // [kg m^2] rotor
  double load_inertia = 0.0;        // [kg m^2] link inertia seen at the link (reflected by ratio^2)
  double viscous_friction = 2e-3;   // [N m s / rad] at the motor
  double torque_constant = 1.0;     // [N m / A]
  double current_limit = 10.0;      // [A] (the initialization packet's armNAzLim)
  double following_error = 0.0;     // [motor turns] threshold, <= 0: not checked
  // DSA loops (position P, velocity PI with anti-windup; the current loop is taken as ideal).
  double kp = 40.0;                 // [1/s] position gain: velocity reference per position error
  double velocity_bandwidth = 300;  // [rad/s] sets kv = J_total * bandwidth / kt
  double velocity_integral = 20;    // [1/s] ki = kv * velocity_integral

  // Total inertia at the motor given the transmission ratio.
  [[nodiscard]] double total_inertia(double ratio) const noexcept {
    return motor_inertia + (ratio != 0.0 ? load_inertia / (ratio * ratio) : 0.0);
  }
};

// Soft control switching on the controller's side (sim/soft_switch.hpp, docs/c4g-simulator.md).
struct SoftSwitchConfig {
  protocol::SwitchTimes times;    // T1, T2, T3 (defaults 50 + 100 + 50 ms: protocol/soft_switch.hpp)
  double still_tolerance = 0.02;  // [motor turns] largest excursion from the start during T1..T3
  double still_velocity = 0.2;    // [motor turns/s] faster than this, the robot moves: the program
                                  // cannot change modes (the state machine's S00 state is "not moving")
  bool reduce_pc_current = true;  // the controller scales the PC's current (eta in, rho out); false:
                                  // the PC's regulators do it themselves and D5 is applied as sent
};

struct RobotConfig {
  std::string name;
  protocol::InitPacket init;       // what the controller announces (period, axes, limits, ...)
  // Physical data per arm and logical axis [arm-1][axis-1]; used for the open axes.
  std::array<std::array<AxisParams, protocol::kAxesPerArm>, protocol::kMaxArms> axes{};
  double drive_on_s = 0.3;         // length of the drive-on procedure (mode 501)
  double drive_off_s = 0.05;       // length of the drive-off procedure (mode 505 shown meanwhile)
  SoftSwitchConfig scs;            // soft control switching entering/leaving modes 1 and 2
  int standby_cycles = 3;          // cycles spent in a standby code (4', 5', 7'', ...) when leaving
  // Modes 7, 8, 9: the largest offset between a reference position and the one scheduled before it
  // [motor turns/s, times the period per cycle] (the manual gives no figure; above the Server's
  // default continuity limit of 100 turns/s so that a PC's own check refuses first).
  double max_offset_speed = 150.0;
};

// The manual's initialization example: one six-axis arm, 2 ms, software 3.11.115.
protocol::InitPacket six_axis_init();
// The default simulated robot built on it.
RobotConfig six_axis_robot();

// Robots by name ("six-axis") or from a file (robot_file.hpp: a captured initialization packet or
// its fields in YAML); invalid_argument listing the known names otherwise.
Result<RobotConfig> find_robot(std::string_view name);
std::vector<std::string> robot_names();

}  // namespace axon::c4g::sim
