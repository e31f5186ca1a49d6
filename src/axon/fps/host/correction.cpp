#include "axon/fps/host/correction.hpp"

#include "axon/core/header_table.hpp"
#include "axon/core/text.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <tuple>

namespace axon::fps::host {

namespace {

class CorrectionCategory final : public std::error_category {
 public:
  const char* name() const noexcept override { return "axon.fps.correction"; }
  std::string message(int c) const override {
    switch (static_cast<CorrectionErrc>(c)) {
      case CorrectionErrc::cannot_open:
        return "measurement file cannot be read";
      case CorrectionErrc::missing_column:
        return "measurement file lacks a column (the header needs robot, x and y)";
      case CorrectionErrc::unknown_column:
        return "measurement file names an unknown column (known: robot, x, y, fibre)";
      case CorrectionErrc::not_a_number:
        return "measurement file holds a value that is not a number";
      case CorrectionErrc::duplicate_robot:
        return "measurement file lists a robot twice";
      case CorrectionErrc::unknown_robot:
        return "measurement file names a robot that is not part of the focal plane";
    }
    return "unknown measurement error";
  }
};

Error at(CorrectionErrc code, const std::string& name, int line, std::string_view what) {
  return make_error(code, fmt::format("{}:{}: {}", name, line, what));
}

std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return std::tolower(c); });
  return out;
}

// Angle difference a - b brought into [-180, 180).
double angle_diff(double a, double b) noexcept {
  double d = std::fmod(a - b + 180.0, 360.0);
  if (d < 0) d += 360.0;
  return d - 180.0;
}

}  // namespace

const std::error_category& correction_category() noexcept {
  static const CorrectionCategory c;
  return c;
}

const Measurement* MeasurementSet::find(std::int32_t robot) const noexcept {
  for (const auto& m : items)
    if (m.robot == robot) return &m;
  return nullptr;
}

Result<MeasurementSet> parse_measurements_csv(std::string_view text, const std::string& name,
                                              std::span<const std::int32_t> known_robots) {
  enum Field { robot, x, y, fibre };
  static constexpr core::TableColumn kColumns[] = {{"robot", robot}, {"x", x}, {"y", y}, {"fibre", fibre}, {"fiber", fibre}};
  static constexpr int kRequired[] = {robot, x, y};
  const std::set<std::int32_t> known(known_robots.begin(), known_robots.end());
  std::set<std::int32_t> seen;
  MeasurementSet out;
  out.source = name;
  core::HeaderTable table(text, kColumns, kRequired);
  while (table.next()) {
    const int line_no = table.line();
    Measurement m;
    m.line = line_no;
    const auto id_text = table.cell(robot);
    const auto id = core::parse_number<std::int64_t>(id_text);
    if (!id) return at(CorrectionErrc::not_a_number, name, line_no, fmt::format("robot id '{}' is not an integer", id_text));
    if (*id < 1 || *id > 2047)
      return at(CorrectionErrc::unknown_robot, name, line_no, fmt::format("robot id {} out of range 1..2047", *id));
    m.robot = static_cast<std::int32_t>(*id);
    for (auto [field, slot, what] : {std::tuple{x, &m.position.x, "x"}, std::tuple{y, &m.position.y, "y"}}) {
      const auto c = table.cell(field);
      const auto v = core::parse_number<double>(c);
      if (!v || !std::isfinite(*v))
        return at(CorrectionErrc::not_a_number, name, line_no, fmt::format("{} '{}' is not a number", what, c));
      *slot = *v;
    }
    if (const auto c = table.cell(fibre); !c.empty()) m.fibre = std::string(c);
    if (!known.empty() && !known.contains(m.robot))
      return at(CorrectionErrc::unknown_robot, name, line_no,
                fmt::format("robot {} is not part of the focal plane", m.robot));
    if (!seen.insert(m.robot).second)
      return at(CorrectionErrc::duplicate_robot, name, line_no, fmt::format("robot {} measured twice", m.robot));
    out.items.push_back(std::move(m));
  }
  if (const auto& e = table.error()) {
    const bool naming = e->problem == core::TableProblem::unknown_column || e->problem == core::TableProblem::duplicate_column;
    const auto code = naming ? CorrectionErrc::unknown_column : CorrectionErrc::missing_column;
    return at(code, name, e->line, e->message);
  }
  if (!table.header_seen()) return at(CorrectionErrc::missing_column, name, table.line(), "no header line (robot,x,y)");
  return out;
}

Result<MeasurementSet> load_measurements(const std::string& path, std::span<const std::int32_t> known_robots) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return make_error(CorrectionErrc::cannot_open, fmt::format("{}: cannot open", path));
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) return make_error(CorrectionErrc::cannot_open, fmt::format("{}: cannot read", path));
  return parse_measurements_csv(ss.str(), path, known_robots);
}

std::string_view to_string(CorrectionStatus s) noexcept {
  switch (s) {
    case CorrectionStatus::within_tolerance:
      return "within tolerance";
    case CorrectionStatus::move:
      return "move";
    case CorrectionStatus::unreachable:
      return "unreachable";
    case CorrectionStatus::not_measured:
      return "not measured";
    case CorrectionStatus::no_position:
      return "no position";
  }
  return "?";
}

std::size_t CorrectionPlan::count(CorrectionStatus s) const noexcept {
  return static_cast<std::size_t>(
      std::count_if(robots.begin(), robots.end(), [s](const RobotCorrection& r) { return r.status == s; }));
}

double CorrectionPlan::worst_error_mm() const noexcept {
  double worst = 0;
  for (const auto& r : robots)
    if (r.measured) worst = std::max(worst, r.error_mm);
  return worst;
}

