#include "axon/c4g/sim/robots.hpp"

#include "axon/c4g/sim/robot_file.hpp"

#include <fmt/format.h>

#include <filesystem>

namespace axon::c4g::sim {

protocol::InitPacket six_axis_init() {
  protocol::InitPacket p;
  p.protocol_number = 10;
  p.fields_per_packet = 3;
  p.fields_per_axis = 9;
  p.open_axes = 6;
  // Start-up modes: all 0. Open axes of arm 1: logical 1..6; the printout's "X" slots are 0 here.
  p.open_axis_list[0] = {1, 2, 3, 4, 5, 6, 0, 0, 0, 0};
  p.calibration[0] = {0.142965f, 0.170353f, 0.222660f, 0.405883f, 0.039380f, 0.355824f, 0, 0, 0, 0};
  p.current_limit[0] = {24.5f, 24.5f, 24.5f, 9.5f, 9.5f, 9.5f, 0, 0, 0, 0};
  p.transmission_ratio[0] = {-181.587296f, 159.260864f, 162.473694f, 72.585968f, 78.75f, -50.0f, 0, 0, 0, 0};
  p.influence[0] = {0, 0, 0, -0.02f, 0.0204f, 0.02f, 0, 0, 0, 0};
  p.following_error[0] = {7.5f, 7.5f, 7.5f, 7.5f, 7.5f, 0, 0, 0, 0, 0};
  p.packet_field_types = {1, 2, 3};
  p.axis_field_types = {1, 2, 2, 2, 2, 2, 3, 3, 3};
  p.period_ms = 2;
  p.version_major = 3;
  p.version_minor = 11;
  p.version_build = 115;
  return p;
}

RobotConfig six_axis_robot() {
  RobotConfig r;
  r.name = "six-axis";
  r.init = six_axis_init();
  // A medium industrial arm: big base motors, small wrist motors; link inertias about the joints.
  const double motor_inertia[6] = {1.2e-3, 1.2e-3, 8e-4, 2.5e-4, 2.5e-4, 1.5e-4};
  const double load_inertia[6] = {60.0, 55.0, 18.0, 1.2, 0.9, 0.3};
  const double torque_constant[6] = {1.2, 1.2, 1.0, 0.6, 0.6, 0.5};
  const double friction[6] = {3e-3, 3e-3, 2e-3, 6e-4, 6e-4, 4e-4};
  for (std::size_t i = 0; i < 6; ++i) {
    AxisParams& a = r.axes[0][i];
    a.motor_inertia = motor_inertia[i];
    a.load_inertia = load_inertia[i];
    a.torque_constant = torque_constant[i];
    a.viscous_friction = friction[i];
    a.current_limit = r.init.current_limit[0][i];
    a.following_error = r.init.following_error[0][i];
  }
  return r;
}

std::vector<std::string> robot_names() { return {"six-axis"}; }

Result<RobotConfig> find_robot(std::string_view name) {
  if (name == "six-axis") return six_axis_robot();
  if (std::filesystem::is_regular_file(std::filesystem::path(std::string(name)))) return load_robot_file(std::string(name));
  return Error(CoreErrc::invalid_argument,
               fmt::format("unknown robot '{}' (known: six-axis, or a file: a 1200-byte initialization packet or its fields in YAML)", name));
}

}  // namespace axon::c4g::sim
