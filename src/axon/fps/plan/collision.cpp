#include "axon/fps/plan/collision.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

namespace axon::fps::plan {

Result<CollisionModel> CollisionModel::build(std::span<const RobotSpec> robots, const ArmDesign& design,
                                             std::span<const FiducialSpec> fiducials,
                                             std::span<const ObstacleSpec> obstacles) {
  CollisionModel m;
  m.design_ = design;
  std::unordered_map<std::int32_t, std::size_t> seen;
  m.robots_.reserve(robots.size());
  for (const auto& r : robots) {
    if (!seen.emplace(r.id, m.robots_.size()).second)
      return make_error(PlanErrc::unknown_robot, fmt::format("duplicate robot id {} in the layout", r.id));
    m.robots_.emplace_back(r, design);
  }
  for (const auto& f : fiducials)
    m.obstacles_.push_back({Obstacle::Kind::fiducial, f.id, fmt::format("fiducial {}", f.id), {f.position, f.position},
                            f.buffer_mm});
  for (const auto& o : obstacles) m.obstacles_.push_back({Obstacle::Kind::other, 0, o.name, o.shape, o.buffer_mm});

  const std::size_t n = m.robots_.size();
  // Neighbour pairs: O(n^2) over centres is a few hundred thousand distances for 500 robots, done
  // once per layout.
  std::vector<std::vector<std::uint32_t>> nb(n), nbp(n), obp(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Positioner& a = m.robots_[i];
    for (std::size_t j = i + 1; j < n; ++j) {
      const Positioner& b = m.robots_[j];
      const double limit = a.buffer_mm() + b.buffer_mm();
      const double reach = a.reach_mm() + b.reach_mm() + limit;
      if (norm2(a.centre() - b.centre()) < reach * reach) {
        const auto p = static_cast<std::uint32_t>(m.robot_pairs_.size());
        m.robot_pairs_.push_back({static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j), limit});
        nb[i].push_back(static_cast<std::uint32_t>(j));
        nb[j].push_back(static_cast<std::uint32_t>(i));
        nbp[i].push_back(p);
        nbp[j].push_back(p);
      }
    }
    for (std::size_t k = 0; k < m.obstacles_.size(); ++k) {
      const Obstacle& o = m.obstacles_[k];
      const double limit = a.buffer_mm() + o.buffer_mm;
      const double reach = a.reach_mm() + limit;
      if (point_segment_distance2(a.centre(), o.shape) < reach * reach) {
        obp[i].push_back(static_cast<std::uint32_t>(m.obstacle_pairs_.size()));
        m.obstacle_pairs_.push_back({static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(k), limit});
      }
    }
  }
  m.nb_offset_.assign(1, 0);
  m.ob_offset_.assign(1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    m.nb_index_.insert(m.nb_index_.end(), nb[i].begin(), nb[i].end());
    m.nb_pair_.insert(m.nb_pair_.end(), nbp[i].begin(), nbp[i].end());
    m.nb_offset_.push_back(static_cast<std::uint32_t>(m.nb_index_.size()));
    m.ob_pair_.insert(m.ob_pair_.end(), obp[i].begin(), obp[i].end());
    m.ob_offset_.push_back(static_cast<std::uint32_t>(m.ob_pair_.size()));
  }
  return m;
}

std::optional<std::size_t> CollisionModel::index_of(std::int32_t id) const noexcept {
  for (std::size_t i = 0; i < robots_.size(); ++i)
    if (robots_[i].id() == id) return i;
  return std::nullopt;
}

std::span<const std::uint32_t> CollisionModel::neighbours(std::size_t i) const noexcept {
  return std::span<const std::uint32_t>(nb_index_).subspan(nb_offset_[i], nb_offset_[i + 1] - nb_offset_[i]);
}

std::span<const std::uint32_t> CollisionModel::pairs_of(std::size_t i) const noexcept {
  return std::span<const std::uint32_t>(nb_pair_).subspan(nb_offset_[i], nb_offset_[i + 1] - nb_offset_[i]);
}

std::span<const std::uint32_t> CollisionModel::obstacle_pairs_of(std::size_t i) const noexcept {
  return std::span<const std::uint32_t>(ob_pair_).subspan(ob_offset_[i], ob_offset_[i + 1] - ob_offset_[i]);
}

void CollisionModel::segments(std::span<const Pose> poses, std::span<Segment> out) const noexcept {
  for (std::size_t i = 0; i < robots_.size(); ++i) out[i] = robots_[i].collision_segment(poses[i]);
}

double CollisionModel::clearance(const RobotPair& p, std::span<const Segment> segs) const noexcept {
  return segment_distance(segs[p.a], segs[p.b]) - p.limit_mm;
}

double CollisionModel::clearance(const ObstaclePair& p, std::span<const Segment> segs) const noexcept {
  return segment_distance(segs[p.robot], obstacles_[p.obstacle].shape) - p.limit_mm;
}

double CollisionModel::robot_clearance(std::size_t i, const Segment& seg, std::span<const Segment> segs) const noexcept {
  double best = std::numeric_limits<double>::infinity();
  const double buf = robots_[i].buffer_mm();
  for (const std::uint32_t j : neighbours(i))
    best = std::min(best, segment_distance(seg, segs[j]) - buf - robots_[j].buffer_mm());
  for (const std::uint32_t k : obstacle_pairs_of(i)) {
    const ObstaclePair& p = obstacle_pairs_[k];
    best = std::min(best, segment_distance(seg, obstacles_[p.obstacle].shape) - p.limit_mm);
  }
  return best;
}

double CollisionModel::find_contacts(std::span<const Segment> segs, std::vector<Contact>& out) const {
  out.clear();
  double best = std::numeric_limits<double>::infinity();
  for (const auto& p : robot_pairs_) {
    const double c = clearance(p, segs);
    best = std::min(best, c);
    if (c < 0) out.push_back({Contact::Kind::robot, p.a, p.b, c});
  }
  for (const auto& p : obstacle_pairs_) {
    const double c = clearance(p, segs);
    best = std::min(best, c);
    if (c < 0) out.push_back({Contact::Kind::obstacle, p.robot, p.obstacle, c});
  }
  return best;
}

}  // namespace axon::fps::plan
