// Small collision models the planner tests build by hand, the clearance of a static pose, and an
// arm's points in a form tests compare exactly.
#pragma once

#include "axon/fps/plan/collision.hpp"
#include "axon/fps/plan/trajectory.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

namespace axon::fps::plan::test {

// The model of `robots` (and fiducials, obstacles) with the default arm design; a model that
// cannot be built fails the test.
inline CollisionModel build(std::vector<RobotSpec> robots, std::vector<FiducialSpec> fids = {},
                            std::vector<ObstacleSpec> obs = {}) {
  auto m = CollisionModel::build(robots, ArmDesign{}, fids, obs);
  EXPECT_TRUE(m) << m.error().message();
  return std::move(m).value();
}

// A robot at (x, y) mm with the default arms and a 2 mm buffer.
inline RobotSpec robot_at(std::int32_t id, double x, double y) { return RobotSpec{id, {x, y}, {}, {}, 2.0}; }

// A hex patch: `rings` rings around the origin, pitch 22.4 mm, ids from 1 row by row.
inline std::vector<RobotSpec> hex_patch(int rings) {
  std::vector<RobotSpec> out;
  const double pitch = 22.4, row = pitch * std::sqrt(3.0) / 2;
  std::int32_t id = 1;
  for (int j = -rings; j <= rings; ++j)
    for (int i = -rings; i <= rings; ++i)
      if (std::abs(i + j) <= rings) out.push_back(robot_at(id++, (i + 0.5 * j) * pitch, j * row));
  return out;
}

// Two robots one pitch (22.4 mm) apart on the x axis, 2 mm buffers.
inline CollisionModel two_robots() {
  return build({RobotSpec{1, {0, 0}, {}, {}, 2.0}, RobotSpec{2, {22.4, 0}, {}, {}, 2.0}});
}

// The smallest clearance over every pair when the robots stand at `poses` (negative: contact).
inline double static_clearance(const CollisionModel& m, const std::vector<Pose>& poses) {
  std::vector<Segment> s(m.size());
  m.segments(poses, s);
  std::vector<Contact> c;
  return m.find_contacts(s, c);
}

// An arm's points as (time, angle) pairs, for EXPECT_EQ on whole paths.
inline std::vector<std::pair<double, double>> pts(const std::vector<TimedAngle>& arm) {
  std::vector<std::pair<double, double>> out;
  for (const TimedAngle& p : arm) out.emplace_back(p.t_s, p.deg);
  return out;
}

}  // namespace axon::fps::plan::test
