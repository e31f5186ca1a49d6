#include "axon/fps/plan/distance.hpp"

#include <algorithm>

namespace axon::fps::plan {

double point_segment_distance2(Vec2 p, const Segment& s) noexcept {
  const Vec2 d = s.b - s.a;
  const Vec2 w = p - s.a;
  const double len2 = norm2(d);
  if (len2 <= 0) return norm2(w);
  const double f = std::clamp(dot(w, d) / len2, 0.0, 1.0);
  return norm2(w - f * d);
}

bool segments_cross_properly(const Segment& s, const Segment& t) noexcept {
  const Vec2 r = s.b - s.a;
  const Vec2 q = t.b - t.a;
  const double o1 = cross(r, t.a - s.a);
  const double o2 = cross(r, t.b - s.a);
  const double o3 = cross(q, s.a - t.a);
  const double o4 = cross(q, s.b - t.a);
  return ((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0));
}

double segment_distance2(const Segment& s, const Segment& t) noexcept {
  if (segments_cross_properly(s, t)) return 0.0;
  return std::min({point_segment_distance2(s.a, t), point_segment_distance2(s.b, t),
                   point_segment_distance2(t.a, s), point_segment_distance2(t.b, s)});
}

}  // namespace axon::fps::plan
