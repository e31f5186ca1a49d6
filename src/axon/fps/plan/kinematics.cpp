#include "axon/fps/plan/kinematics.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <numbers>

namespace axon::fps::plan {

namespace {

// Slack for angles and radii computed in floating point (well below any mechanical figure).
constexpr double kEpsDeg = 1e-9;
constexpr double kEpsMm = 1e-9;

bool iequal(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
         });
}

}  // namespace

std::vector<Fibre> ArmDesign::default_fibres() {
  // Fibre head layout (see docs/fps-plan.md): the two science fibres sit side by side 0.75 mm
  // apart; the science fibre at full extension reaches one hex pitch (22.4 mm) from the centre,
  // and the metrology fibre lies on the arm's axis one fibre spacing behind the pair.
  const double half = 0.375;
  const double science_x = std::sqrt(22.4 * 22.4 - half * half) - ArmLengths{}.alpha_length_mm;  // 14.9969
  const double metrology_x = science_x - std::sqrt(0.75 * 0.75 - half * half);                  // 14.3473
  return {{"metrology", {metrology_x, 0.0}}, {"apogee", {science_x, half}}, {"boss", {science_x, -half}}};
}

std::optional<std::size_t> ArmDesign::fibre_index(std::string_view name) const {
  for (std::size_t i = 0; i < fibres.size(); ++i)
    if (iequal(fibres[i].name, name)) return i;
  return std::nullopt;
}

std::string_view to_string(Elbow e) noexcept { return e == Elbow::ccw ? "ccw" : "cw"; }

std::optional<double> wrap_into(double deg, double lo, double hi) noexcept {
  if (!std::isfinite(deg) || !(lo <= hi)) return std::nullopt;
  // The lowest deg + 360 k that is >= lo (with a little slack for rounding).
  const double k = std::ceil((lo - deg - kEpsDeg) / 360.0);
  double v = deg + 360.0 * k;
  if (v < lo) v = lo;  // within the slack
  if (v > hi + kEpsDeg) return std::nullopt;
  return std::min(v, hi);
}

Positioner::Positioner(const RobotSpec& spec, const ArmDesign& design)
    : id_(spec.id),
      centre_(spec.centre),
      buffer_(spec.buffer_mm),
      limits_(spec.limits),
      alpha_zero_rad_((spec.calibration.orientation_deg + spec.calibration.alpha_offset_deg) * kRad),
      beta_zero_rad_(spec.calibration.beta_offset_deg * kRad),
      arms_{design.alpha_length_mm + spec.calibration.alpha_length_delta_mm,
            design.beta_tip_mm + spec.calibration.beta_length_delta_mm,
            design.beta_collision_mm + spec.calibration.beta_length_delta_mm} {
  fibres_.reserve(design.fibres.size());
  for (const auto& f : design.fibres) {
    Vec2 o{f.offset.x + spec.calibration.beta_length_delta_mm, f.offset.y};
    for (const auto& m : spec.calibration.fibres)
      if (iequal(m.name, f.name)) o = m.offset;
    fibres_.push_back({norm(o), std::atan2(o.y, o.x), o});
  }
}

Vec2 Positioner::beta_axis(Pose p) const noexcept {
  return centre_ + arms_.alpha_length_mm * unit(alpha_zero_rad_ + p.alpha_deg * kRad);
}

Segment Positioner::collision_segment(Pose p) const noexcept {
  const double a = alpha_zero_rad_ + p.alpha_deg * kRad;
  const double b = a + beta_zero_rad_ + p.beta_deg * kRad;
  const Vec2 axis = centre_ + arms_.alpha_length_mm * unit(a);
  return {axis, axis + arms_.beta_collision_mm * unit(b)};
}

Vec2 Positioner::tip(Pose p) const noexcept {
  const double a = alpha_zero_rad_ + p.alpha_deg * kRad;
  const double b = a + beta_zero_rad_ + p.beta_deg * kRad;
  return centre_ + arms_.alpha_length_mm * unit(a) + arms_.beta_tip_mm * unit(b);
}

