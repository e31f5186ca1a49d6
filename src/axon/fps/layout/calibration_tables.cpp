#include "axon/fps/layout/calibration_tables.hpp"

#include "axon/core/text.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <map>
#include <numbers>
#include <sstream>
#include <vector>

namespace axon::fps {
namespace {

// Axes whose lengths or right angle are off by more than this are refused (the tables give them
// to 1e-15 or so; this only catches a typo or a swapped column).
constexpr double kAxisTolerance = 1e-3;

struct Row {
  int line = 0;
  std::vector<std::string_view> cells;
};

struct Table {
  std::string file;
  std::vector<std::string_view> header;
  std::vector<Row> rows;
};

Error table_error(const std::string& file, int line, std::string_view what) {
  return Error(CoreErrc::config_bad_value, fmt::format("{}:{}: {}", file, line, what));
}

// Header and rows; blank lines are skipped, every row has as many cells as the header.
Result<Table> read_table(std::string_view text, const std::string& file) {
  constexpr std::string_view kBom = "\xEF\xBB\xBF";
  if (text.substr(0, kBom.size()) == kBom) text.remove_prefix(kBom.size());
  Table t{file, {}, {}};
  bool header = false;
  for (int line = 1; !text.empty(); ++line) {
    const auto nl = text.find('\n');
    const std::string_view l = text.substr(0, nl);
    text = nl == std::string_view::npos ? std::string_view{} : text.substr(nl + 1);
    if (core::trim(l).empty()) continue;
    auto cells = core::split_fields(l);
    if (!header) {
      t.header = std::move(cells);
      header = true;
    } else if (cells.size() != t.header.size()) {
      return table_error(file, line, fmt::format("{} cells, but the header names {} columns", cells.size(), t.header.size()));
    } else {
      t.rows.push_back({line, std::move(cells)});
    }
  }
  if (!header) return table_error(file, 1, "empty table: no header line");
  return t;
}

// The columns a reader needs, looked up by name once; cells by the position in that list.
class Columns {
 public:
  static Result<Columns> find(const Table& t, std::initializer_list<std::string_view> names) {
    Columns c(t);
    for (const auto name : names) {
      std::size_t found = t.header.size();
      for (std::size_t i = 0; i < t.header.size(); ++i) {
        if (t.header[i] != name) continue;
        if (found != t.header.size()) return table_error(t.file, 1, fmt::format("column '{}' appears twice", name));
        found = i;
      }
      if (found == t.header.size()) return table_error(t.file, 1, fmt::format("no column '{}'", name));
      c.index_.push_back(found);
    }
    return c;
  }

  [[nodiscard]] std::string_view text(const Row& r, std::size_t k) const { return r.cells[index_[k]]; }

  [[nodiscard]] Error error(const Row& r, std::size_t k, std::string_view what) const {
    return table_error(table_->file, r.line, fmt::format("column '{}': {}", table_->header[index_[k]], what));
  }

  [[nodiscard]] Result<double> number(const Row& r, std::size_t k) const {
    const auto v = core::parse_number<double>(text(r, k));
    if (!v || !std::isfinite(*v)) return error(r, k, fmt::format("expected a finite number, got '{}'", text(r, k)));
    return *v;
  }

