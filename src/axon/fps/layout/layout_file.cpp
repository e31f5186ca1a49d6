#include "axon/fps/layout/layout_file.hpp"

#include <fmt/format.h>

#include <cmath>
#include <map>
#include <optional>
#include <string_view>

namespace axon::fps {
namespace {

struct Located {
  core::ConfigNode node;
  double x = 0, y = 0;
  std::string what;  // "robot 12", "fiducial 3"
};

Result<GatewaySite> load_gateway(const core::ConfigNode& n) {
  AXON_TRY(n.reject_unknown({"id", "address", "sextant", "channels"}));
  GatewaySite g;
  AXON_TRY(id, n.get_in<int>("id", 1, 65535));
  g.id = static_cast<std::uint16_t>(id);
  AXON_TRY(address, n.get_or<std::string>("address", ""));
  g.address = address;
  if (n.has("sextant")) {
    AXON_TRY(s, n.get_in<int>("sextant", 0, kSextants));
    g.sextant = s;
  }
  if (n.has("channels")) {
    AXON_TRY(c, n.get_in<int>("channels", 1, kMaxGatewayChannels));
    g.channels = c;
  }
  return g;
}

// An optional length: absent, or a number above zero.
Result<std::optional<double>> optional_length(const core::ConfigNode& n, std::string_view key) {
  if (!n.has(key)) return std::optional<double>{};
  AXON_TRY(c, n.child(key));
  AXON_TRY(v, c.as<double>());
  if (!(v > 0)) return c.error(CoreErrc::config_bad_value, fmt::format("a length must be above 0 mm, not {}", v));
  return std::optional<double>(v);
}

// {metrology: [X, Y], apogee: [X, Y], boss: [X, Y]}: measured fibre positions on the beta arm.
Result<std::vector<FibreOffset>> load_fibre_offsets(const core::ConfigNode& n) {
  if (!n.is_map()) return n.error(CoreErrc::config_bad_value, "expected a map {FIBRE: [X, Y], ...}");
  std::vector<FibreOffset> out;
  for (const auto& key : n.keys()) {
    AXON_TRY(c, n.child(key));
    auto f = parse_fibre(key);
    if (!f) return c.error(CoreErrc::config_bad_value, fmt::format("unknown fibre '{}'; expected boss, apogee or metrology", key));
    AXON_TRY(xy, c.items());
    if (xy.size() != 2) return c.error(CoreErrc::config_bad_value, "expected [X, Y] in mm on the beta arm");
    AXON_TRY(x, xy[0].as<double>());
    AXON_TRY(y, xy[1].as<double>());
    out.push_back({*f, x, y});
  }
  return out;
}

// orientation_deg, alpha_length_mm, beta_length_mm, fibre_offsets: all optional.
Result<void> load_robot_geometry(const core::ConfigNode& n, RobotSite& r) {
  AXON_TRY(o, n.get_or<double>("orientation_deg", 0.0));
  r.orientation_deg = o;
  AXON_TRY(a, optional_length(n, "alpha_length_mm"));
  AXON_TRY(b, optional_length(n, "beta_length_mm"));
  r.alpha_length_mm = a;
  r.beta_length_mm = b;
  if (n.has("fibre_offsets")) {
    AXON_TRY(f, n.child("fibre_offsets"));
    AXON_TRY(offsets, load_fibre_offsets(f));
    r.fibre_offsets = std::move(offsets);
  }
  return ok();
}

Result<RobotSite> load_robot(const core::ConfigNode& n, const std::map<std::uint16_t, GatewaySite>& gateways) {
  AXON_TRY(n.reject_unknown({"id", "x", "y", "sextant", "gateway", "bus", "fibres", "disabled", "offline", "offsets",
                             "orientation_deg", "alpha_length_mm", "beta_length_mm", "fibre_offsets"}));
  RobotSite r;
  AXON_TRY(id, n.get_in<int>("id", 1, 2047));
  r.id = static_cast<std::uint16_t>(id);
  AXON_TRY(x, n.get<double>("x"));
  AXON_TRY(y, n.get<double>("y"));
  r.x_mm = x;
  r.y_mm = y;
  AXON_TRY(s, n.get_in<int>("sextant", 1, kSextants));
  r.sextant = s;
  AXON_TRY(gw_node, n.child("gateway"));
  AXON_TRY(gw, gw_node.as<int>());
  auto g = gw < 0 || gw > 65535 ? gateways.end() : gateways.find(static_cast<std::uint16_t>(gw));
  if (g == gateways.end()) {
    std::string known;
    for (const auto& [gid, site] : gateways) known += fmt::format("{}{}", known.empty() ? "" : ", ", gid);
    return gw_node.error(CoreErrc::config_bad_value,
                         fmt::format("gateway {} is not declared under 'gateways' (declared: {})", gw,
                                     known.empty() ? "none" : known));
  }
  AXON_TRY(bus, n.get_in<int>("bus", 1, g->second.channels));
  r.bus = BusRef{g->first, static_cast<std::uint8_t>(bus)};
  if (n.has("fibres")) {
    AXON_TRY(list, n.child("fibres"));
    AXON_TRY(items, list.items());
    for (const auto& item : items) {
      AXON_TRY(name, item.as<std::string>());
      auto f = parse_fibre(name);
      if (!f) return item.error(CoreErrc::config_bad_value, fmt::format("unknown fibre '{}'; expected boss, apogee or metrology", name));
      if (r.carries(*f)) return item.error(CoreErrc::config_bad_value, fmt::format("fibre '{}' listed twice", name));
      r.fibres.push_back(*f);
    }
  }
  AXON_TRY(disabled, n.get_or<bool>("disabled", false));
  AXON_TRY(offline, n.get_or<bool>("offline", false));
  r.disabled = disabled;
  r.offline = offline;
  if (n.has("offsets")) {
    AXON_TRY(o, n.child("offsets"));
    if (!o.is_map()) return o.error(CoreErrc::config_bad_value, "expected a map {alpha: DEG, beta: DEG}");
    AXON_TRY(o.reject_unknown({"alpha", "beta"}));
    AXON_TRY(a, o.get_or<double>("alpha", 0.0));
    AXON_TRY(b, o.get_or<double>("beta", 0.0));
    r.offsets = ArmOffsets{a, b};
  }
  AXON_TRY(load_robot_geometry(n, r));
  return r;
}

Result<Fiducial> load_fiducial(const core::ConfigNode& n) {
  AXON_TRY(n.reject_unknown({"id", "x", "y"}));
  Fiducial f;
  AXON_TRY(id, n.get_in<int>("id", 0, 1000000));
  AXON_TRY(x, n.get<double>("x"));
  AXON_TRY(y, n.get<double>("y"));
  f.id = id;
  f.x_mm = x;
  f.y_mm = y;
  return f;
}

Result<GuideCamera> load_guide_camera(const core::ConfigNode& n) {
  AXON_TRY(n.reject_unknown({"id", "x1", "y1", "x2", "y2", "buffer_mm"}));
  GuideCamera g;
  AXON_TRY(id, n.get_in<int>("id", 0, 1000000));
  AXON_TRY(x1, n.get<double>("x1"));
  AXON_TRY(y1, n.get<double>("y1"));
  AXON_TRY(x2, n.get<double>("x2"));
  AXON_TRY(y2, n.get<double>("y2"));
  AXON_TRY(buffer, n.get_or<double>("buffer_mm", g.buffer_mm));
  g = GuideCamera{id, x1, y1, x2, y2, buffer};
  if (std::hypot(x2 - x1, y2 - y1) < kMinGuideCameraLengthMm)
    return n.error(CoreErrc::config_bad_value, fmt::format("guide camera {}: (x1, y1) and (x2, y2) are the same point", id));
  if (buffer < 0) return n.error(CoreErrc::config_bad_value, fmt::format("guide camera {}: buffer_mm must not be negative", id));
  return g;
}

// arms: {alpha_length_mm, beta_tip_mm, beta_collision_mm}, each optional (defaults: ArmLengths{}).
Result<ArmLengths> load_arms(const core::ConfigNode& root) {
  ArmLengths arms;
  if (!root.has("arms")) return arms;
  AXON_TRY(n, root.child("arms"));
  if (!n.is_map()) return n.error(CoreErrc::config_bad_value, "expected a map {alpha_length_mm, beta_tip_mm, beta_collision_mm}");
  AXON_TRY(n.reject_unknown({"alpha_length_mm", "beta_tip_mm", "beta_collision_mm"}));
  AXON_TRY(a, optional_length(n, "alpha_length_mm"));
  AXON_TRY(t, optional_length(n, "beta_tip_mm"));
  AXON_TRY(c, optional_length(n, "beta_collision_mm"));
  return ArmLengths{a.value_or(arms.alpha_length_mm), t.value_or(arms.beta_tip_mm), c.value_or(arms.beta_collision_mm)};
}

Result<std::vector<core::ConfigNode>> list_of(const core::ConfigNode& root, std::string_view key, bool required) {
  if (!required && !root.has(key)) return std::vector<core::ConfigNode>{};
  AXON_TRY(node, root.child(key));
  return node.items();
}

// The line where each id was first used: a second use is an error naming that line.
class FirstLines {
 public:
  explicit FirstLines(std::string_view what) : what_(what) {}
  Result<void> note(const core::ConfigNode& n, int id) {
    if (auto it = lines_.find(id); it != lines_.end())
      return n.error(CoreErrc::config_bad_value, fmt::format("{} id {} already used at line {}", what_, id, it->second));
    lines_.emplace(id, n.line());
    return ok();
  }

