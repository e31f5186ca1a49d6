// Forward and inverse kinematics of the two-arm fibre positioner (millimetres, degrees).
//
// Frame conventions (docs/fps-plan.md has the figure sources):
// - A robot's centre is its alpha axis on the focal plane. Its own x axis is turned by
//   `orientation_deg` counter-clockwise from the focal plane's x axis (0 for a plate drilled
//   square to the layout).
// - alpha is measured counter-clockwise from the robot's x axis to the alpha arm; beta from the
//   alpha arm's direction to the beta arm's (beta 0: stretched out, 180: folded back).
// - Points on the beta arm are given in the beta-arm frame: x from the beta axis towards the arm's
//   end, y at right angles towards increasing beta.
// - Per-robot calibration adds zero offsets to the commanded angles and length corrections to the
//   arms: world alpha = orientation + alpha + alpha_offset; beta arm direction = world alpha +
//   beta + beta_offset; alpha arm length = nominal + alpha_length_delta; every x on the beta arm is
//   shifted by beta_length_delta, except fibres whose measured position the calibration gives.
//
// A Positioner precomputes what its hot paths need, so forward kinematics, the collision segment
// and inverse kinematics never allocate.
#pragma once

#include "axon/fps/layout/arm_lengths.hpp"
#include "axon/fps/plan/distance.hpp"
#include "axon/fps/plan/error.hpp"
#include "axon/fps/plan/vec2.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace axon::fps::plan {

// A fibre (or any marked point) carried by the beta arm, in the beta-arm frame.
struct Fibre {
  std::string name;
  Vec2 offset;
};

// Index of the nominal fibres in ArmDesign::fibres as built by default.
inline constexpr std::size_t kMetrologyFibre = 0;
inline constexpr std::size_t kApogeeFibre = 1;
inline constexpr std::size_t kBossFibre = 2;

// The nominal mechanical design shared by every robot of one focal plane: the arm lengths (the
// layout's ArmLengths, fps/layout/arm_lengths.hpp) and the fibres the beta arm carries.
struct ArmDesign : ArmLengths {
  std::vector<Fibre> fibres = default_fibres();

  // metrology (14.347, 0), apogee (14.997, +0.375), boss (14.997, -0.375): see docs/fps-plan.md.
  static std::vector<Fibre> default_fibres();
  // The index of the fibre called `name` (case-insensitive), or nullopt.
  [[nodiscard]] std::optional<std::size_t> fibre_index(std::string_view name) const;
};

// Per-robot corrections to the nominal design (all zero by default).
struct RobotCalibration {
  double orientation_deg = 0;
  double alpha_offset_deg = 0;
  double beta_offset_deg = 0;
  double alpha_length_delta_mm = 0;
  double beta_length_delta_mm = 0;
  // Measured fibre positions on this robot's beta arm, matched to the design's fibres by name
  // (case-insensitive); taken as they are (beta_length_delta_mm does not move them). Fibres not
  // listed keep the design's offset shifted by beta_length_delta_mm; names the design lacks are
  // ignored.
  std::vector<Fibre> fibres;
};

// The commanded angle range a planner may use (inside the hard stops; see docs/fps-plan.md).
struct AngleLimits {
  double alpha_min_deg = 0;
  double alpha_max_deg = 360;
  double beta_min_deg = 0;
  double beta_max_deg = 360;
};

// One robot as the focal-plane layout describes it: what the planner needs, nothing more.
struct RobotSpec {
  std::int32_t id = 0;
  Vec2 centre;
  RobotCalibration calibration{};
  AngleLimits limits{};
  double buffer_mm = 2.0;  // collision buffer: radius of the beta arm's capsule
};

struct Pose {
  double alpha_deg = 0;
  double beta_deg = 0;
  friend constexpr bool operator==(const Pose&, const Pose&) = default;
};

