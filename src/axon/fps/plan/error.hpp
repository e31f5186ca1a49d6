// Errors of the fps planning geometry: why a target cannot be reached or accepted.
//
// Inverse kinematics and target validation report one of these per robot; file parsing reports
// bad_target_file with the file, line and what was wrong in the detail.
#pragma once

#include "axon/core/error.hpp"

namespace axon::fps::plan {

enum class PlanErrc {
  too_close = 1,       // the point is inside the inner radius of the annulus the fibre can reach
  too_far,             // the point is beyond the outer radius of that annulus
  outside_hard_stops,  // reachable, but neither elbow's angles lie within the robot's angle limits
  unknown_robot,       // a target names a robot id the focal plane does not have
  unknown_fibre,       // a target names a fibre the beta arm does not carry
  duplicate_target,    // the same robot appears twice in one target set
  robot_collision,     // the target pose brings the beta arm too close to a neighbour's
  obstacle_collision,  // the target pose brings the beta arm too close to a fiducial or obstacle
  bad_target_file,     // the target file cannot be parsed (syntax, missing or contradicting columns)
  bad_trajectory,      // a trajectory is empty, has decreasing times or non-finite values
  outside_safe_zone,   // targets leave their robots' safe zones (spec section 11; safe_zone.hpp)
};

const std::error_category& plan_category() noexcept;
inline std::error_code make_error_code(PlanErrc e) noexcept { return {static_cast<int>(e), plan_category()}; }

}  // namespace axon::fps::plan

template <>
struct std::is_error_code_enum<axon::fps::plan::PlanErrc> : std::true_type {};
