#include "axon/fps/sim/arm_path.hpp"

#include <algorithm>
#include <cmath>

namespace axon::fps::sim {

ArmPath& ArmPath::line_to(double deg, double deg_per_s) {
  if (corners_.empty()) corners_.push_back({SimTime{}, deg});
  const double distance = std::abs(deg - corners_.back().deg);
  const SimDuration d = deg_per_s > 0 ? seconds(distance / deg_per_s) : SimDuration::zero();
  return point(end() + d, deg);
}

ArmPath& ArmPath::hold(SimDuration d) {
  if (corners_.empty()) corners_.push_back({SimTime{}, 0.0});
  return point(end() + d, corners_.back().deg);
}

ArmPath& ArmPath::point(SimTime t, double deg) {
  if (!corners_.empty() && t < corners_.back().t) t = corners_.back().t;
  corners_.push_back({t, deg});
  return *this;
}

double ArmPath::at(SimTime t) const noexcept {
  if (corners_.empty()) return 0.0;
  if (t <= corners_.front().t) return corners_.front().deg;
  if (t >= corners_.back().t) return corners_.back().deg;
  const auto it = std::upper_bound(corners_.begin(), corners_.end(), t,
                                   [](SimTime v, const Corner& c) { return v < c.t; });
  const Corner& b = *it;
  const Corner& a = *(it - 1);
  const double f = static_cast<double>((t - a.t).count()) / static_cast<double>((b.t - a.t).count());
  return a.deg + (b.deg - a.deg) * f;
}

double ArmPath::speed_at(SimTime t) const noexcept {
  if (corners_.size() < 2 || t < corners_.front().t || t >= corners_.back().t) return 0.0;
  const auto it = std::upper_bound(corners_.begin(), corners_.end(), t,
                                   [](SimTime v, const Corner& c) { return v < c.t; });
  const Corner& b = *it;
  const Corner& a = *(it - 1);
  return (b.deg - a.deg) / to_seconds(b.t - a.t);
}

ArmPath ArmPath::shifted(double delta) const {
  ArmPath p = *this;
  for (auto& c : p.corners_) c.deg += delta;
  return p;
}

std::optional<SimTime> ArmPath::first_outside(double lo, double hi) const noexcept {
  if (corners_.empty()) return std::nullopt;
  const auto outside = [&](double d) { return d < lo || d > hi; };
  if (outside(corners_.front().deg)) return corners_.front().t;
  for (std::size_t i = 1; i < corners_.size(); ++i) {
    const Corner& a = corners_[i - 1];
    const Corner& b = corners_[i];
    if (!outside(b.deg)) continue;
    const double limit = b.deg < lo ? lo : hi;
    const double f = (limit - a.deg) / (b.deg - a.deg);  // a is inside, b outside: never 0/0
    return a.t + SimDuration(static_cast<std::int64_t>(std::floor(static_cast<double>((b.t - a.t).count()) * f)));
  }
  return std::nullopt;
}

ArmPath ArmPath::clamped(double lo, double hi, bool slip) const {
  ArmPath out;
  if (corners_.empty()) return out;
  double lost = 0;  // command minus arm, grown by slipping
  const auto clamp = [&](double d) { return std::clamp(d, lo, hi); };
  double prev_cmd = corners_.front().deg;
  double prev_arm = clamp(prev_cmd);
  if (slip) lost = prev_cmd - prev_arm;
  out.corners_.push_back({corners_.front().t, prev_arm});
  for (std::size_t i = 1; i < corners_.size(); ++i) {
    const Corner& a = corners_[i - 1];
    const Corner& b = corners_[i];
    const double want = slip ? b.deg - lost : b.deg;  // where the arm would go without the stops
    const double from = slip ? prev_cmd - lost : prev_cmd;
    if (want >= lo && want <= hi) {
      // The segment may start outside (closed loop waiting at the stop) and come back in.
      if (!slip && (from < lo || from > hi) && b.t > a.t) {
        const double limit = from < lo ? lo : hi;
        const double f = (limit - from) / (want - from);
        out.point(a.t + SimDuration(static_cast<std::int64_t>(static_cast<double>((b.t - a.t).count()) * f)), limit);
      }
      out.point(b.t, want);
    } else {
      const double limit = want < lo ? lo : hi;
      if (prev_arm != limit && b.t > a.t && from != want) {
        const double f = std::clamp((limit - from) / (want - from), 0.0, 1.0);
        out.point(a.t + SimDuration(static_cast<std::int64_t>(static_cast<double>((b.t - a.t).count()) * f)), limit);
      }
      out.point(b.t, limit);
      if (slip) lost = b.deg - limit;
    }
    prev_cmd = b.deg;
    prev_arm = out.corners_.back().deg;
  }
  return out;
}

}  // namespace axon::fps::sim
