// Troubleshooting false collisions (interface document 9.4.2 and 9.4.3) as host diagnostics with a
// verdict per robot and arm (the results: troubleshoot_types.hpp).
//
// Both run test moves: one arm of one robot turned by a few degrees and back, alone. Before each,
// the robot's and its neighbours' positions are read and the sweep is proven clear of them and of
// the fixed obstacles with the planner's geometry (plan::check_arm_sweep), first in the positive
// direction, then in the negative one; a robot with no room either way is not tested and says what
// is in the way. The moves go through the command client, so the array's collision lock refuses
// them like any other move.
//
// friction_survey (9.4.2): per arm, a test move there and back at each of the options' motor
// speeds, reading position and current while the arm is between 10 % and 90 % of the way; the
// median current per speed is fitted with a stiction plus viscous line, and the fit is compared
// with the arm's first record in the history: grown beyond the limit is `increased`, with the
// document's advice (a higher collision margin; a lower speed in the cold). Robots that are not
// neighbours of each other are measured at the same time.
//
// hall_test (9.4.3): per arm, open loop without collision detection (121 / 125), the hall reading
// (44) and the position (32), a relative move at low speed, both read again, the move back, then
// closed loop with collision detection (118 / 122) and the speed restored on every way out. The
// host cannot look at the robot: a hall reading that did not change is a faulty sensor if the arm
// turned and a motor, cable or h-bridge fault if it did not, and the advice says to look.
#pragma once

#include "axon/fps/host/array.hpp"
#include "axon/fps/host/troubleshoot_types.hpp"
#include "axon/fps/plan/collision.hpp"

#include <boost/asio/awaitable.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace axon::fps::host {

// The signed step of a test move of `arm` (alpha or beta) of robot `id` that is proven clear:
// +step_deg when it is, else -step_deg. HostErrc::not_ready names what is in the way of both (or a
// neighbour whose position cannot be read); HostErrc::unknown_positioner for a robot not in the
// model; HostErrc::locked while the array is locked.
boost::asio::awaitable<Result<double>> clear_test_step(Array& array, const plan::CollisionModel& model, std::uint16_t id,
                                                       Arm arm, double step_deg);

// Every listed robot (empty: every robot of the model the array knows). HostErrc::locked when the
// array is locked at the start; HostErrc::invalid_argument for options that cannot measure (fewer
// than two speeds, a step not above 2 deg); everything else per arm in the report.
boost::asio::awaitable<Result<FrictionReport>> friction_survey(Array& array, const plan::CollisionModel& model,
                                                               std::vector<std::uint16_t> ids, FrictionOptions options);

// One robot. HostErrc::locked, unknown_positioner and invalid_argument as above; the rest per arm.
boost::asio::awaitable<Result<HallTestReport>> hall_test(Array& array, const plan::CollisionModel& model,
                                                         std::uint16_t id, HallTestOptions options);

// The friction history: a CSV file with the header
//   time_utc,robot,arm,stiction_percent,viscous_percent_per_krpm,rms_percent,move_ratio
// and one FrictionRecord a line (arm "alpha" or "beta"). A file that does not exist is an empty
// history; a malformed line is CoreErrc::config_bad_value naming the file and line.
Result<std::vector<FrictionRecord>> load_friction_history(const std::string& path);
// Appends (writing the header into a new file).
Result<void> append_friction_history(const std::string& path, const std::vector<FrictionRecord>& records);

}  // namespace axon::fps::host
