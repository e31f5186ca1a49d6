#include "fps/sim/geometry.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace axon::fps::sim {

namespace {

Vec2 sub(Vec2 a, Vec2 b) noexcept { return {a.x - b.x, a.y - b.y}; }
double dot(Vec2 a, Vec2 b) noexcept { return a.x * b.x + a.y * b.y; }

double point_segment(Vec2 p, const Segment& s) noexcept {
  const Vec2 d = sub(s.b, s.a);
  const double len2 = dot(d, d);
  const double f = len2 > 0 ? std::clamp(dot(sub(p, s.a), d) / len2, 0.0, 1.0) : 0.0;
  const Vec2 q{s.a.x + d.x * f, s.a.y + d.y * f};
  return std::hypot(p.x - q.x, p.y - q.y);
}

double cross(Vec2 a, Vec2 b) noexcept { return a.x * b.y - a.y * b.x; }

bool segments_cross(const Segment& s, const Segment& t) noexcept {
  const Vec2 r = sub(s.b, s.a);
  const Vec2 q = sub(t.b, t.a);
  const double den = cross(r, q);
  if (den == 0) return false;  // parallel: the endpoint distances below cover it
  const Vec2 w = sub(t.a, s.a);
  const double u = cross(w, q) / den;
  const double v = cross(w, r) / den;
  return u >= 0 && u <= 1 && v >= 0 && v <= 1;
}

}  // namespace

double segment_distance(const Segment& s, const Segment& t) noexcept {
  if (segments_cross(s, t)) return 0.0;
  return std::min({point_segment(s.a, t), point_segment(s.b, t), point_segment(t.a, s), point_segment(t.b, s)});
}

Segment beta_segment(const RobotGeometry& g, double alpha_deg, double beta_deg) noexcept {
  constexpr double rad = std::numbers::pi / 180.0;
  const double a = (g.orientation_deg + alpha_deg) * rad;
  const double b = a + beta_deg * rad;
  const Vec2 axis{g.base.x + g.alpha_arm_mm * std::cos(a), g.base.y + g.alpha_arm_mm * std::sin(a)};
  return {axis, {axis.x + g.beta_arm_mm * std::cos(b), axis.y + g.beta_arm_mm * std::sin(b)}};
}

}  // namespace axon::fps::sim