  // A whole number within [lo, hi], after an optional prefix of letters ("F201752").
  [[nodiscard]] Result<int> id(const Row& r, std::size_t k, int lo, int hi) const {
    std::string_view s = text(r, k);
    while (!s.empty() && std::isalpha(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
    const auto v = core::parse_number<int>(s);
    if (!v || *v < lo || *v > hi) return error(r, k, fmt::format("expected an id {}..{}, got '{}'", lo, hi, text(r, k)));
    return *v;
  }

 private:
  explicit Columns(const Table& t) : table_(&t) {}
  const Table* table_;
  std::vector<std::size_t> index_;
};

// A hole's (or camera's) centre and in-plane axes.
struct Frame {
  double x = 0, y = 0, ix = 1, iy = 0, jx = 0, jy = 1;
};

// Reads x, y, ix, iy, jx, jy from columns first..first+5 and checks the axes.
Result<Frame> read_frame(const Columns& c, const Row& r, std::size_t first) {
  Frame f;
  double* out[] = {&f.x, &f.y, &f.ix, &f.iy, &f.jx, &f.jy};
  for (std::size_t k = 0; k < 6; ++k) {
    AXON_TRY(v, c.number(r, first + k));
    *out[k] = v;
  }
  const double ni = std::hypot(f.ix, f.iy), nj = std::hypot(f.jx, f.jy);
  const double dot = f.ix * f.jx + f.iy * f.jy, cross = f.ix * f.jy - f.iy * f.jx;
  if (std::abs(ni - 1) > kAxisTolerance || std::abs(nj - 1) > kAxisTolerance || std::abs(dot) > kAxisTolerance ||
      cross < 0)
    return c.error(r, first + 2,
                   fmt::format("axes i = ({}, {}), j = ({}, {}) are not a right-handed pair of unit vectors in the plane",
                               f.ix, f.iy, f.jx, f.jy));
  return f;
}

struct Hole {
  Frame frame;
  std::string_view type;
};

Result<std::map<std::string, Hole, std::less<>>> read_holes(const Table& t) {
  enum { hole, type, x };  // then y, ix, iy, jx, jy
  AXON_TRY(c, Columns::find(t, {"holeID", "holeType", "xWok", "yWok", "ix", "iy", "jx", "jy"}));
  std::map<std::string, Hole, std::less<>> out;
  std::map<std::string, int, std::less<>> lines;
  for (const auto& r : t.rows) {
    AXON_TRY(f, read_frame(c, r, x));
    const std::string id(c.text(r, hole));
    if (auto it = lines.find(id); it != lines.end())
      return c.error(r, hole, fmt::format("hole '{}' already listed at line {}", id, it->second));
    lines.emplace(id, r.line);
    out.emplace(id, Hole{f, c.text(r, type)});
  }
  return out;
}

int sextant_of(double x, double y) {
  if (x == 0 && y == 0) return 1;
  double deg = std::atan2(y, x) * 180 / std::numbers::pi;
  if (deg < 0) deg += 360;
  return std::clamp(static_cast<int>(deg / 60) + 1, 1, kSextants);
}

enum PositionerColumn { p_id, p_hole, p_alpha_len, p_met_x, p_met_y, p_ap_x, p_ap_y, p_boss_x, p_boss_y, p_alpha_off, p_beta_off, p_dx, p_dy };

// The fibres the hole type names (metrology always) with their measured positions.
Result<void> read_fibres(const Columns& c, const Row& r, std::string_view type, RobotSite& s) {
  struct Pick {
    Fibre fibre;
    bool carried;
    std::size_t x;
  };
  const bool apogee = type.find("Apogee") != std::string_view::npos;
  const bool boss = type.find("Boss") != std::string_view::npos;
  for (const Pick& p : {Pick{Fibre::metrology, true, p_met_x}, Pick{Fibre::boss, boss, p_boss_x}, Pick{Fibre::apogee, apogee, p_ap_x}}) {
    if (!p.carried) continue;
    AXON_TRY(fx, c.number(r, p.x));
    AXON_TRY(fy, c.number(r, p.x + 1));
    s.fibres.push_back(p.fibre);
    s.fibre_offsets.push_back({p.fibre, fx, fy});
  }
  return ok();
}

Result<RobotSite> read_robot(const Columns& c, const Row& r, const std::map<std::string, Hole, std::less<>>& holes) {
  RobotSite s;
  AXON_TRY(id, c.id(r, p_id, 1, 2047));
  s.id = static_cast<std::uint16_t>(id);
  const auto hole = holes.find(c.text(r, p_hole));
  if (hole == holes.end()) return c.error(r, p_hole, fmt::format("hole '{}' is not in the wok table", c.text(r, p_hole)));
  const Frame& f = hole->second.frame;
  AXON_TRY(dx, c.number(r, p_dx));
  AXON_TRY(dy, c.number(r, p_dy));
  s.x_mm = f.x + dx * f.ix + dy * f.jx;
  s.y_mm = f.y + dx * f.iy + dy * f.jy;
  s.orientation_deg = std::atan2(f.iy, f.ix) * 180 / std::numbers::pi;
  AXON_TRY(alpha_len, c.number(r, p_alpha_len));
  if (!(alpha_len > 0)) return c.error(r, p_alpha_len, fmt::format("an arm length must be above 0, not {}", alpha_len));
  s.alpha_length_mm = alpha_len;
  AXON_TRY(alpha_off, c.number(r, p_alpha_off));
  AXON_TRY(beta_off, c.number(r, p_beta_off));
  s.offsets = ArmOffsets{alpha_off, beta_off};
  AXON_TRY(read_fibres(c, r, hole->second.type, s));
  s.sextant = sextant_of(s.x_mm, s.y_mm);
  s.bus = BusRef{static_cast<std::uint16_t>(s.sextant), 1};
  return s;
}

Result<std::vector<RobotSite>> read_robots(const Table& t, const std::map<std::string, Hole, std::less<>>& holes) {
  AXON_TRY(c, Columns::find(t, {"positionerID", "holeID", "alphaArmLen", "metX", "metY", "apX", "apY", "bossX", "bossY",
                                "alphaOffset", "betaOffset", "dx", "dy"}));
  std::vector<RobotSite> out;
  std::map<int, int> lines;
  for (const auto& r : t.rows) {
    AXON_TRY(s, read_robot(c, r, holes));
    if (auto it = lines.find(s.id); it != lines.end())
      return c.error(r, p_id, fmt::format("robot {} already listed at line {}", s.id, it->second));
    lines.emplace(s.id, r.line);
    out.push_back(std::move(s));
  }
  return out;
}

Result<std::vector<Fiducial>> read_fiducials(const Table& t) {
  AXON_TRY(c, Columns::find(t, {"id", "xWok", "yWok"}));
  std::vector<Fiducial> out;
  std::map<int, int> lines;
  for (const auto& r : t.rows) {
    AXON_TRY(id, c.id(r, 0, 0, 1000000));
    AXON_TRY(x, c.number(r, 1));
    AXON_TRY(y, c.number(r, 2));
    if (auto it = lines.find(id); it != lines.end())
      return c.error(r, 0, fmt::format("fiducial {} already listed at line {}", id, it->second));
    lines.emplace(id, r.line);
    out.push_back({id, x, y});
  }
  return out;
}

Result<std::vector<GuideCamera>> read_cameras(const Table& t, const CalibrationOptions& o) {
  AXON_TRY(c, Columns::find(t, {"id", "xWok", "yWok", "ix", "iy", "jx", "jy"}));
  std::vector<GuideCamera> out;
  std::map<int, int> lines;
  for (const auto& r : t.rows) {
    AXON_TRY(id, c.id(r, 0, 0, 1000000));
    AXON_TRY(f, read_frame(c, r, 1));
    if (auto it = lines.find(id); it != lines.end())
      return c.error(r, 0, fmt::format("guide camera {} already listed at line {}", id, it->second));
    lines.emplace(id, r.line);
    // The edge's middle lies `inset` along -j from the centre; it runs along i.
    const double mx = f.x - o.camera_inset_mm * f.jx, my = f.y - o.camera_inset_mm * f.jy;
    const double hx = o.camera_half_length_mm * f.ix, hy = o.camera_half_length_mm * f.iy;
    out.push_back({id, mx - hx, my - hy, mx + hx, my + hy, o.camera_buffer_mm});
  }
  return out;
}

Result<std::string> read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error(CoreErrc::io, fmt::format("cannot read the calibration table '{}'", path));
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

Result<FocalPlane> parse_calibration_tables(const CalibrationText& text, const CalibrationOptions& o) {
  AXON_TRY(wok, read_table(text.wok, text.wok_name));
  AXON_TRY(holes, read_holes(wok));
  AXON_TRY(positioners, read_table(text.positioners, text.positioners_name));
  AXON_TRY(robots, read_robots(positioners, holes));
  AXON_TRY(fid_table, read_table(text.fiducials, text.fiducials_name));
  AXON_TRY(fiducials, read_fiducials(fid_table));
  AXON_TRY(cam_table, read_table(text.guide_cameras, text.guide_cameras_name));
  AXON_TRY(cameras, read_cameras(cam_table, o));

  FocalPlaneSpec spec;
  spec.name = o.name.empty() ? "calibration" : o.name;
  spec.pitch_mm = o.pitch_mm;
  spec.neighbours.adjacent_radius_mm = o.pitch_mm * 1.1;
  spec.arms = o.arms;
  for (int k = 1; k <= kSextants; ++k) spec.gateways.push_back(GatewaySite{static_cast<std::uint16_t>(k), "", k, kMaxGatewayChannels});
  spec.robots = std::move(robots);
  spec.fiducials = std::move(fiducials);
  spec.guide_cameras = std::move(cameras);
  auto plane = FocalPlane::build(std::move(spec));
  if (!plane) return Error(plane.error().code, fmt::format("calibration tables ({}): {}", text.positioners_name, plane.error().detail));
  return plane;
}

Result<FocalPlane> load_calibration_dir(const std::string& dir, const CalibrationOptions& options) {
  namespace fs = std::filesystem;
  const fs::path d(dir);
  CalibrationText t;
  t.positioners_name = (d / "positionerTable.csv").string();
  t.wok_name = (d / "wokCoords.csv").string();
  t.fiducials_name = (d / "fiducialCoords.csv").string();
  t.guide_cameras_name = (d / "gfaCoords.csv").string();
  AXON_TRY(p, read_file(t.positioners_name));
  AXON_TRY(w, read_file(t.wok_name));
  AXON_TRY(f, read_file(t.fiducials_name));
  AXON_TRY(g, read_file(t.guide_cameras_name));
  t.positioners = p;
  t.wok = w;
  t.fiducials = f;
  t.guide_cameras = g;
  CalibrationOptions o = options;
  if (o.name.empty()) o.name = fs::absolute(d).lexically_normal().filename().string();
  if (o.name.empty()) o.name = fs::absolute(d).lexically_normal().parent_path().filename().string();
  return parse_calibration_tables(t, o);
}

bool is_calibration_dir(const std::string& dir) {
  std::error_code ec;
  return std::filesystem::is_directory(dir, ec) && std::filesystem::is_regular_file(std::filesystem::path(dir) / "positionerTable.csv", ec);
}

}  // namespace axon::fps