bool CorrectionPlan::converged() const noexcept {
  return !robots.empty() && count(CorrectionStatus::within_tolerance) == robots.size();
}

const RobotCorrection* CorrectionPlan::find(std::int32_t robot) const noexcept {
  for (const auto& r : robots)
    if (r.robot == robot) return &r;
  return nullptr;
}

std::map<std::int32_t, plan::Pose> CorrectionPlan::moves() const {
  std::map<std::int32_t, plan::Pose> out;
  for (const auto& r : robots)
    if (r.status == CorrectionStatus::move) out[r.robot] = r.command;
  return out;
}

Result<std::pair<plan::Vec2, std::size_t>> target_point(const plan::Positioner& robot, const plan::ArmDesign& design,
                                                        const plan::Target& t) {
  const auto fibre = design.fibre_index(t.fibre);
  if (!fibre) return make_error(plan::PlanErrc::unknown_fibre, fmt::format("fibre '{}'", t.fibre));
  if (t.position) return std::pair{*t.position, *fibre};
  return std::pair{robot.fibre(t.pose.value_or(plan::Pose{}), *fibre), *fibre};
}

plan::Elbow elbow_of(const plan::Positioner& robot, plan::Pose pose, std::size_t fibre) {
  // Solve for the fibre's own position and keep the branch that gives back the pose.
  const plan::IkSolutions s = robot.inverse(robot.fibre(pose, fibre), fibre);
  auto distance = [&](const plan::Pose& p) {
    return std::abs(angle_diff(p.alpha_deg, pose.alpha_deg)) + std::abs(angle_diff(p.beta_deg, pose.beta_deg));
  };
  return distance(s.pose[1]) < distance(s.pose[0]) ? plan::Elbow::cw : plan::Elbow::ccw;
}

CorrectionPlan plan_corrections(const plan::CollisionModel& model, std::span<const plan::Target> targets,
                                const MeasurementSet& measured, const std::map<std::int32_t, plan::Pose>& current,
                                const CorrectionOptions& options) {
  using S = CorrectionStatus;
  CorrectionPlan out;
  out.tolerance_mm = options.tolerance_mm;
  std::set<std::int32_t> targeted;
  for (const plan::Target& t : targets) {
    RobotCorrection r;
    r.robot = t.robot;
    r.fibre = t.fibre;
    targeted.insert(t.robot);
    const auto index = model.index_of(t.robot);
    if (!index) {
      r.status = S::unreachable;
      r.detail = "not part of the focal plane";
      out.robots.push_back(std::move(r));
      continue;
    }
    const plan::Positioner& robot = model.robot(*index);
    auto point = target_point(robot, model.design(), t);
    if (!point) {
      r.status = S::unreachable;
      r.detail = point.error().message();
      out.robots.push_back(std::move(r));
      continue;
    }
    r.target = point.value().first;
    const std::size_t fibre = point.value().second;
    const Measurement* m = measured.find(t.robot);
    if (const auto c = current.find(t.robot); c != current.end()) r.current = c->second;
    if (!m) {
      r.status = S::not_measured;
      r.detail = fmt::format("not in {}", measured.source);
      out.robots.push_back(std::move(r));
      continue;
    }
    r.measured = m->position;
    r.error = m->position - r.target;
    r.error_mm = plan::norm(r.error);
    if (m->fibre && lower(*m->fibre) != lower(t.fibre)) {
      r.status = S::unreachable;
      r.detail = fmt::format("{}:{}: measured fibre '{}' but the target is for '{}'", measured.source, m->line,
                             *m->fibre, t.fibre);
      out.robots.push_back(std::move(r));
      continue;
    }
    if (r.error_mm <= options.tolerance_mm) {
      r.status = S::within_tolerance;
      out.robots.push_back(std::move(r));
      continue;
    }
    if (!r.current) {
      r.status = S::no_position;
      r.detail = "its current angles are unknown";
      out.robots.push_back(std::move(r));
      continue;
    }
    r.elbow = elbow_of(robot, *r.current, fibre);
    auto want = robot.inverse(r.target, fibre, r.elbow);
    auto got = robot.inverse(m->position, fibre, r.elbow);
    if (!want || !got) {
      r.status = S::unreachable;
      r.detail = fmt::format("{} point: {}", !want ? "target" : "measured", (!want ? want : got).error().message());
      out.robots.push_back(std::move(r));
      continue;
    }
    r.delta = {angle_diff(want.value().alpha_deg, got.value().alpha_deg),
               angle_diff(want.value().beta_deg, got.value().beta_deg)};
    r.command = {r.current->alpha_deg + r.delta.alpha_deg, r.current->beta_deg + r.delta.beta_deg};
    if (std::max(std::abs(r.delta.alpha_deg), std::abs(r.delta.beta_deg)) > options.max_correction_deg) {
      r.status = S::unreachable;
      r.detail = fmt::format("correction alpha {:+.4f} beta {:+.4f} deg exceeds {} deg (wrong fibre identified?)",
                             r.delta.alpha_deg, r.delta.beta_deg, options.max_correction_deg);
    } else if (!robot.within_limits(r.command)) {
      r.status = S::unreachable;
      r.detail = fmt::format("new command alpha {:.4f} beta {:.4f} deg outside the angle limits", r.command.alpha_deg,
                             r.command.beta_deg);
    } else {
      r.status = S::move;
    }
    out.robots.push_back(std::move(r));
  }
  for (const auto& m : measured.items)
    if (!targeted.contains(m.robot))
      out.notes.push_back(fmt::format("{}:{}: robot {} has no target; left alone", measured.source, m.line, m.robot));
  return out;
}

}  // namespace axon::fps::host
