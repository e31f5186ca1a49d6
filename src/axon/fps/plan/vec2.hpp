// A plain 2D vector for the planner's hot paths (millimetres on the focal plane).
//
// Kept trivially copyable and free of Eigen so that the collision checker's inner loops stay
// simple; convert with to_eigen()/from_eigen() where matrix code is wanted.
#pragma once

#include <Eigen/Core>

#include <cmath>
#include <numbers>

namespace axon::fps::plan {

// Degrees to radians (multiply by kRad) and back (kDeg).
inline constexpr double kRad = std::numbers::pi / 180.0;
inline constexpr double kDeg = 180.0 / std::numbers::pi;

struct Vec2 {
  double x = 0;
  double y = 0;

  friend constexpr Vec2 operator+(Vec2 a, Vec2 b) noexcept { return {a.x + b.x, a.y + b.y}; }
  friend constexpr Vec2 operator-(Vec2 a, Vec2 b) noexcept { return {a.x - b.x, a.y - b.y}; }
  friend constexpr Vec2 operator*(double s, Vec2 a) noexcept { return {s * a.x, s * a.y}; }
  friend constexpr bool operator==(Vec2, Vec2) = default;
};

constexpr double dot(Vec2 a, Vec2 b) noexcept { return a.x * b.x + a.y * b.y; }
constexpr double cross(Vec2 a, Vec2 b) noexcept { return a.x * b.y - a.y * b.x; }
constexpr double norm2(Vec2 a) noexcept { return dot(a, a); }
// sqrt of the squares, not std::hypot: lengths here are millimetres (no overflow to guard against),
// and hypot cost the planner a third of its time.
inline double norm(Vec2 a) noexcept { return std::sqrt(a.x * a.x + a.y * a.y); }
// The unit vector at `rad` radians counter-clockwise from +x.
inline Vec2 unit(double rad) noexcept { return {std::cos(rad), std::sin(rad)}; }
// `v` rotated counter-clockwise by the angle whose cosine and sine are given.
constexpr Vec2 rotate(Vec2 v, double c, double s) noexcept { return {c * v.x - s * v.y, s * v.x + c * v.y}; }

inline Eigen::Vector2d to_eigen(Vec2 v) { return {v.x, v.y}; }
inline Vec2 from_eigen(const Eigen::Vector2d& v) { return {v.x(), v.y()}; }

}  // namespace axon::fps::plan