// The two inverse-kinematics branches. ccw: seen from the beta axis, the fibre lies counter-clockwise
// of the alpha arm's direction (angle in [0, 180] deg; beta about 0..180); cw: clockwise (beta about
// 180..360). The in-service planner only uses ccw.
enum class Elbow : std::uint8_t { ccw = 0, cw = 1 };
std::string_view to_string(Elbow e) noexcept;

struct IkSolutions {
  std::array<Pose, 2> pose{};   // indexed by Elbow; angles brought into the limits where possible
  std::array<bool, 2> ok{};     // that elbow's angles lie within the robot's limits
  PlanErrc reason{};            // why neither elbow works (too_close, too_far, outside_hard_stops)

  [[nodiscard]] bool any() const noexcept { return ok[0] || ok[1]; }
  [[nodiscard]] std::optional<Pose> get(Elbow e) const noexcept {
    const auto i = static_cast<std::size_t>(e);
    return ok[i] ? std::optional<Pose>(pose[i]) : std::nullopt;
  }
};

class Positioner {
 public:
  Positioner() = default;
  Positioner(const RobotSpec& spec, const ArmDesign& design);

  [[nodiscard]] std::int32_t id() const noexcept { return id_; }
  [[nodiscard]] Vec2 centre() const noexcept { return centre_; }
  [[nodiscard]] double buffer_mm() const noexcept { return buffer_; }
  [[nodiscard]] const AngleLimits& limits() const noexcept { return limits_; }
  // This robot's arms: the design's with its calibration's length corrections.
  [[nodiscard]] const ArmLengths& arms() const noexcept { return arms_; }
  [[nodiscard]] double alpha_length_mm() const noexcept { return arms_.alpha_length_mm; }
  [[nodiscard]] double collision_length_mm() const noexcept { return arms_.beta_collision_mm; }
  // Farthest the collision segment gets from the centre (alpha arm + collision segment).
  [[nodiscard]] double reach_mm() const noexcept { return arms_.alpha_length_mm + arms_.beta_collision_mm; }
  [[nodiscard]] std::size_t fibre_count() const noexcept { return fibres_.size(); }

  [[nodiscard]] Vec2 beta_axis(Pose p) const noexcept;
  [[nodiscard]] Segment collision_segment(Pose p) const noexcept;
  // The end of the beta arm (the figure the spec's safe-zone section uses).
  [[nodiscard]] Vec2 tip(Pose p) const noexcept;
  // Position of fibre `fibre` (index into the design's list; must be < fibre_count()).
  [[nodiscard]] Vec2 fibre(Pose p, std::size_t fibre) const noexcept;

  // The annulus fibre `fibre` can reach, as distances from the centre.
  [[nodiscard]] double min_reach_mm(std::size_t fibre) const noexcept;
  [[nodiscard]] double max_reach_mm(std::size_t fibre) const noexcept;

  // Both elbows that put fibre `fibre` on `target` (focal-plane coordinates).
  [[nodiscard]] IkSolutions inverse(Vec2 target, std::size_t fibre) const noexcept;
  // The same with one chosen elbow, or the error saying why not (with context).
  [[nodiscard]] Result<Pose> inverse(Vec2 target, std::size_t fibre, Elbow elbow) const;

  // True when the pose lies within the robot's angle limits.
  [[nodiscard]] bool within_limits(Pose p) const noexcept;

 private:
  struct FibrePolar {
    double radius = 0;     // from the beta axis
    double angle_rad = 0;  // from the beta arm's direction
    Vec2 offset;           // corrected offset in the beta-arm frame
  };

  std::int32_t id_ = 0;
  Vec2 centre_;
  double buffer_ = 2.0;
  AngleLimits limits_;
  double alpha_zero_rad_ = 0;  // orientation + alpha offset
  double beta_zero_rad_ = 0;   // beta offset
  ArmLengths arms_;
  std::vector<FibrePolar> fibres_;
};

// `deg` moved by whole turns into [lo, hi] (the lowest such value), or nullopt when no turn fits.
std::optional<double> wrap_into(double deg, double lo, double hi) noexcept;

}  // namespace axon::fps::plan
