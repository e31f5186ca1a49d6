#include "axon/fps/host/trajectory_speed.hpp"

#include <algorithm>
#include <cmath>

namespace axon::fps::host {

namespace {

// The highest speed ratio over one arm's segments, from `start` at time 0.
double worst_ratio(const std::vector<protocol::TrajectoryPoint>& points, double start, double limit_deg_s) {
  double worst = 0;
  double prev_deg = start;
  double prev_s = 0;
  for (const auto& p : points) {
    const double deg = p.position.degrees();
    const double s = p.time.seconds();
    const double dt = s - prev_s;
    const double speed = dt > 0 ? std::abs(deg - prev_deg) / dt : (deg == prev_deg ? 0 : INFINITY);
    worst = std::max(worst, limit_deg_s > 0 ? speed / limit_deg_s : INFINITY);
    prev_deg = deg;
    prev_s = s;
  }
  return worst;
}

}  // namespace

SpeedCheck check_speed(const protocol::Trajectory& trajectory, ArmAngles start, const plan::SpeedLimits& limits) {
  SpeedCheck c;
  c.duration_s = trajectory.duration().seconds();
  c.worst_ratio = std::max(worst_ratio(trajectory.alpha(), start.alpha, limits.alpha_deg_s),
                           worst_ratio(trajectory.beta(), start.beta, limits.beta_deg_s));
  return c;
}

std::optional<SlowestRobot> slowest_robot(const std::map<std::uint16_t, protocol::Trajectory>& trajectories,
                                          const std::map<std::uint16_t, ArmAngles>& starts,
                                          const plan::SpeedLimits& limits) {
  std::optional<SlowestRobot> out;
  std::size_t too_fast = 0;
  for (const auto& [id, t] : trajectories) {
    auto it = starts.find(id);
    if (it == starts.end()) continue;
    const auto c = check_speed(t, it->second, limits);
    too_fast += c.feasible() ? 0 : 1;
    if (!out || c.shortest_duration_s() > out->needed_s) out = SlowestRobot{id, c.shortest_duration_s(), 0};
  }
  if (out) out->too_fast = too_fast;
  return out;
}

double feasible_duration_s(double shortest_s) noexcept {
  return std::ceil(shortest_s * 1.005 * 10.0 - 1e-9) / 10.0;
}

}  // namespace axon::fps::host
