#include "axon/fps/sim/collision_monitor.hpp"

namespace axon::fps::sim {

CollisionMonitor::CollisionMonitor(plan::CollisionModel model, bool neighbours)
    : model_(std::move(model)), neighbours_(neighbours) {}

std::vector<CollisionMonitor::Contact> CollisionMonitor::update(std::span<const Pose> poses) {
  std::vector<Contact> out;
  const std::size_t n = model_.size();
  if (poses.size() != n) return out;
  if (previous_.size() != n) {
    previous_.assign(poses.begin(), poses.end());
    previous_segments_.resize(n);
    model_.segments(previous_, previous_segments_);
    return out;
  }
  std::vector<bool> moved(n);
  bool any = false;
  for (std::size_t i = 0; i < n; ++i) {
    moved[i] = !(poses[i] == previous_[i]);
    any = any || moved[i];
  }
  if (!any) return out;
  // Each robot's segment once per update; unmoved robots keep the previous one.
  segments_.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    segments_[i] = moved[i] ? model_.robot(i).collision_segment(poses[i]) : previous_segments_[i];
  const auto report = [&](std::size_t i, std::optional<std::size_t> other, std::size_t obstacle, double c) {
    out.push_back(Contact{i, other, obstacle, c, poses[i].alpha_deg != previous_[i].alpha_deg,
                          poses[i].beta_deg != previous_[i].beta_deg});
  };
  // In contact now, and either not before or deeper than before.
  const auto hit = [](double now, double before) { return now < 0 && (before >= 0 || now < before - 1e-9); };
  if (neighbours_) {
    for (const plan::RobotPair& p : model_.robot_pairs()) {
      if (!moved[p.a] && !moved[p.b]) continue;
      const double now = model_.clearance(p, segments_);
      if (now >= 0 || !hit(now, model_.clearance(p, previous_segments_))) continue;
      if (moved[p.a]) report(p.a, p.b, 0, now);
      if (moved[p.b]) report(p.b, p.a, 0, now);
    }
  }
  for (const plan::ObstaclePair& p : model_.obstacle_pairs()) {
    if (!moved[p.robot]) continue;
    const double now = model_.clearance(p, segments_);
    if (now < 0 && hit(now, model_.clearance(p, previous_segments_))) report(p.robot, std::nullopt, p.obstacle, now);
  }
  previous_.assign(poses.begin(), poses.end());
  previous_segments_.swap(segments_);
  return out;
}

}  // namespace axon::fps::sim
