#include "axon/fps/plan/targets.hpp"

#include "axon/core/header_table.hpp"
#include "axon/fps/plan/error.hpp"
#include "axon/core/text.hpp"

#include "axon/core/config.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

namespace axon::fps::plan {

namespace {

Error file_error(const std::string& name, int line, std::string_view what) {
  return make_error(PlanErrc::bad_target_file, fmt::format("{}:{}: {}", name, line, what));
}

std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return std::tolower(c); });
  return out;
}

std::optional<Elbow> parse_elbow(std::string_view s) {
  const std::string l = lower(s);
  if (l == "ccw") return Elbow::ccw;
  if (l == "cw") return Elbow::cw;
  return std::nullopt;
}

// A target's fields as read, checked for the combinations that make sense.
struct Fields {
  std::optional<std::int64_t> robot;
  std::optional<double> alpha, beta, x, y;
  std::optional<std::string> fibre, elbow;
};

Result<Target> make_target(const Fields& f, const std::string& name, int line) {
  if (!f.robot) return file_error(name, line, "missing robot id");
  if (*f.robot < 1 || *f.robot > 2047)
    return file_error(name, line, fmt::format("robot id {} out of range 1..2047", *f.robot));
  Target t;
  t.robot = static_cast<std::int32_t>(*f.robot);
  t.line = line;
  const bool has_pose = f.alpha || f.beta;
  const bool has_xy = f.x || f.y;
  if (has_pose == has_xy)
    return file_error(name, line, "give either alpha and beta, or x and y (exactly one of the two)");
  if (has_pose) {
    if (!f.alpha || !f.beta) return file_error(name, line, "alpha and beta go together");
    if (f.fibre || f.elbow) return file_error(name, line, "fibre and elbow only apply to x/y targets");
    t.pose = Pose{*f.alpha, *f.beta};
  } else {
    if (!f.x || !f.y) return file_error(name, line, "x and y go together");
    t.position = Vec2{*f.x, *f.y};
    if (f.fibre) t.fibre = *f.fibre;
    if (f.elbow) {
      t.elbow = parse_elbow(*f.elbow);
      if (!t.elbow) return file_error(name, line, fmt::format("elbow '{}': expected ccw or cw", *f.elbow));
    }
  }
  for (const auto& v : {f.alpha, f.beta, f.x, f.y})
    if (v && !std::isfinite(*v)) return file_error(name, line, "non-finite number");
  return t;
}

}  // namespace

Result<std::vector<Target>> parse_targets_yaml(std::string_view text, const std::string& name) {
  auto wrap = [](const Error& e) { return make_error(PlanErrc::bad_target_file, e.message()); };
  auto root = core::ConfigNode::load_string(text, name);
  if (!root) return wrap(root.error());
  if (!root.value().is_map()) return file_error(name, 1, "expected a map with a 'targets' list");
  if (auto r = root.value().reject_unknown({"targets"}); !r) return wrap(r.error());
  auto list = root.value().child("targets");
  if (!list) return wrap(list.error());
  auto items = list.value().items();
  if (!items) return wrap(items.error());
  std::vector<Target> out;
  for (const auto& item : items.value()) {
    if (!item.is_map()) return file_error(name, item.line(), "each target is a map");
    if (auto r = item.reject_unknown({"robot", "alpha", "beta", "x", "y", "fibre", "fiber", "elbow"}); !r)
      return wrap(r.error());
    Fields f;
    auto num = [&](std::string_view key, std::optional<double>& into) -> Result<void> {
      if (!item.has(key)) return ok();
      AXON_TRY(v, item.get<double>(key));
      into = v;
      return ok();
    };
    auto all = [&]() -> Result<void> {
      AXON_TRY(r, item.get<std::int64_t>("robot"));
      f.robot = r;
      AXON_TRY(num("alpha", f.alpha));
      AXON_TRY(num("beta", f.beta));
      AXON_TRY(num("x", f.x));
      AXON_TRY(num("y", f.y));
      for (const char* key : {"fibre", "fiber"})
        if (item.has(key)) {
          AXON_TRY(s, item.get<std::string>(key));
          f.fibre = s;
        }
      if (item.has("elbow")) {
        AXON_TRY(s, item.get<std::string>("elbow"));
        f.elbow = s;
      }
      return ok();
    }();
    if (!all) return wrap(all.error());
    AXON_TRY(t, make_target(f, name, item.line()));
    out.push_back(std::move(t));
  }
  return out;
}

