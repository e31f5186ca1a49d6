// Safe zones (spec section 11): how far the end of a positioner's beta arm may really be from where
// its commanded angles put it, for a robot within the mechanical specification, and the check of a
// set of target poses against that zone.
//
// The error budget (11.1.1, 11.1.2) is kept per arm as its parts: a length tolerance, the
// circularity and thermal change of the arm's length, and four angle errors (hysteresis,
// non-linearity, the fibres' torque, the control error while moving). From a robot's own arm
// lengths (Positioner::arms()) they give the safe zone of its arm end (11.1.3):
// - a length error, the two arms' length errors stacked (-0.249 .. +0.239 mm for the design), and
// - a lateral error: the alpha arm swings by its angle error; the beta arm's direction errs by both
//   angle errors, because it turns with the alpha arm (the document's 848 um for the beta arm is
//   sin(1.50 + 1.48 deg) x 16.321 mm; its formula names the beta error only), plus the beta arm's
//   thermal term: +-1.046 mm for the design.
//
// check_safe_zone() says, per robot, whose target would take the arm end out of its safe zone:
// - reach (targets given as a fibre's focal-plane point): a point within the length error of the
//   edge of the annulus the fibre can reach cannot be reached by every robot within the
//   tolerances: the check names the robot and by how much the point lies outside the annulus
//   shrunk by the errors;
// - clearance: a target whose collision clearance (collision.hpp: distance minus both buffers)
//   leaves less room than the safe zones of the two robots (or of the robot, for a fixed obstacle)
//   need: a robot within the tolerances may touch there. Named with the other robot or obstacle
//   and by how much the clearance falls short.
// Nothing here allocates per check beyond the report.
#pragma once

#include "axon/fps/plan/collision.hpp"
#include "axon/fps/plan/targets.hpp"

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace axon::fps::plan {

// One arm's error budget: lengths in mm (thermal bounds signed), angles in degrees (+-).
struct ArmErrorBudget {
  double length_tolerance_mm = 0.100;
  double circularity_mm = 0.015;
  double thermal_min_mm = 0;  // <= 0
  double thermal_max_mm = 0;  // >= 0
  double hysteresis_deg = 0.30;
  double non_linearity_deg = 0.60;
  double fibre_torque_deg = 0.50;
  double dynamic_deg = 0;
  double thermal_lateral_mm = 0;  // lateral error from heat (beta: +-0.001 mm)

  [[nodiscard]] double length_min_mm() const noexcept { return -length_tolerance_mm - circularity_mm + thermal_min_mm; }
  [[nodiscard]] double length_max_mm() const noexcept { return length_tolerance_mm + circularity_mm + thermal_max_mm; }
  [[nodiscard]] double angle_deg() const noexcept {
    return hysteresis_deg + non_linearity_deg + fibre_torque_deg + dynamic_deg;
  }
};

// Both arms' budgets; the defaults are the document's tables (aluminium parts, -40 .. +20 K).
struct PositionerErrors {
  ArmErrorBudget alpha{.thermal_min_mm = -0.006, .thermal_max_mm = 0.003, .dynamic_deg = 0.10};
  ArmErrorBudget beta{.thermal_min_mm = -0.013, .thermal_max_mm = 0.006, .dynamic_deg = 0.08, .thermal_lateral_mm = 0.001};
};

// The safe zone of one robot's arm end (mm).
struct SafeZone {
  double alpha_length_min_mm = 0, alpha_length_max_mm = 0;
  double beta_length_min_mm = 0, beta_length_max_mm = 0;
  double alpha_lateral_mm = 0;  // the alpha arm's share of the lateral error
  double beta_lateral_mm = 0;   // the beta arm's share (both angle errors, thermal term)

  [[nodiscard]] double length_min_mm() const noexcept { return alpha_length_min_mm + beta_length_min_mm; }
  [[nodiscard]] double length_max_mm() const noexcept { return alpha_length_max_mm + beta_length_max_mm; }
  [[nodiscard]] double lateral_mm() const noexcept { return alpha_lateral_mm + beta_lateral_mm; }
  // The farthest the real arm end can be from the commanded one (length and lateral at once).
  [[nodiscard]] double radius_mm() const noexcept;
};

// The safe zone of a robot with these arm lengths (its own: Positioner::arms()).
[[nodiscard]] SafeZone safe_zone(const ArmLengths& arms, const PositionerErrors& errors = {}) noexcept;

struct SafeZoneIssue {
  enum class Kind : std::uint8_t {
    beyond_reach,        // the fibre's target point lies too near the outer edge of its annulus
    inside_reach,        // ... too near the inner edge (folded)
    robot_clearance,     // too little room to a neighbour's arm for both safe zones
    obstacle_clearance,  // too little room to a fixed obstacle for the robot's safe zone
  };
  std::int32_t robot = 0;
  Kind kind = Kind::beyond_reach;
  double by_mm = 0;            // how far the target is outside the safe zone (> 0)
  std::int32_t other = 0;      // the neighbour's id (robot_clearance)
  std::string obstacle;        // the obstacle's name (obstacle_clearance)
  [[nodiscard]] std::string to_string() const;  // "robot 12: target 0.180 mm beyond ..."
};
std::string_view to_string(SafeZoneIssue::Kind k) noexcept;

struct SafeZoneReport {
  std::vector<SafeZoneIssue> issues;  // by robot (model order), then kind
  [[nodiscard]] bool ok() const noexcept { return issues.empty(); }
  // The robots with an issue, ascending, each once.
  [[nodiscard]] std::vector<std::int32_t> robots() const;
  // One line per issue.
  [[nodiscard]] std::string summary() const;
};

struct SafeZoneOptions {
  PositionerErrors errors{};
  bool reach = true;
  bool clearance = true;
};

// What the check needs to know of the targets besides their poses (each optional, model order).
struct SafeZoneTargets {
  // Robots not reported themselves (frozen, held, untargeted) but still neighbours of the others.
  std::vector<bool> skip;
  // The fibre (index into the design's fibres) whose focal-plane point a robot's target is: only
  // such targets get the reach check (an explicit pose is reached by every robot; its arm end is
  // then off by the length error, which the clearance check covers).
  std::vector<std::optional<std::size_t>> point_fibre;
};

// Checks `targets` (one pose per robot, model order). A pair of robots is reported once, on the
// first of the two in model order that is not skipped.
[[nodiscard]] SafeZoneReport check_safe_zone(const CollisionModel& model, std::span<const Pose> targets,
                                             const SafeZoneTargets& which = {}, const SafeZoneOptions& options = {});

// point_fibre for a target set resolved to `poses` (target_poses): robots whose target is a
// focal-plane point that their pose puts the fibre on (parked targets do not).
[[nodiscard]] std::vector<std::optional<std::size_t>> point_fibres(const CollisionModel& model, std::span<const Target> targets,
                                                                   std::span<const Pose> poses);

}  // namespace axon::fps::plan