 private:
  std::string_view what_;
  std::map<int, int> lines_;
};

Result<std::vector<GuideCamera>> load_guide_cameras(const core::ConfigNode& root) {
  std::vector<GuideCamera> out;
  FirstLines lines("guide camera");
  AXON_TRY(nodes, list_of(root, "guide_cameras", false));
  for (const auto& n : nodes) {
    AXON_TRY(g, load_guide_camera(n));
    AXON_TRY(lines.note(n, g.id));
    out.push_back(g);
  }
  return out;
}

// Sites closer than half a pitch are the same site written twice (or a typo).
Result<void> check_overlaps(const std::vector<Located>& sites, double pitch) {
  for (std::size_t i = 0; i < sites.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (std::hypot(sites[i].x - sites[j].x, sites[i].y - sites[j].y) < pitch / 2)
        return sites[i].node.error(CoreErrc::config_bad_value,
                                   fmt::format("{} at ({}, {}) overlaps {} at ({}, {}) (line {})", sites[i].what,
                                               sites[i].x, sites[i].y, sites[j].what, sites[j].x, sites[j].y,
                                               sites[j].node.line()));
  return ok();
}

// Exactly (the shortest text that reads back to the same double): for the measured geometry.
std::string exact(double v) { return fmt::format("{}", v); }

std::string num(double v) {
  if (std::abs(v) >= 1e15) return exact(v);  // beyond what a long long or 4 decimals say well
  if (v == std::round(v)) return fmt::format("{}", static_cast<long long>(v));
  std::string s = fmt::format("{:.4f}", v);
  while (s.back() == '0') s.pop_back();
  return s;
}

// The robot's optional geometry keys, each only when set (so plain layouts stay as they were).
std::string robot_geometry_yaml(const RobotSite& r) {
  std::string out;
  if (r.orientation_deg != 0) out += fmt::format(", orientation_deg: {}", exact(r.orientation_deg));
  if (r.alpha_length_mm) out += fmt::format(", alpha_length_mm: {}", exact(*r.alpha_length_mm));
  if (r.beta_length_mm) out += fmt::format(", beta_length_mm: {}", exact(*r.beta_length_mm));
  if (!r.fibre_offsets.empty()) {
    out += ", fibre_offsets: {";
    for (std::size_t i = 0; i < r.fibre_offsets.size(); ++i) {
      const auto& f = r.fibre_offsets[i];
      out += fmt::format("{}{}: [{}, {}]", i ? ", " : "", fibre_name(f.fibre), exact(f.x_mm), exact(f.y_mm));
    }
    out += "}";
  }
  return out;
}

}  // namespace

Result<FocalPlane> load_layout(const core::ConfigNode& root) {
  if (!root.is_map()) return root.error(CoreErrc::config_bad_value, "expected a layout map (name, gateways, robots, fiducials)");
  AXON_TRY(root.reject_unknown({"name", "pitch_mm", "neighbours", "arms", "gateways", "robots", "fiducials", "guide_cameras"}));
  FocalPlaneSpec spec;
  AXON_TRY(name, root.get_or<std::string>("name", "unnamed"));
  spec.name = name;
  if (root.has("pitch_mm")) {
    AXON_TRY(p, root.get_in<double>("pitch_mm", 1.0, 1000.0));
    spec.pitch_mm = p;
  }
  spec.neighbours.adjacent_radius_mm = spec.pitch_mm * 1.1;
  if (root.has("neighbours")) {
    AXON_TRY(n, root.child("neighbours"));
    AXON_TRY(n.reject_unknown({"robot_radius_mm", "adjacent_radius_mm", "fiducial_radius_mm"}));
    AXON_TRY(r, n.get_or<double>("robot_radius_mm", spec.neighbours.robot_radius_mm));
    AXON_TRY(a, n.get_or<double>("adjacent_radius_mm", spec.neighbours.adjacent_radius_mm));
    AXON_TRY(f, n.get_or<double>("fiducial_radius_mm", spec.neighbours.fiducial_radius_mm));
    if (r < 0 || a < 0 || f < 0) return n.error(CoreErrc::config_bad_value, "radii must not be negative");
    spec.neighbours = NeighbourOptions{r, a, f};
  }

  AXON_TRY(arms, load_arms(root));
  spec.arms = arms;

  std::map<std::uint16_t, GatewaySite> gateways;
  AXON_TRY(gw_nodes, list_of(root, "gateways", true));
  for (const auto& n : gw_nodes) {
    AXON_TRY(g, load_gateway(n));
    if (gateways.count(g.id)) return n.error(CoreErrc::config_bad_value, fmt::format("gateway {} declared twice", g.id));
    gateways.emplace(g.id, g);
    spec.gateways.push_back(g);
  }

  std::vector<Located> sites;
  FirstLines robot_lines("robot");
  AXON_TRY(robot_nodes, list_of(root, "robots", true));
  for (const auto& n : robot_nodes) {
    AXON_TRY(r, load_robot(n, gateways));
    AXON_TRY(robot_lines.note(n, r.id));
    sites.push_back(Located{n, r.x_mm, r.y_mm, fmt::format("robot {}", r.id)});
    spec.robots.push_back(std::move(r));
  }

  FirstLines fiducial_lines("fiducial");
  AXON_TRY(fid_nodes, list_of(root, "fiducials", false));
  for (const auto& n : fid_nodes) {
    AXON_TRY(f, load_fiducial(n));
    AXON_TRY(fiducial_lines.note(n, f.id));
    sites.push_back(Located{n, f.x_mm, f.y_mm, fmt::format("fiducial {}", f.id)});
    spec.fiducials.push_back(f);
  }
  AXON_TRY(check_overlaps(sites, spec.pitch_mm));

  AXON_TRY(cameras, load_guide_cameras(root));
  spec.guide_cameras = std::move(cameras);

  auto plane = FocalPlane::build(std::move(spec));
  if (!plane) return root.error(CoreErrc::config_bad_value, plane.error().detail);
  return std::move(plane).value();
}

Result<FocalPlane> load_layout_file(const std::string& path) {
  AXON_TRY(root, core::ConfigNode::load_file(path));
  return load_layout(root);
}

std::string to_yaml(const FocalPlane& plane) {
  const auto& s = plane.spec();
  std::string out;
  out += fmt::format("# axon fps focal-plane layout (docs/fps-layout.md): {} robots, {} fiducials, {} gateways\n",
                     s.robots.size(), s.fiducials.size(), s.gateways.size());
  out += fmt::format("name: {}\npitch_mm: {}\n", core::yaml_quoted(s.name), num(s.pitch_mm));
  out += fmt::format("neighbours: {{robot_radius_mm: {}, adjacent_radius_mm: {}, fiducial_radius_mm: {}}}\n",
                     num(s.neighbours.robot_radius_mm), num(s.neighbours.adjacent_radius_mm),
                     num(s.neighbours.fiducial_radius_mm));
  if (s.arms != ArmLengths{})
    out += fmt::format("arms: {{alpha_length_mm: {}, beta_tip_mm: {}, beta_collision_mm: {}}}\n", exact(s.arms.alpha_length_mm),
                       exact(s.arms.beta_tip_mm), exact(s.arms.beta_collision_mm));
  out += "gateways:\n";
  for (const auto& g : s.gateways)
    out += fmt::format("  - {{id: {}, address: {}, sextant: {}, channels: {}}}\n", g.id, core::yaml_quoted(g.address),
                       g.sextant, g.channels);
  out += "robots:\n";
  for (const auto& r : s.robots) {
    std::string fibres;
    for (Fibre f : r.fibres) fibres += fmt::format("{}{}", fibres.empty() ? "" : ", ", fibre_name(f));
    out += fmt::format("  - {{id: {}, x: {}, y: {}, sextant: {}, gateway: {}, bus: {}, fibres: [{}]", r.id, num(r.x_mm),
                       num(r.y_mm), r.sextant, r.bus.gateway, r.bus.channel, fibres);
    if (r.disabled) out += ", disabled: true";
    if (r.offline) out += ", offline: true";
    if (r.offsets) out += fmt::format(", offsets: {{alpha: {}, beta: {}}}", num(r.offsets->alpha_deg), num(r.offsets->beta_deg));
    out += robot_geometry_yaml(r);
    out += "}\n";
  }
  out += "fiducials:\n";
  for (const auto& f : s.fiducials) out += fmt::format("  - {{id: {}, x: {}, y: {}}}\n", f.id, num(f.x_mm), num(f.y_mm));
  if (!s.guide_cameras.empty()) out += "guide_cameras:\n";
  for (const auto& g : s.guide_cameras)
    out += fmt::format("  - {{id: {}, x1: {}, y1: {}, x2: {}, y2: {}, buffer_mm: {}}}\n", g.id, exact(g.x1_mm), exact(g.y1_mm),
                       exact(g.x2_mm), exact(g.y2_mm), exact(g.buffer_mm));
  return out;
}

}  // namespace axon::fps
