// Exact distances between points and segments in the plane (the collision primitives).
//
// Two segments either cross properly (distance 0) or their closest pair of points includes an
// endpoint of one of them, so the distance is the smallest of four point-to-segment distances.
// The crossing test uses only the signs of cross products, so parallel, collinear, touching and
// zero-length segments need no special case: they never count as a proper crossing and the
// endpoint distances give the right answer (0 where they touch or overlap).
#pragma once

#include "axon/fps/plan/vec2.hpp"

namespace axon::fps::plan {

struct Segment {
  Vec2 a;
  Vec2 b;  // equal to a for a point
};

// Squared distance from p to the segment s.
double point_segment_distance2(Vec2 p, const Segment& s) noexcept;
inline double point_segment_distance(Vec2 p, const Segment& s) noexcept {
  return std::sqrt(point_segment_distance2(p, s));
}

// True when the segments cross at a single interior point of both (not at an endpoint).
bool segments_cross_properly(const Segment& s, const Segment& t) noexcept;

// Squared shortest distance between two segments (either may be a point).
double segment_distance2(const Segment& s, const Segment& t) noexcept;
inline double segment_distance(const Segment& s, const Segment& t) noexcept {
  return std::sqrt(segment_distance2(s, t));
}

}  // namespace axon::fps::plan
