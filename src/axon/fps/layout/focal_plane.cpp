#include "axon/fps/layout/focal_plane.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <set>
#include <string_view>

namespace axon::fps {

std::string BusRef::to_string() const { return fmt::format("gw{}/{}", gateway, channel); }

std::string_view fibre_name(Fibre f) noexcept {
  switch (f) {
    case Fibre::boss: return "boss";
    case Fibre::apogee: return "apogee";
    case Fibre::metrology: return "metrology";
  }
  return "?";
}

std::optional<Fibre> parse_fibre(std::string_view name) noexcept {
  for (Fibre f : {Fibre::boss, Fibre::apogee, Fibre::metrology})
    if (fibre_name(f) == name) return f;
  return std::nullopt;
}

bool RobotSite::carries(Fibre f) const noexcept { return std::find(fibres.begin(), fibres.end(), f) != fibres.end(); }

namespace {

Error bad(std::string what) { return Error(CoreErrc::config_bad_value, std::move(what)); }

double distance(double ax, double ay, double bx, double by) { return std::hypot(ax - bx, ay - by); }

bool finite(std::initializer_list<double> values) {
  for (double v : values)
    if (!std::isfinite(v)) return false;
  return true;
}

// A length must be a finite number above zero.
Result<void> check_length(double v, std::string_view what) {
  if (!std::isfinite(v) || !(v > 0)) return bad(fmt::format("{} must be a finite length above 0, not {}", what, v));
  return ok();
}

Result<void> check_robot_geometry(const RobotSite& r) {
  if (!finite({r.x_mm, r.y_mm, r.orientation_deg}))
    return bad(fmt::format("robot {}: position and orientation must be finite numbers", r.id));
  if (r.alpha_length_mm) {
    AXON_TRY(check_length(*r.alpha_length_mm, fmt::format("robot {}: alpha length", r.id)));
  }
  if (r.beta_length_mm) {
    AXON_TRY(check_length(*r.beta_length_mm, fmt::format("robot {}: beta length", r.id)));
  }
  for (std::size_t i = 0; i < r.fibre_offsets.size(); ++i) {
    const auto& f = r.fibre_offsets[i];
    if (!finite({f.x_mm, f.y_mm}))
      return bad(fmt::format("robot {}: {} fibre position must be finite", r.id, fibre_name(f.fibre)));
    for (std::size_t j = 0; j < i; ++j)
      if (r.fibre_offsets[j].fibre == f.fibre)
        return bad(fmt::format("robot {}: {} fibre position given twice", r.id, fibre_name(f.fibre)));
  }
  return ok();
}

Result<void> check_fixed_geometry(const FocalPlaneSpec& spec) {
  AXON_TRY(check_length(spec.arms.alpha_length_mm, "arms: alpha length"));
  AXON_TRY(check_length(spec.arms.beta_tip_mm, "arms: beta tip"));
  AXON_TRY(check_length(spec.arms.beta_collision_mm, "arms: beta collision segment"));
  for (const auto& f : spec.fiducials)
    if (!finite({f.x_mm, f.y_mm})) return bad(fmt::format("fiducial {}: position must be finite", f.id));
  std::set<int> ids;
  for (const auto& g : spec.guide_cameras) {
    if (!ids.insert(g.id).second) return bad(fmt::format("guide camera {} listed twice", g.id));
    if (!finite({g.x1_mm, g.y1_mm, g.x2_mm, g.y2_mm}))
      return bad(fmt::format("guide camera {}: end points must be finite", g.id));
    if (distance(g.x1_mm, g.y1_mm, g.x2_mm, g.y2_mm) < kMinGuideCameraLengthMm)
      return bad(fmt::format("guide camera {}: its two end points coincide (a zero-length segment)", g.id));
    if (!std::isfinite(g.buffer_mm) || g.buffer_mm < 0)
      return bad(fmt::format("guide camera {}: buffer must be finite and not negative, not {}", g.id, g.buffer_mm));
  }
  return ok();
}

}  // namespace

Result<FocalPlane> FocalPlane::build(FocalPlaneSpec spec) {
  if (!(spec.pitch_mm > 0)) return bad(fmt::format("layout '{}': pitch must be positive", spec.name));
  const double min_sep = spec.pitch_mm / 2;
  AXON_TRY(check_fixed_geometry(spec));
  std::map<std::uint16_t, const GatewaySite*> gateways;
  for (const auto& g : spec.gateways) {
    if (g.channels < 1 || g.channels > kMaxGatewayChannels)
      return bad(fmt::format("gateway {}: channels must be 1..{}", g.id, kMaxGatewayChannels));
    if (g.sextant < 0 || g.sextant > kSextants) return bad(fmt::format("gateway {}: sextant must be 0..6", g.id));
    if (!gateways.emplace(g.id, &g).second) return bad(fmt::format("gateway {} declared twice", g.id));
  }
  std::set<std::uint16_t> ids;
  for (std::size_t i = 0; i < spec.robots.size(); ++i) {
    const auto& r = spec.robots[i];
    if (r.id < 1 || r.id > 2047) return bad(fmt::format("robot id {} outside 1..2047", r.id));
    if (!ids.insert(r.id).second) return bad(fmt::format("robot {} listed twice", r.id));
    AXON_TRY(check_robot_geometry(r));
    if (r.sextant < 1 || r.sextant > kSextants) return bad(fmt::format("robot {}: sextant {} outside 1..6", r.id, r.sextant));
    auto g = gateways.find(r.bus.gateway);
    if (g == gateways.end()) return bad(fmt::format("robot {}: gateway {} is not declared", r.id, r.bus.gateway));
    if (r.bus.channel < 1 || r.bus.channel > g->second->channels)
      return bad(fmt::format("robot {}: bus {} outside 1..{} of gateway {}", r.id, r.bus.channel, g->second->channels,
                             r.bus.gateway));
    for (std::size_t j = 0; j < i; ++j) {
      const auto& o = spec.robots[j];
      if (distance(r.x_mm, r.y_mm, o.x_mm, o.y_mm) < min_sep)
        return bad(fmt::format("robot {} at ({:.3f}, {:.3f}) overlaps robot {} at ({:.3f}, {:.3f})", r.id, r.x_mm, r.y_mm,
                               o.id, o.x_mm, o.y_mm));
    }
  }
  std::set<int> fids;
  for (std::size_t i = 0; i < spec.fiducials.size(); ++i) {
    const auto& f = spec.fiducials[i];
    if (!fids.insert(f.id).second) return bad(fmt::format("fiducial {} listed twice", f.id));
    for (const auto& r : spec.robots)
      if (distance(f.x_mm, f.y_mm, r.x_mm, r.y_mm) < min_sep)
        return bad(fmt::format("fiducial {} at ({:.3f}, {:.3f}) overlaps robot {}", f.id, f.x_mm, f.y_mm, r.id));
    for (std::size_t j = 0; j < i; ++j)
      if (distance(f.x_mm, f.y_mm, spec.fiducials[j].x_mm, spec.fiducials[j].y_mm) < min_sep)
        return bad(fmt::format("fiducial {} overlaps fiducial {}", f.id, spec.fiducials[j].id));
  }
  FocalPlane plane(std::move(spec));
  for (std::size_t i = 0; i < plane.spec_.robots.size(); ++i) plane.index_[plane.spec_.robots[i].id] = i;
  plane.compute_neighbours();
  return plane;
}

void FocalPlane::compute_neighbours() {
  const auto& robots = spec_.robots;
  const auto& opt = spec_.neighbours;
  neighbours_.assign(robots.size(), {});
  for (std::size_t i = 0; i < robots.size(); ++i) {
    // Distances quantised to 10 um so that equal distances on the grid sort by id, however the
    // positions were rounded when written.
    std::vector<std::pair<long long, std::uint16_t>> near;
    std::vector<std::pair<long long, int>> fids;
    auto key = [](double d) { return std::llround(d * 100.0); };
    for (std::size_t j = 0; j < robots.size(); ++j) {
      if (i == j) continue;
      const double d = distance(robots[i].x_mm, robots[i].y_mm, robots[j].x_mm, robots[j].y_mm);
      if (d <= opt.robot_radius_mm || d <= opt.adjacent_radius_mm) near.emplace_back(key(d), robots[j].id);
    }
    for (const auto& f : spec_.fiducials) {
      const double d = distance(robots[i].x_mm, robots[i].y_mm, f.x_mm, f.y_mm);
      if (d <= opt.fiducial_radius_mm) fids.emplace_back(key(d), f.id);
    }
    std::sort(near.begin(), near.end());
    std::sort(fids.begin(), fids.end());
    auto& n = neighbours_[i];
    for (const auto& [k, id] : near) {
      const auto* o = &robots[index_.at(id)];
      const double d = distance(robots[i].x_mm, robots[i].y_mm, o->x_mm, o->y_mm);
      if (d <= opt.robot_radius_mm) n.robots.push_back(id);
      if (d <= opt.adjacent_radius_mm) n.adjacent.push_back(id);
    }
    for (const auto& [k, id] : fids) n.fiducials.push_back(id);
  }
}

const RobotSite* FocalPlane::find(std::uint16_t id) const noexcept {
  auto it = index_.find(id);
  return it == index_.end() ? nullptr : &spec_.robots[it->second];
}

const GatewaySite* FocalPlane::gateway(std::uint16_t id) const noexcept {
  for (const auto& g : spec_.gateways)
    if (g.id == id) return &g;
  return nullptr;
}

const Fiducial* FocalPlane::fiducial(int id) const noexcept {
  for (const auto& f : spec_.fiducials)
    if (f.id == id) return &f;
  return nullptr;
}

const Neighbours& FocalPlane::neighbours(std::uint16_t id) const noexcept {
  static const Neighbours none;
  auto it = index_.find(id);
  return it == index_.end() ? none : neighbours_[it->second];
}

std::map<BusRef, std::vector<std::uint16_t>> FocalPlane::by_bus() const {
  std::map<BusRef, std::vector<std::uint16_t>> out;
  for (const auto& [id, i] : index_) out[spec_.robots[i].bus].push_back(id);
  return out;
}

std::map<int, std::vector<std::uint16_t>> FocalPlane::by_sextant() const {
  std::map<int, std::vector<std::uint16_t>> out;
  for (const auto& [id, i] : index_) out[spec_.robots[i].sextant].push_back(id);
  return out;
}

std::map<std::uint16_t, std::vector<std::uint16_t>> FocalPlane::by_gateway() const {
  std::map<std::uint16_t, std::vector<std::uint16_t>> out;
  for (const auto& [id, i] : index_) out[spec_.robots[i].bus.gateway].push_back(id);
  return out;
}

std::vector<BusRef> FocalPlane::buses() const {
  std::vector<BusRef> out;
  for (const auto& [bus, ids] : by_bus()) out.push_back(bus);
  return out;
}

}  // namespace axon::fps