Result<std::vector<Target>> parse_targets_csv(std::string_view text, const std::string& name) {
  enum Field { robot, alpha, beta, x, y, fibre, elbow };
  static constexpr core::TableColumn kColumns[] = {{"robot", robot}, {"alpha", alpha}, {"beta", beta},
                                                   {"x", x},         {"y", y},         {"fibre", fibre},
                                                   {"fiber", fibre}, {"elbow", elbow}};
  static constexpr int kRequired[] = {robot};
  core::HeaderTable table(text, kColumns, kRequired);
  std::vector<Target> out;
  while (table.next()) {
    const int line_no = table.line();
    Fields f;
    if (const auto c = table.cell(robot); !c.empty()) {
      f.robot = core::parse_number<std::int64_t>(c);
      if (!f.robot) return file_error(name, line_no, fmt::format("robot id '{}' is not an integer", c));
    }
    for (auto [field, slot] : {std::pair{alpha, &f.alpha}, std::pair{beta, &f.beta}, std::pair{x, &f.x}, std::pair{y, &f.y}}) {
      const auto c = table.cell(field);
      if (c.empty()) continue;
      *slot = core::parse_number<double>(c);
      if (!*slot) return file_error(name, line_no, fmt::format("'{}' is not a number", c));
    }
    if (const auto c = table.cell(fibre); !c.empty()) f.fibre = std::string(c);
    if (const auto c = table.cell(elbow); !c.empty()) f.elbow = std::string(c);
    AXON_TRY(t, make_target(f, name, line_no));
    out.push_back(std::move(t));
  }
  if (const auto& e = table.error()) return file_error(name, e->line, e->message);
  if (!table.header_seen()) return file_error(name, table.line(), "no header line");
  return out;
}

Result<std::vector<Target>> load_targets(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return make_error(PlanErrc::bad_target_file, fmt::format("{}: cannot open", path));
  std::ostringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  const std::string l = lower(path);
  auto ends = [&](std::string_view s) { return l.size() >= s.size() && l.compare(l.size() - s.size(), s.size(), s) == 0; };
  if (ends(".csv")) return parse_targets_csv(text, path);
  if (ends(".yaml") || ends(".yml")) return parse_targets_yaml(text, path);
  return make_error(PlanErrc::bad_target_file, fmt::format("{}: unknown extension (expected .yaml, .yml or .csv)", path));
}

std::string_view to_string(RobotOutcome::Status s) noexcept {
  switch (s) {
    case RobotOutcome::Status::ok:
      return "ok";
    case RobotOutcome::Status::untargeted:
      return "untargeted";
    case RobotOutcome::Status::parked:
      return "parked";
    case RobotOutcome::Status::rejected:
      return "rejected";
  }
  return "?";
}

bool TargetValidation::ok() const noexcept {
  return errors.empty() && std::none_of(robots.begin(), robots.end(), [](const RobotOutcome& r) {
           return r.status == RobotOutcome::Status::rejected;
         });
}

std::string TargetValidation::summary() const {
  std::string s;
  for (const auto& e : errors) s += e.message() + "\n";
  for (const auto& r : robots)
    if (r.issue) s += fmt::format("robot {}: {}: {}\n", r.robot, to_string(r.status), r.issue->message());
  return s;
}

std::vector<Pose> TargetValidation::poses() const {
  std::vector<Pose> p;
  p.reserve(robots.size());
  for (const auto& r : robots) p.push_back(r.pose);
  return p;
}

namespace {

// Resolve one target to a pose, or the reason it cannot be.
Result<Pose> resolve(const Positioner& robot, const ArmDesign& design, const Target& t) {
  if (t.pose) {
    if (!robot.within_limits(*t.pose))
      return make_error(PlanErrc::outside_hard_stops,
                        fmt::format("alpha {} beta {} deg outside alpha {}..{}, beta {}..{}", t.pose->alpha_deg,
                                    t.pose->beta_deg, robot.limits().alpha_min_deg, robot.limits().alpha_max_deg,
                                    robot.limits().beta_min_deg, robot.limits().beta_max_deg));
    return *t.pose;
  }
  const auto fibre = design.fibre_index(t.fibre);
  if (!fibre) return make_error(PlanErrc::unknown_fibre, fmt::format("fibre '{}'", t.fibre));
  if (t.elbow) return robot.inverse(*t.position, *fibre, *t.elbow);
  const IkSolutions s = robot.inverse(*t.position, *fibre);
  if (s.ok[0]) return s.pose[0];
  return robot.inverse(*t.position, *fibre, Elbow::cw);  // the cw pose or the reason neither works
}

std::string contact_text(const CollisionModel& m, const Contact& c) {
  if (c.kind == Contact::Kind::robot)
    return fmt::format("with robot {} (clearance {:.3f} mm)", m.robot(c.b).id(), c.clearance_mm);
  return fmt::format("with {} (clearance {:.3f} mm)", m.obstacles()[c.b].name, c.clearance_mm);
}

}  // namespace

