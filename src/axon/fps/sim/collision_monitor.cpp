#include "axon/fps/sim/collision_monitor.hpp"

#include <cmath>

namespace axon::fps::sim {

CollisionMonitor::CollisionMonitor(std::vector<RobotGeometry> robots, bool neighbours) : robots_(std::move(robots)) {
  if (!neighbours) return;
  for (std::size_t i = 0; i < robots_.size(); ++i) {
    for (std::size_t j = i + 1; j < robots_.size(); ++j) {
      const double d = std::hypot(robots_[i].base.x - robots_[j].base.x, robots_[i].base.y - robots_[j].base.y);
      if (d < robots_[i].reach_mm() + robots_[j].reach_mm()) {
        pairs_.push_back({i, j, robots_[i].buffer_mm + robots_[j].buffer_mm});
      }
    }
  }
}

void CollisionMonitor::set_obstacles(std::vector<Obstacle> obstacles) { obstacles_ = std::move(obstacles); }

std::vector<CollisionMonitor::Contact> CollisionMonitor::update(std::span<const Pose> poses) {
  std::vector<Contact> out;
  if (poses.size() != robots_.size()) return out;
  const auto segments_at = [&](std::span<const Pose> p, std::vector<Segment>& into) {
    into.resize(p.size());
    for (std::size_t i = 0; i < p.size(); ++i) into[i] = beta_segment(robots_[i], p[i].alpha_deg, p[i].beta_deg);
  };
  if (previous_.size() != poses.size()) {
    previous_.assign(poses.begin(), poses.end());
    segments_at(previous_, previous_segments_);
    return out;
  }
  std::vector<bool> moved(poses.size());
  bool any = false;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    moved[i] = !(poses[i] == previous_[i]);
    any = any || moved[i];
  }
  if (!any) return out;
  // Each robot's segment once per update; unmoved robots keep the previous one.
  segments_.resize(poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    segments_[i] = moved[i] ? beta_segment(robots_[i], poses[i].alpha_deg, poses[i].beta_deg) : previous_segments_[i];
  }
  const auto report = [&](std::size_t i, std::optional<std::size_t> other, std::size_t obstacle, double d) {
    out.push_back(Contact{i, other, obstacle, d, poses[i].alpha_deg != previous_[i].alpha_deg,
                          poses[i].beta_deg != previous_[i].beta_deg});
  };
  // Touching now, and either not touching before or closer than before.
  const auto hit = [](double now, double before, double limit) {
    return now < limit && (before >= limit || now < before - 1e-9);
  };
  for (const Pair& p : pairs_) {
    if (!moved[p.a] && !moved[p.b]) continue;
    if (surely_apart(segments_[p.a], segments_[p.b], p.limit)) continue;
    const double now = segment_distance(segments_[p.a], segments_[p.b]);
    if (now >= p.limit) continue;
    const double before = segment_distance(previous_segments_[p.a], previous_segments_[p.b]);
    if (!hit(now, before, p.limit)) continue;
    if (moved[p.a]) report(p.a, p.b, 0, now);
    if (moved[p.b]) report(p.b, p.a, 0, now);
  }
  for (std::size_t i = 0; i < poses.size(); ++i) {
    if (!moved[i]) continue;
    for (std::size_t k = 0; k < obstacles_.size(); ++k) {
      const double limit = robots_[i].buffer_mm + obstacles_[k].radius_mm;
      if (surely_apart(segments_[i], obstacles_[k].shape, limit)) continue;
      const double now = segment_distance(segments_[i], obstacles_[k].shape);
      if (now >= limit) continue;
      const double before = segment_distance(previous_segments_[i], obstacles_[k].shape);
      if (hit(now, before, limit)) report(i, std::nullopt, k, now);
    }
  }
  previous_.assign(poses.begin(), poses.end());
  previous_segments_.swap(segments_);
  return out;
}

}  // namespace axon::fps::sim
