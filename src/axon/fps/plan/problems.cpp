#include "axon/fps/plan/problems.hpp"

#include "axon/fps/plan/safe_zone.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <numeric>
#include <random>

namespace axon::fps::plan {

std::vector<Pose> folded_poses(const CollisionModel& model, Pose fold) { return std::vector<Pose>(model.size(), fold); }

std::vector<Pose> random_poses(const CollisionModel& model, std::uint64_t seed, const RandomPoseOptions& o) {
  const std::size_t n = model.size();
  std::vector<Pose> poses(n, o.fallback);
  std::vector<Segment> segs(n);
  model.segments(poses, segs);
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::mt19937_64 rng(seed);
  std::shuffle(order.begin(), order.end(), rng);
  std::uniform_real_distribution<double> alpha(o.alpha_min_deg, o.alpha_max_deg), beta(o.beta_min_deg, o.beta_max_deg);
  for (const std::size_t i : order) {
    const Positioner& r = model.robot(i);
    for (int k = 0; k < o.attempts; ++k) {
      const Pose p{alpha(rng), beta(rng)};
      if (!r.within_limits(p)) continue;
      const Segment s = r.collision_segment(p);
      if (model.robot_clearance(i, s, segs) >= o.min_clearance_mm) {
        poses[i] = p;
        segs[i] = s;
        break;
      }
    }
  }
  return poses;
}

Result<ProblemPoses> poses_from_file(const CollisionModel& model, const std::string& path, TargetPolicy policy) {
  AXON_TRY(targets, load_targets(path));
  auto usable = usable_targets(model, targets, policy);
  if (!usable) return Error(usable.error().code, fmt::format("'{}':\n{}", path, usable.error().detail));
  const TargetValidation& v = usable.value();
  ProblemPoses out;
  out.poses = v.poses();
  out.notes = v.summary();
  for (const RobotOutcome& r : v.robots)
    if (r.status == RobotOutcome::Status::parked) out.parked.push_back(r);
  out.point_fibre = point_fibres(model, targets, out.poses);
  return out;
}

Result<ProblemPoses> poses_by_name(const CollisionModel& model, const std::string& name, std::uint64_t seed,
                                   TargetPolicy policy) {
  if (name != "folded" && name != "random") return poses_from_file(model, name, policy);
  ProblemPoses out;
  out.poses = name == "folded" ? folded_poses(model) : random_poses(model, seed);
  out.point_fibre.assign(model.size(), std::nullopt);
  return out;
}

}  // namespace axon::fps::plan
