#include "axon/fps/plan/trajectory.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <limits>
#include <utility>
#include <cmath>

namespace axon::fps::plan {

Result<void> validate(std::span<const TimedAngle> points, std::string_view what) {
  if (points.empty()) return make_error(PlanErrc::bad_trajectory, fmt::format("{}: no points", what));
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!std::isfinite(points[i].t_s) || !std::isfinite(points[i].deg))
      return make_error(PlanErrc::bad_trajectory, fmt::format("{}: point {} is not finite", what, i));
    if (i > 0 && !(points[i].t_s > points[i - 1].t_s))
      return make_error(PlanErrc::bad_trajectory,
                        fmt::format("{}: point {} at {} s does not come after {} s", what, i, points[i].t_s,
                                    points[i - 1].t_s));
  }
  return ok();
}

Result<void> validate(const RobotTrajectory& t) {
  AXON_TRY(validate(t.alpha, "alpha"));
  return validate(t.beta, "beta");
}

namespace {
double lerp(const TimedAngle& a, const TimedAngle& b, double t) noexcept {
  const double f = (t - a.t_s) / (b.t_s - a.t_s);
  return a.deg + f * (b.deg - a.deg);
}
}  // namespace

double angle_at(std::span<const TimedAngle> points, double t_s) noexcept {
  if (points.empty()) return 0;
  if (t_s <= points.front().t_s) return points.front().deg;
  if (t_s >= points.back().t_s) return points.back().deg;
  const auto it = std::upper_bound(points.begin(), points.end(), t_s,
                                   [](double t, const TimedAngle& p) { return t < p.t_s; });
  return lerp(*(it - 1), *it, t_s);
}

double end_time(const RobotTrajectory& t) noexcept {
  return std::max(t.alpha.empty() ? 0.0 : t.alpha.back().t_s, t.beta.empty() ? 0.0 : t.beta.back().t_s);
}

RobotTrajectory window(const RobotTrajectory& t, double t0_s, double t1_s) {
  RobotTrajectory out;
  for (auto [from, to] : {std::pair{&t.alpha, &out.alpha}, std::pair{&t.beta, &out.beta}}) {
    to->push_back({0.0, angle_at(*from, t0_s)});
    for (const TimedAngle& p : *from)
      if (p.t_s > t0_s && p.t_s < t1_s) to->push_back({p.t_s - t0_s, p.deg});
    to->push_back({t1_s - t0_s, angle_at(*from, t1_s)});
  }
  return out;
}

double max_speed(std::span<const TimedAngle> points) noexcept {
  double v = 0;
  for (std::size_t i = 1; i < points.size(); ++i)
    v = std::max(v, std::abs(points[i].deg - points[i - 1].deg) / (points[i].t_s - points[i - 1].t_s));
  return v;
}

double AngleCursor::at(double t_s) noexcept {
  if (points_.empty()) return 0;
  if (t_s < last_t_) i_ = 0;
  last_t_ = t_s;
  if (t_s <= points_.front().t_s) return points_.front().deg;
  if (t_s >= points_.back().t_s) return points_.back().deg;
  while (i_ + 1 < points_.size() && points_[i_ + 1].t_s <= t_s) ++i_;
  return lerp(points_[i_], points_[i_ + 1], t_s);
}

double AngleCursor::speed() const noexcept {
  if (points_.empty() || last_t_ < points_.front().t_s || last_t_ >= points_.back().t_s) return 0;
  const TimedAngle& a = points_[i_];
  const TimedAngle& b = points_[i_ + 1];
  return std::abs(b.deg - a.deg) / (b.t_s - a.t_s);
}

double AngleCursor::next_point() const noexcept {
  if (points_.empty() || last_t_ >= points_.back().t_s) return std::numeric_limits<double>::infinity();
  if (last_t_ < points_.front().t_s) return points_.front().t_s;
  return points_[i_ + 1].t_s;
}

}  // namespace axon::fps::plan