TargetValidation validate_targets(const CollisionModel& model, std::span<const Target> targets,
                                  const ValidationOptions& options) {
  using Status = RobotOutcome::Status;
  TargetValidation v;
  const std::size_t n = model.size();
  v.robots.resize(n);
  std::vector<int> order(n, -1);  // position in the target list, to park later targets first
  for (std::size_t i = 0; i < n; ++i) v.robots[i] = {model.robot(i).id(), Status::untargeted, options.park, {}};

  auto fail = [&](std::size_t i, Error e) {
    RobotOutcome& r = v.robots[i];
    r.pose = options.park;
    r.status = options.policy == TargetPolicy::park ? Status::parked : Status::rejected;
    r.issue = std::move(e);
  };

  for (std::size_t k = 0; k < targets.size(); ++k) {
    const Target& t = targets[k];
    const auto idx = model.index_of(t.robot);
    const std::string where = t.line ? fmt::format("target line {}: ", t.line) : std::string{};
    if (!idx) {
      v.errors.push_back(make_error(PlanErrc::unknown_robot, fmt::format("{}robot {}", where, t.robot)));
      continue;
    }
    if (order[*idx] >= 0) {
      v.errors.push_back(make_error(PlanErrc::duplicate_target, fmt::format("{}robot {}", where, t.robot)));
      continue;
    }
    order[*idx] = static_cast<int>(k);
    auto pose = resolve(model.robot(*idx), model.design(), t);
    if (!pose) {
      fail(*idx, Error(pose.error().code, where + pose.error().detail));
      continue;
    }
    v.robots[*idx].status = Status::ok;
    v.robots[*idx].pose = pose.value();
  }
  if (!options.check_collisions) return v;

  std::vector<Pose> poses(n);
  std::vector<Segment> segs(n);
  std::vector<Contact> contacts;
  std::vector<char> touched(n);
  auto flip = [](const Contact& c) { return Contact{c.kind, c.b, c.a, c.clearance_mm}; };
  auto code_of = [](const Contact& c) {
    return c.kind == Contact::Kind::robot ? PlanErrc::robot_collision : PlanErrc::obstacle_collision;
  };
  // A robot that collides at the park pose (or untargeted): nothing left to give way.
  auto stuck = [&](std::size_t i, const Contact& seen) {
    RobotOutcome& r = v.robots[i];
    if (r.status == Status::rejected) return;
    r.issue = make_error(code_of(seen), "at the park pose " + contact_text(model, seen));
    r.status = Status::rejected;
  };

  if (options.policy == TargetPolicy::reject) {
    for (std::size_t i = 0; i < n; ++i) poses[i] = v.robots[i].pose;
    model.segments(poses, segs);
    model.find_contacts(segs, contacts);
    auto reject = [&](std::size_t i, const Contact& seen) {
      RobotOutcome& r = v.robots[i];
      if (r.status == Status::ok) {
        r.status = Status::rejected;
        r.issue = make_error(code_of(seen), contact_text(model, seen));
      }
    };
    for (const Contact& c : contacts) {
      const bool a_live = v.robots[c.a].status == Status::ok;
      const bool b_live = c.kind == Contact::Kind::robot && v.robots[c.b].status == Status::ok;
      if (a_live) reject(c.a, c);
      if (b_live) reject(c.b, flip(c));
      if (!a_live && !b_live) {
        stuck(c.a, c);
        if (c.kind == Contact::Kind::robot) stuck(c.b, flip(c));
      }
    }
    for (auto& r : v.robots)
      if (r.status == Status::rejected) r.pose = options.park;
    return v;
  }

  // Park policy: each round parks at least one more robot or stops, so n + 1 rounds suffice.
  for (std::size_t round = 0; round <= n; ++round) {
    for (std::size_t i = 0; i < n; ++i) poses[i] = v.robots[i].pose;
    model.segments(poses, segs);
    model.find_contacts(segs, contacts);
    std::fill(touched.begin(), touched.end(), 0);
    bool changed = false;
    for (const Contact& c : contacts) {
      const bool robot = c.kind == Contact::Kind::robot;
      if (touched[c.a] || (robot && touched[c.b])) continue;  // moved this round: look again next round
      const bool a_live = v.robots[c.a].status == Status::ok;
      const bool b_live = robot && v.robots[c.b].status == Status::ok;
      if (!a_live && !b_live) {
        stuck(c.a, c);
        if (robot) stuck(c.b, flip(c));
        continue;
      }
      // The robot that gives way: the live one; of two live ones, the one listed later.
      const bool park_b = b_live && (!a_live || order[c.b] > order[c.a]);
      const std::size_t loser = park_b ? c.b : c.a;
      fail(loser, make_error(code_of(c), contact_text(model, park_b ? flip(c) : c)));
      touched[loser] = 1;
      changed = true;
    }
    if (!changed) break;
  }
  return v;
}

Result<TargetValidation> usable_targets(const CollisionModel& model, std::span<const Target> targets, TargetPolicy policy) {
  ValidationOptions vo;
  vo.policy = policy;
  TargetValidation v = validate_targets(model, targets, vo);
  if (!v.errors.empty() || (!v.ok() && policy == TargetPolicy::reject)) return Error(PlanErrc::bad_target_file, v.summary());
  return v;
}

Result<std::vector<Pose>> target_poses(const CollisionModel& model, std::span<const Target> targets, TargetPolicy policy,
                                       std::string* notes) {
  AXON_TRY(v, usable_targets(model, targets, policy));
  if (notes) *notes = v.summary();
  return v.poses();
}

}  // namespace axon::fps::plan
