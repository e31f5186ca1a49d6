// Correction moves after a measurement of the fibres (pure: no I/O but reading a file).
//
// After a move the fibre viewing camera measures where each fibre really is. The measured position
// says where the commanded angles actually put the fibre; the difference between the inverse
// kinematics of the target and of the measured point, both with the elbow the robot stands in, is
// the angular error of the command. The new command is the current one plus that difference:
//
//     command_new = command + (IK(target) - IK(measured))
//
// To first order this is the same as commanding IK(target + (target - measured)); it is exact when
// the robot's miss is a constant angular offset of its arms (zero errors, backlash), the dominant
// term in practice.
//
// Robots whose fibre is within `tolerance_mm` of its target are left alone; robots whose target or
// measured point cannot be reached with their elbow, whose new command falls outside the angle
// limits or whose correction exceeds `max_correction_deg` (a sign of a mis-identified fibre) are
// reported and not moved.
//
// Measurement files are CSV with a header naming the columns `robot`, `x`, `y` (mm, focal-plane
// coordinates) and optionally `fibre`; `#` starts a comment, blank lines are skipped.
#pragma once

#include "axon/core/error.hpp"
#include "axon/fps/plan/collision.hpp"
#include "axon/fps/plan/targets.hpp"

#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace axon::fps::host {

enum class CorrectionErrc {
  cannot_open = 1,   // the measurement file cannot be read
  missing_column,    // the header lacks robot, x or y, or a row has too few cells
  unknown_column,    // the header names a column that is not known
  not_a_number,      // a cell that must be a number is not one
  duplicate_robot,   // the same robot measured twice in one file
  unknown_robot,     // a robot that is not part of the focal plane
};

const std::error_category& correction_category() noexcept;
inline std::error_code make_error_code(CorrectionErrc e) noexcept { return {static_cast<int>(e), correction_category()}; }

struct Measurement {
  std::int32_t robot = 0;
  plan::Vec2 position;                // mm, focal-plane coordinates
  std::optional<std::string> fibre;   // which fibre was measured, when the file says
  int line = 0;                       // where it came from
};

struct MeasurementSet {
  std::string source;                 // file name (for messages)
  std::vector<Measurement> items;     // in file order

  [[nodiscard]] const Measurement* find(std::int32_t robot) const noexcept;
};

// Parses a measurement CSV. When `known_robots` is not empty, a robot outside it is an error.
// Errors carry "name:line: what".
Result<MeasurementSet> parse_measurements_csv(std::string_view text, const std::string& name,
                                              std::span<const std::int32_t> known_robots = {});
Result<MeasurementSet> load_measurements(const std::string& path, std::span<const std::int32_t> known_robots = {});

struct CorrectionOptions {
  double tolerance_mm = 0.005;        // 5 um
  double max_correction_deg = 5.0;    // per arm; larger ones are refused
};

enum class CorrectionStatus : std::uint8_t {
  within_tolerance,  // left alone
  move,              // a correction move is needed (command holds it)
  unreachable,       // no correction possible (detail says why); not moved
  not_measured,      // the measurement does not include this robot
  no_position,       // the robot's current angles are unknown (did not answer, not in the array)
};
std::string_view to_string(CorrectionStatus s) noexcept;

struct RobotCorrection {
  std::int32_t robot = 0;
  CorrectionStatus status = CorrectionStatus::not_measured;
  std::string fibre;                  // the fibre the target is for
  plan::Vec2 target;                  // mm
  std::optional<plan::Vec2> measured; // mm
  plan::Vec2 error;                   // measured - target, mm
  double error_mm = 0;                // its length
  std::optional<plan::Pose> current;  // the commanded angles the measurement belongs to
  plan::Elbow elbow = plan::Elbow::ccw;
  plan::Pose delta;                   // correction, deg (status move)
  plan::Pose command;                 // the new command, deg (status move)
  std::string detail;                 // why not, for unreachable / not_measured / no_position
};

struct CorrectionPlan {
  std::vector<RobotCorrection> robots;  // one per target, in target order
  std::vector<std::string> notes;       // measured robots without a target, fibre mismatches ...
  double tolerance_mm = 0.005;

  [[nodiscard]] std::size_t count(CorrectionStatus s) const noexcept;
  // Largest error among measured robots (0 without any).
  [[nodiscard]] double worst_error_mm() const noexcept;
  // Every targeted robot measured and within tolerance.
  [[nodiscard]] bool converged() const noexcept;
  [[nodiscard]] const RobotCorrection* find(std::int32_t robot) const noexcept;
  // The moves to send: robot -> new command.
  [[nodiscard]] std::map<std::int32_t, plan::Pose> moves() const;
};

// Where the target of `t` lies for `robot` (its point, or the fibre's position at its pose) and the
// fibre's index. Errors: unknown fibre.
Result<std::pair<plan::Vec2, std::size_t>> target_point(const plan::Positioner& robot, const plan::ArmDesign& design,
                                                        const plan::Target& t);

// The elbow the robot stands in at `pose` for fibre `fibre`.
plan::Elbow elbow_of(const plan::Positioner& robot, plan::Pose pose, std::size_t fibre);

// One correction decision per target. `current` holds each robot's commanded angles now (what
// the measurement belongs to).
CorrectionPlan plan_corrections(const plan::CollisionModel& model, std::span<const plan::Target> targets,
                                const MeasurementSet& measured, const std::map<std::int32_t, plan::Pose>& current,
                                const CorrectionOptions& options = {});

}  // namespace axon::fps::host

template <>
struct std::is_error_code_enum<axon::fps::host::CorrectionErrc> : std::true_type {};
