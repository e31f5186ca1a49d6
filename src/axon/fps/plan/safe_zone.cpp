#include "axon/fps/plan/safe_zone.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace axon::fps::plan {
namespace {

constexpr double kZoneRad = std::numbers::pi / 180.0;
// A point target counts as reached by its pose when the fibre lands this close to it.
constexpr double kOnPointMm = 1e-4;

bool zone_skipped(const SafeZoneTargets& which, std::size_t i) { return i < which.skip.size() && which.skip[i]; }

// The reach check of a robot whose target is fibre `f`'s point: the annulus the fibre reaches,
// shrunk by the arms' length errors (the fibre sits on the beta arm and shares its length error).
void check_zone_reach(const Positioner& p, std::size_t f, Pose pose, const SafeZone& z, SafeZoneReport& out) {
  const double d = norm(p.fibre(pose, f) - p.centre());
  const double outer = p.max_reach_mm(f) + z.length_min_mm();
  if (d > outer) out.issues.push_back({p.id(), SafeZoneIssue::Kind::beyond_reach, d - outer, 0, {}});
  // The inner edge moves out when the longer arm is long and the shorter one short.
  const double r = p.max_reach_mm(f) - p.alpha_length_mm();
  const double grow = r >= p.alpha_length_mm() ? z.beta_length_max_mm - z.alpha_length_min_mm
                                               : z.alpha_length_max_mm - z.beta_length_min_mm;
  const double inner = p.min_reach_mm(f) + grow;
  if (d < inner) out.issues.push_back({p.id(), SafeZoneIssue::Kind::inside_reach, inner - d, 0, {}});
}

void check_zone_clearance(const CollisionModel& model, std::span<const Segment> segs, const std::vector<double>& radius,
                     const SafeZoneTargets& which, std::size_t i, SafeZoneReport& out) {
  for (const auto pi : model.pairs_of(i)) {
    const RobotPair& pair = model.robot_pairs()[pi];
    const std::size_t other = pair.a == i ? pair.b : pair.a;
    if (other < i && !zone_skipped(which, other)) continue;  // reported on the other robot
    const double need = radius[i] + radius[other];
    const double c = model.clearance(pair, segs);
    if (c < need)
      out.issues.push_back({model.robot(i).id(), SafeZoneIssue::Kind::robot_clearance, need - c, model.robot(other).id(), {}});
  }
  for (const auto oi : model.obstacle_pairs_of(i)) {
    const ObstaclePair& pair = model.obstacle_pairs()[oi];
    const double c = model.clearance(pair, segs);
    if (c < radius[i])
      out.issues.push_back({model.robot(i).id(), SafeZoneIssue::Kind::obstacle_clearance, radius[i] - c, 0,
                            model.obstacles()[pair.obstacle].name});
  }
}

}  // namespace

double SafeZone::radius_mm() const noexcept {
  return std::hypot(std::max(-length_min_mm(), length_max_mm()), lateral_mm());
}

SafeZone safe_zone(const ArmLengths& arms, const PositionerErrors& e) noexcept {
  SafeZone z;
  z.alpha_length_min_mm = e.alpha.length_min_mm();
  z.alpha_length_max_mm = e.alpha.length_max_mm();
  z.beta_length_min_mm = e.beta.length_min_mm();
  z.beta_length_max_mm = e.beta.length_max_mm();
  // The worst case takes the longest arms (11.1.2's l + l_err).
  z.alpha_lateral_mm = std::sin(e.alpha.angle_deg() * kZoneRad) * (arms.alpha_length_mm + z.alpha_length_max_mm) +
                       e.alpha.thermal_lateral_mm;
  z.beta_lateral_mm = std::sin((e.alpha.angle_deg() + e.beta.angle_deg()) * kZoneRad) * (arms.beta_tip_mm + z.beta_length_max_mm) +
                      e.beta.thermal_lateral_mm;
  return z;
}

std::string_view to_string(SafeZoneIssue::Kind k) noexcept {
  switch (k) {
    case SafeZoneIssue::Kind::beyond_reach: return "beyond_reach";
    case SafeZoneIssue::Kind::inside_reach: return "inside_reach";
    case SafeZoneIssue::Kind::robot_clearance: return "robot_clearance";
    case SafeZoneIssue::Kind::obstacle_clearance: return "obstacle_clearance";
  }
  return "?";
}

std::string SafeZoneIssue::to_string() const {
  switch (kind) {
    case Kind::beyond_reach:
      return fmt::format("robot {}: target {:.3f} mm beyond the reach every robot within tolerance has", robot, by_mm);
    case Kind::inside_reach:
      return fmt::format("robot {}: target {:.3f} mm inside the fold every robot within tolerance can reach", robot, by_mm);
    case Kind::robot_clearance:
      return fmt::format("robot {}: target {:.3f} mm too close to robot {}'s for both safe zones", robot, by_mm, other);
    case Kind::obstacle_clearance:
      return fmt::format("robot {}: target {:.3f} mm too close to {} for its safe zone", robot, by_mm, obstacle);
  }
  return {};
}

std::vector<std::int32_t> SafeZoneReport::robots() const {
  std::vector<std::int32_t> ids;
  for (const auto& i : issues) ids.push_back(i.robot);
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  return ids;
}

std::string SafeZoneReport::summary() const {
  std::string s;
  for (const auto& i : issues) s += i.to_string() + "\n";
  return s;
}

SafeZoneReport check_safe_zone(const CollisionModel& model, std::span<const Pose> targets, const SafeZoneTargets& which,
                               const SafeZoneOptions& options) {
  SafeZoneReport out;
  const std::size_t n = std::min(model.size(), targets.size());
  std::vector<double> radius(model.size());
  for (std::size_t i = 0; i < model.size(); ++i) radius[i] = safe_zone(model.robot(i).arms(), options.errors).radius_mm();
  std::vector<Segment> segs(model.size());
  if (options.clearance && n == model.size()) model.segments(targets, segs);
  for (std::size_t i = 0; i < n; ++i) {
    if (zone_skipped(which, i)) continue;
    const Positioner& p = model.robot(i);
    if (options.reach && i < which.point_fibre.size() && which.point_fibre[i] && *which.point_fibre[i] < p.fibre_count())
      check_zone_reach(p, *which.point_fibre[i], targets[i], safe_zone(p.arms(), options.errors), out);
    if (options.clearance && n == model.size()) check_zone_clearance(model, segs, radius, which, i, out);
  }
  return out;
}

std::vector<std::optional<std::size_t>> point_fibres(const CollisionModel& model, std::span<const Target> targets,
                                                     std::span<const Pose> poses) {
  std::vector<std::optional<std::size_t>> out(model.size());
  for (const auto& t : targets) {
    if (!t.position) continue;
    const auto i = model.index_of(t.robot);
    const auto f = model.design().fibre_index(t.fibre);
    if (!i || !f || *i >= poses.size()) continue;
    if (norm(model.robot(*i).fibre(poses[*i], *f) - *t.position) <= kOnPointMm) out[*i] = f;
  }
  return out;
}

}  // namespace axon::fps::plan
