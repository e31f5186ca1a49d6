// Moving robots out of a contact, as the protocol document asks after a collision (9.4.1: clear
// the flags, then move the robot away by at least 2 degrees) and as a power loss mid-move needs
// (robots that stop dead can stand a fraction of a millimetre inside a neighbour's collision
// buffer, and the planner then holds them where they stand). Each move is one arm of one robot,
// certified by plan::plan_back_off against every neighbour's pose as read from the robots: it never
// brings a contact closer and touches nothing new. Robots move one at a time, each move planned
// from the poses the previous moves left.
#pragma once

#include "axon/fps/host/array.hpp"
#include "axon/fps/plan/collision.hpp"
#include "axon/fps/plan/stop_sweep.hpp"

#include <boost/asio/awaitable.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace axon::fps::host {

struct BackOffStep {
  std::uint16_t id = 0;
  plan::BackOff plan;   // the certified move (plan.found false: there was none)
  bool moved = false;
  std::string problem;  // why the robot did not move, "" when it did
};

struct BackOffReport {
  std::vector<std::string> contacts_before;  // "robot 1 / robot 2 (-0.083 mm)", at the full buffer
  std::vector<BackOffStep> steps;
  std::vector<std::string> contacts_after;   // between robots whose poses are known
  // Every robot asked for moved and no contact is left.
  [[nodiscard]] bool ok() const noexcept;
  // One line per step and the contacts before and after, for an operator.
  [[nodiscard]] std::string summary() const;
};

struct BackOffRequest {
  // The robots to move away (after a collision, the robot that reported it). Empty: every robot in
  // contact with another or with a fixed obstacle, one robot per contact (the first of the pair
  // with a move that ends clear).
  std::vector<std::uint16_t> ids;
  plan::BackOffOptions plan;
};

// Errors: HostErrc::locked (the array's lock refuses the moves: unlock first, which clears the
// collision flags as the document asks), HostErrc::unknown_positioner (a robot not in the model or
// the array). Everything else (no certified move, a neighbour whose position is unknown, a move
// that failed) is in the report.
boost::asio::awaitable<Result<BackOffReport>> back_off(Array& array, const plan::CollisionModel& model,
                                                       BackOffRequest request);

}  // namespace axon::fps::host
