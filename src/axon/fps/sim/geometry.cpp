#include "axon/fps/sim/geometry.hpp"

#include <cmath>
#include <numbers>

namespace axon::fps::sim {

bool surely_apart(const Segment& s, const Segment& t, double limit) noexcept {
  // Each segment lies within half its length of its midpoint.
  const double hs = 0.5 * plan::norm(s.b - s.a);
  const double ht = 0.5 * plan::norm(t.b - t.a);
  const Vec2 d{(s.a.x + s.b.x - t.a.x - t.b.x) * 0.5, (s.a.y + s.b.y - t.a.y - t.b.y) * 0.5};
  const double reach = hs + ht + limit;
  return plan::norm2(d) >= reach * reach;
}

Segment beta_segment(const RobotGeometry& g, double alpha_deg, double beta_deg) noexcept {
  constexpr double rad = std::numbers::pi / 180.0;
  const double a = (g.orientation_deg + alpha_deg) * rad;
  const double b = a + beta_deg * rad;
  const Vec2 axis{g.base.x + g.alpha_arm_mm * std::cos(a), g.base.y + g.alpha_arm_mm * std::sin(a)};
  return {axis, {axis.x + g.beta_arm_mm * std::cos(b), axis.y + g.beta_arm_mm * std::sin(b)}};
}

}  // namespace axon::fps::sim
