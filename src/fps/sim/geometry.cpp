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
  return std::sqrt((p.x - q.x) * (p.x - q.x) + (p.y - q.y) * (p.y - q.y));
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

bool surely_apart(const Segment& s, const Segment& t, double limit) noexcept {
  // Each segment lies within half its length of its midpoint.
  const double hs = 0.5 * std::sqrt(dot(sub(s.b, s.a), sub(s.b, s.a)));
  const double ht = 0.5 * std::sqrt(dot(sub(t.b, t.a), sub(t.b, t.a)));
  const Vec2 d{(s.a.x + s.b.x - t.a.x - t.b.x) * 0.5, (s.a.y + s.b.y - t.a.y - t.b.y) * 0.5};
  const double reach = hs + ht + limit;
  return dot(d, d) >= reach * reach;
}

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