Vec2 Positioner::fibre(Pose p, std::size_t fibre) const noexcept {
  const double a = alpha_zero_rad_ + p.alpha_deg * kRad;
  const double b = a + beta_zero_rad_ + p.beta_deg * kRad;
  const Vec2 o = fibres_[fibre].offset;
  return centre_ + arms_.alpha_length_mm * unit(a) + rotate(o, std::cos(b), std::sin(b));
}

double Positioner::min_reach_mm(std::size_t fibre) const noexcept {
  return std::abs(arms_.alpha_length_mm - fibres_[fibre].radius);
}

double Positioner::max_reach_mm(std::size_t fibre) const noexcept { return arms_.alpha_length_mm + fibres_[fibre].radius; }

bool Positioner::within_limits(Pose p) const noexcept {
  return p.alpha_deg >= limits_.alpha_min_deg - kEpsDeg && p.alpha_deg <= limits_.alpha_max_deg + kEpsDeg &&
         p.beta_deg >= limits_.beta_min_deg - kEpsDeg && p.beta_deg <= limits_.beta_max_deg + kEpsDeg;
}

IkSolutions Positioner::inverse(Vec2 target, std::size_t fibre) const noexcept {
  IkSolutions out;
  const FibrePolar& f = fibres_[fibre];
  const Vec2 d = target - centre_;
  const double dist = norm(d);
  const double l1 = arms_.alpha_length_mm;
  const double l2 = f.radius;
  if (dist > l1 + l2 + kEpsMm) {
    out.reason = PlanErrc::too_far;
    return out;
  }
  if (dist < std::abs(l1 - l2) - kEpsMm) {
    out.reason = PlanErrc::too_close;
    return out;
  }
  // Law of cosines for the angle g between the alpha arm and the line from the beta axis to the
  // fibre; the two elbows are +g and -g.
  const double c = std::clamp((dist * dist - l1 * l1 - l2 * l2) / (2 * l1 * l2), -1.0, 1.0);
  const double g_abs = std::acos(c);
  const double to_target = std::atan2(d.y, d.x);
  for (std::size_t i = 0; i < 2; ++i) {
    const double g = i == 0 ? g_abs : -g_abs;
    const double alpha_world = to_target - std::atan2(l2 * std::sin(g), l1 + l2 * std::cos(g));
    const double alpha = (alpha_world - alpha_zero_rad_) * kDeg;
    const double beta = (g - f.angle_rad - beta_zero_rad_) * kDeg;
    const auto a = wrap_into(alpha, limits_.alpha_min_deg, limits_.alpha_max_deg);
    const auto b = wrap_into(beta, limits_.beta_min_deg, limits_.beta_max_deg);
    out.pose[i] = {a ? *a : std::remainder(alpha, 360.0), b ? *b : std::remainder(beta, 360.0)};
    out.ok[i] = a.has_value() && b.has_value();
  }
  if (!out.any()) out.reason = PlanErrc::outside_hard_stops;
  return out;
}

Result<Pose> Positioner::inverse(Vec2 target, std::size_t fibre, Elbow elbow) const {
  const IkSolutions s = inverse(target, fibre);
  if (auto p = s.get(elbow)) return *p;
  const PlanErrc why = s.any() ? PlanErrc::outside_hard_stops : s.reason;
  return make_error(why, fmt::format("robot {}: fibre {} to ({:.3f}, {:.3f}) mm, {} elbow (distance {:.3f} mm, "
                                     "reach {:.3f}..{:.3f} mm)",
                                     id_, fibre, target.x, target.y, to_string(elbow), norm(target - centre_),
                                     min_reach_mm(fibre), max_reach_mm(fibre)));
}

}  // namespace axon::fps::plan
