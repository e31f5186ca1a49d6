#include "axon/fps/layout/layout_file.hpp"

#include <fmt/format.h>

#include <cmath>
#include <map>

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

Result<RobotSite> load_robot(const core::ConfigNode& n, const std::map<std::uint16_t, GatewaySite>& gateways) {
  AXON_TRY(n.reject_unknown({"id", "x", "y", "sextant", "gateway", "bus", "fibres", "disabled", "offline", "offsets"}));
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

Result<std::vector<core::ConfigNode>> list_of(const core::ConfigNode& root, std::string_view key, bool required) {
  if (!required && !root.has(key)) return std::vector<core::ConfigNode>{};
  AXON_TRY(node, root.child(key));
  return node.items();
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

std::string num(double v) {
  if (v == std::round(v)) return fmt::format("{}", static_cast<long long>(v));
  std::string s = fmt::format("{:.4f}", v);
  while (s.back() == '0') s.pop_back();
  return s;
}

}  // namespace

Result<FocalPlane> load_layout(const core::ConfigNode& root) {
  if (!root.is_map()) return root.error(CoreErrc::config_bad_value, "expected a layout map (name, gateways, robots, fiducials)");
  AXON_TRY(root.reject_unknown({"name", "pitch_mm", "neighbours", "gateways", "robots", "fiducials"}));
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

  std::map<std::uint16_t, GatewaySite> gateways;
  AXON_TRY(gw_nodes, list_of(root, "gateways", true));
  for (const auto& n : gw_nodes) {
    AXON_TRY(g, load_gateway(n));
    if (gateways.count(g.id)) return n.error(CoreErrc::config_bad_value, fmt::format("gateway {} declared twice", g.id));
    gateways.emplace(g.id, g);
    spec.gateways.push_back(g);
  }

  std::vector<Located> sites;
  std::map<std::uint16_t, int> robot_lines;
  AXON_TRY(robot_nodes, list_of(root, "robots", true));
  for (const auto& n : robot_nodes) {
    AXON_TRY(r, load_robot(n, gateways));
    if (auto it = robot_lines.find(r.id); it != robot_lines.end())
      return n.error(CoreErrc::config_bad_value, fmt::format("robot id {} already used at line {}", r.id, it->second));
    robot_lines.emplace(r.id, n.line());
    sites.push_back(Located{n, r.x_mm, r.y_mm, fmt::format("robot {}", r.id)});
    spec.robots.push_back(std::move(r));
  }

  std::map<int, int> fiducial_lines;
  AXON_TRY(fid_nodes, list_of(root, "fiducials", false));
  for (const auto& n : fid_nodes) {
    AXON_TRY(f, load_fiducial(n));
    if (auto it = fiducial_lines.find(f.id); it != fiducial_lines.end())
      return n.error(CoreErrc::config_bad_value, fmt::format("fiducial id {} already used at line {}", f.id, it->second));
    fiducial_lines.emplace(f.id, n.line());
    sites.push_back(Located{n, f.x_mm, f.y_mm, fmt::format("fiducial {}", f.id)});
    spec.fiducials.push_back(f);
  }
  AXON_TRY(check_overlaps(sites, spec.pitch_mm));

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
    out += "}\n";
  }
  out += "fiducials:\n";
  for (const auto& f : s.fiducials) out += fmt::format("  - {{id: {}, x: {}, y: {}}}\n", f.id, num(f.x_mm), num(f.y_mm));
  return out;
}

}  // namespace axon::fps
