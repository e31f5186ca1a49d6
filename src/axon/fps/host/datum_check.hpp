// The check the protocol document asks for before a datum search or a datum calibration (5.3.11 to
// 5.3.16): the chosen arms run to their hard stops and a collision on the way would be taken for
// the stop, so nothing may be in the region they can sweep. The robot's and its neighbours'
// positions are read, and plan::check_sweep_to_stops proves the region clear against the
// neighbours' poses and the fixed obstacles of the layout's geometry.
#pragma once

#include "axon/fps/host/array.hpp"
#include "axon/fps/plan/collision.hpp"
#include "axon/fps/plan/stop_sweep.hpp"

#include <boost/asio/awaitable.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace axon::fps::host {

// Errors: HostErrc::locked (the array's lock refuses the datum),
// HostErrc::unknown_positioner (the robot is not in the model or the array),
// HostErrc::not_ready naming a neighbour whose position could not be read (an unknown pose cannot
// be proven clear) or, when the sweep is not clear, every body in the way with its clearance.
// The pose of every robot of `model`, read from the robot at `index` and its neighbours (the others
// never meet it and are left at 0, 0). A position that cannot be read is HostErrc::not_ready:
// "<what> refused: the position of neighbour 7 is unknown (...)": an unknown pose cannot be proven
// clear.
boost::asio::awaitable<Result<std::vector<plan::Pose>>> read_poses_around(Array& array, const plan::CollisionModel& model,
                                                                          std::size_t index, const std::string& what);

boost::asio::awaitable<Result<plan::StopSweep>> check_datum_sweep(Array& array, const plan::CollisionModel& model,
                                                                  std::uint16_t id, Arm arm);

}  // namespace axon::fps::host
