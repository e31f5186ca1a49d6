#include "axon/fps/host/troubleshoot.hpp"
#include "axon/core/clock.hpp"
#include "axon/fps/plan/arm_name.hpp"

#include "axon/fps/host/concurrent.hpp"
#include "axon/fps/host/datum_check.hpp"
#include "axon/fps/plan/stop_sweep.hpp"

#include <fmt/chrono.h>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace axon::fps::host {

namespace asio = boost::asio;
using protocol::CommandId;

namespace {

char arm_letter(Arm a) noexcept { return a == Arm::alpha ? 'a' : 'b'; }

std::string now_utc() {
  return fmt::format("{:%Y-%m-%dT%H:%M:%SZ}", std::chrono::floor<std::chrono::seconds>(std::chrono::system_clock::now()));
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

ArmAngles one_arm(Arm arm, double deg) { return arm == Arm::alpha ? ArmAngles{deg, 0} : ArmAngles{0, deg}; }

}  // namespace

const char* to_string(FrictionVerdict v) noexcept {
  switch (v) {
    case FrictionVerdict::ok: return "ok";
    case FrictionVerdict::increased: return "increased";
    case FrictionVerdict::baseline: return "baseline";
    case FrictionVerdict::failed: return "failed";
  }
  return "?";
}

const char* to_string(HallVerdict v) noexcept {
  switch (v) {
    case HallVerdict::ok: return "ok";
    case HallVerdict::no_hall_change: return "no_hall_change";
    case HallVerdict::inaccurate: return "inaccurate";
    case HallVerdict::failed: return "failed";
  }
  return "?";
}

// ---- friction: the pure parts ---------------------------------------------------------------------

std::optional<FrictionFit> fit_friction(std::span<const FrictionPoint> points) {
  const double n = static_cast<double>(points.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (const auto& p : points) {
    const double x = p.speed_rpm / 1000.0;
    sx += x;
    sy += p.current_percent;
    sxx += x * x;
    sxy += x * p.current_percent;
  }
  const double det = n * sxx - sx * sx;
  if (points.size() < 2 || std::abs(det) < 1e-12) return std::nullopt;
  FrictionFit f;
  f.viscous_percent_per_krpm = (n * sxy - sx * sy) / det;
  f.stiction_percent = (sy - f.viscous_percent_per_krpm * sx) / n;
  double ss = 0;
  for (const auto& p : points) ss += std::pow(p.current_percent - f.at(p.speed_rpm), 2);
  f.rms_percent = std::sqrt(ss / n);
  return f;
}

FrictionFinding judge_friction(FrictionFinding m, std::span<const FrictionRecord> history, const FrictionOptions& o) {
  if (!m.fit) {
    m.verdict = FrictionVerdict::failed;
    if (m.problem.empty()) {
      m.problem = "fewer than two speeds gave readings during the test moves";
      m.advice = "use a larger step or lower speeds";
    }
    return m;
  }
  for (const auto& r : history)
    if (r.id == m.id && r.arm == m.arm && (!m.baseline || r.time_utc < m.baseline->time_utc)) m.baseline = r;
  if (!m.baseline) {
    m.verdict = FrictionVerdict::baseline;
    return m;
  }
  const double ref = o.reference_rpm;
  const double before = m.baseline->fit.at(ref);
  m.growth = before > 0 ? m.fit->at(ref) / before - 1.0 : 0.0;
  m.move_growth = m.baseline->move_ratio > 0 && m.move_ratio > 0 ? m.move_ratio / m.baseline->move_ratio - 1.0 : 0.0;
  const bool current_up = m.growth > o.growth_limit;
  const bool slower = m.move_growth > o.growth_limit;
  m.verdict = current_up || slower ? FrictionVerdict::increased : FrictionVerdict::ok;
  if (m.verdict == FrictionVerdict::increased) {
    const std::string what =
        current_up ? fmt::format("current at {:g} rpm {:.1f} % against {:.1f} % on {} (+{:.0f} %)", ref, m.fit->at(ref),
                                 before, m.baseline->time_utc, 100 * m.growth)
                   : fmt::format("test moves {:.0f} % slower than on {}", 100 * m.move_growth, m.baseline->time_utc);
    m.advice = fmt::format(
        "{}: more friction in the gear. If it reports collisions it did not have, raise its collision margin "
        "(SET_COLLISION_MARGIN, 111; defaults alpha -5, beta 20, at most 30; lost at power-off, so send it after every "
        "power cycle), clear the flags and move it; below 0 C keep the motor speed at 2000-3000 rpm (document 10)",
        what);
  }
  return m;
}

bool FrictionReport::ok() const noexcept {
  return std::none_of(arms.begin(), arms.end(), [](const FrictionFinding& f) {
    return f.verdict == FrictionVerdict::increased || f.verdict == FrictionVerdict::failed;
  });
}

std::vector<FrictionRecord> FrictionReport::records() const {
  std::vector<FrictionRecord> out;
  for (const auto& f : arms)
    if (f.fit) out.push_back({time_utc, f.id, f.arm, *f.fit, f.move_ratio});
  return out;
}

std::string FrictionReport::summary() const {
  std::string s;
  for (const auto& f : arms) {
    s += fmt::format("robot {} {}: {}", f.id, arm_name(f.arm), to_string(f.verdict));
    if (f.fit)
      s += fmt::format(", stiction {:.1f} % + {:.2f} %/krpm (rms {:.2f} %)", f.fit->stiction_percent,
                       f.fit->viscous_percent_per_krpm, f.fit->rms_percent);
    if (f.baseline) s += fmt::format(", {:+.0f} % since {}", 100 * f.growth, f.baseline->time_utc);
    if (!f.problem.empty()) s += ": " + f.problem;
    s += "\n";
    if (!f.advice.empty()) s += "  " + f.advice + "\n";
  }
  return s;
}

// ---- test moves -------------------------------------------------------------------------------

asio::awaitable<Result<double>> clear_test_step(Array& array, const plan::CollisionModel& model, std::uint16_t id,
                                                Arm arm, double step_deg) {
  if (auto admitted = array.admit_all(CommandId::go_to_relative_position, {id}); !admitted) co_return admitted.error();
  const auto index = model.index_of(id);
  if (!index) co_return Error(HostErrc::unknown_positioner, fmt::format("robot {} is not in the layout", id));
  auto read = co_await read_poses_around(array, model, *index, fmt::format("test move of robot {}", id));
  if (!read) co_return read.error();
  const auto& poses = read.value();
  const double from = arm == Arm::alpha ? poses[*index].alpha_deg : poses[*index].beta_deg;
  std::vector<std::string> blocked;
  for (const double step : {step_deg, -step_deg}) {
    const auto sweep = plan::check_arm_sweep(model, *index, poses, arm_letter(arm), from + step);
    if (sweep.clear) co_return step;
    blocked.push_back(fmt::format("{:+g} deg: {}", step, fmt::join(sweep.in_the_way, ", ")));
  }
  co_return Error(HostErrc::not_ready, fmt::format("no room for a test move of robot {} {} from {:.1f} deg ({})", id,
                                                   to_string(arm), from, fmt::join(blocked, "; ")));
}

namespace {

// A relative move of one arm, with the arm's position and current read while it is between 10 %
// and 90 % of the way; the readings' currents are added to `currents`. Returns the robot's ETA.
asio::awaitable<Result<double>> sampled_move(Positioner& p, Arm arm, double step, std::vector<double>& currents) {
  auto start = co_await p.read_position();
  if (!start) co_return start.error();
  const double from = arm == Arm::alpha ? start.value().alpha : start.value().beta;
  auto eta = co_await p.start_goto(one_arm(arm, step), true);
  if (!eta) co_return eta.error();
  const double eta_s = arm == Arm::alpha ? eta.value().alpha.seconds() : eta.value().beta.seconds();
  const auto timeout = std::chrono::duration_cast<core::Duration>(std::chrono::duration<double>(eta_s)) + p.options().move_margin;
  const auto until = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    auto r = co_await p.read_position_and_current(arm);
    if (!r) break;  // the wait below says what is wrong
    const double f = (r.value().position.degrees() - from) / step;
    if (f > 0.1 && f < 0.9) currents.push_back(std::abs(static_cast<double>(r.value().value)));
    if (f >= 0.9 || std::chrono::steady_clock::now() > until) break;
  }
  auto idle = co_await p.wait_until_idle(timeout);
  if (!idle) {
    if (idle.error() != HostErrc::collision) {  // never leave it moving unwatched
      if (auto aborted = co_await p.abort(); !aborted)
        co_return Error(idle.error().code,
                        idle.error().detail + "; TRAJECTORY_ABORT was not acknowledged: " + aborted.error().message());
    }
    co_return idle.error();
  }
  co_return eta_s;
}

// One arm at every speed: there and back at each.
asio::awaitable<FrictionFinding> measure_arm(Array& array, const plan::CollisionModel& model, Positioner& p, Arm arm,
                                             const FrictionOptions& o) {
  FrictionFinding f;
  f.id = p.id();
  f.arm = arm_letter(arm);
  auto step = co_await clear_test_step(array, model, p.id(), arm, o.step_deg);
  if (!step) {
    f.problem = step.error().message();
    co_return f;
  }
  f.step_deg = step.value();
  double moved_s = 0, announced_s = 0;
  for (const double rpm : o.speeds_rpm) {
    const auto r = static_cast<std::int64_t>(std::lround(rpm));
    if (auto s = co_await p.set_speed(r, r); !s) {
      f.problem = fmt::format("SET_SPEED {:g} rpm: {}", rpm, s.error().message());
      break;
    }
    std::vector<double> currents;
    FrictionPoint point{rpm};
    const auto t0 = std::chrono::steady_clock::now();
    for (const double d : {f.step_deg, -f.step_deg}) {
      auto m = co_await sampled_move(p, arm, d, currents);
      if (!m) {
        f.problem = fmt::format("test move at {:g} rpm: {}", rpm, m.error().message());
        break;
      }
      point.eta_s += m.value();
    }
    if (!f.problem.empty()) break;
    point.move_s = core::seconds_since(t0);
    point.readings = static_cast<int>(currents.size());
    if (currents.empty()) continue;
    point.current_percent = median(currents);
    moved_s += point.move_s;
    announced_s += point.eta_s;
    f.points.push_back(point);
  }
  if (auto restored = co_await p.set_speed(o.restore_speed_rpm, o.restore_speed_rpm); !restored && f.problem.empty())
    f.problem = fmt::format("the speed was not set back to {} rpm: {}", o.restore_speed_rpm, restored.error().message());
  if (f.problem.empty()) f.fit = fit_friction(f.points);
  f.move_ratio = announced_s > 0 ? moved_s / announced_s : 0;
  if (!f.problem.empty() && array.locked())
    f.advice = "not measured: the array locked; after a collision, unlock and back the robot off (backoff) first";
  co_return f;
}

// Robots in rounds: no two robots of a round are neighbours, so one's test moves cannot meet the
// other's arms (each sweep is proven against the neighbours standing still).
std::vector<std::vector<std::uint16_t>> rounds_of(const plan::CollisionModel& model, const std::vector<std::uint16_t>& ids) {
  std::vector<std::vector<std::uint16_t>> rounds;
  std::vector<std::set<std::size_t>> members;
  for (const auto id : ids) {
    const auto i = model.index_of(id);
    std::size_t k = 0;
    if (i) {
      const auto nb = model.neighbours(*i);
      while (k < members.size() &&
             std::any_of(nb.begin(), nb.end(), [&](auto j) { return members[k].contains(static_cast<std::size_t>(j)); }))
        ++k;
    }
    if (k == rounds.size()) {
      rounds.emplace_back();
      members.emplace_back();
    }
    rounds[k].push_back(id);
    if (i) members[k].insert(*i);
  }
  return rounds;
}

Result<void> check_options(const FrictionOptions& o) {
  std::set<double> speeds(o.speeds_rpm.begin(), o.speeds_rpm.end());
  if (speeds.size() < 2) return Error(HostErrc::invalid_argument, "the friction fit needs at least two different speeds");
  for (const double s : speeds)
    if (!(s >= 1 && s <= 10000)) return Error(HostErrc::invalid_argument, fmt::format("speed {:g} rpm: use 1..10000", s));
  if (!(o.step_deg > 2 && o.step_deg <= 45))
    return Error(HostErrc::invalid_argument, "the test move must be above 2 deg (the precise approach) and at most 45 deg");
  if (!(o.growth_limit > 0) || !(o.reference_rpm > 0))
    return Error(HostErrc::invalid_argument, "growth limit and reference speed must be positive");
  return ok();
}

}  // namespace

asio::awaitable<Result<FrictionReport>> friction_survey(Array& array, const plan::CollisionModel& model,
                                                        std::vector<std::uint16_t> ids, FrictionOptions o) {
  if (auto c = check_options(o); !c) co_return c.error();
  if (ids.empty())
    for (const auto id : array.ids())
      if (model.index_of(id)) ids.push_back(id);
  if (auto admitted = array.admit_all(CommandId::go_to_relative_position, ids); !admitted) co_return admitted.error();
  if (o.time_utc.empty()) o.time_utc = now_utc();
  std::map<std::uint16_t, std::vector<FrictionFinding>> found;
  for (const auto& round : rounds_of(model, ids)) {
    co_await for_each_concurrently(round.size(), [&](std::size_t k) -> asio::awaitable<void> {
      const auto id = round[k];
      auto& out = found[id];
      auto p = array.positioner(id);
      for (const Arm arm : {Arm::alpha, Arm::beta}) {
        if ((arm == Arm::alpha && !o.alpha) || (arm == Arm::beta && !o.beta)) continue;
        FrictionFinding f;
        if (!p) {
          f.id = id;
          f.arm = arm_letter(arm);
          f.problem = p.error().message();
        } else {
          f = co_await measure_arm(array, model, *p.value(), arm, o);
        }
        out.push_back(judge_friction(std::move(f), o.history, o));
      }
    });
  }
  FrictionReport report;
  report.time_utc = o.time_utc;
  for (const auto id : ids)
    for (auto& f : found[id]) report.arms.push_back(std::move(f));
  co_return report;
}

// ---- hall test --------------------------------------------------------------------------------

bool HallTestReport::ok() const noexcept {
  return !arms.empty() && std::all_of(arms.begin(), arms.end(), [](const HallFinding& f) { return f.verdict == HallVerdict::ok; });
}

std::string HallTestReport::summary() const {
  std::string s;
  for (const auto& f : arms) {
    s += fmt::format("robot {} {}: {}", f.id, arm_name(f.arm), to_string(f.verdict));
    if (f.verdict != HallVerdict::failed)
      s += fmt::format(" (open-loop move {:+.1f} deg: position {:.3f} -> {:.3f}, hall {:.3f} -> {:.3f}, hall off by {:.3f} deg)",
                       f.step_deg, f.position_before_deg, f.position_after_deg, f.hall_before_deg, f.hall_after_deg,
                       f.tracking_error_deg);
    if (!f.problem.empty()) s += ": " + f.problem;
    if (!f.restored) s += " [NOT restored to closed loop with collision detection]";
    s += "\n";
    if (!f.advice.empty()) s += "  " + f.advice + "\n";
  }
  return s;
}

namespace {

double of(const ArmAngles& a, Arm arm) { return arm == Arm::alpha ? a.alpha : a.beta; }

// The readings and the open-loop move there and back; f.problem says what failed.
asio::awaitable<void> open_loop_probe(Positioner& p, Arm arm, const HallTestOptions& o, HallFinding& f) {
  auto failed = [&](std::string_view what, const auto& r) {
    if (!r) f.problem = fmt::format("{}: {}", what, r.error().message());
    return !r;
  };
  if (failed("SET_SPEED", co_await p.set_speed(o.speed_rpm, o.speed_rpm))) co_return;
  auto hall = co_await p.read_hall_position();
  auto pos = co_await p.read_position();
  if (failed("GET_HALL_POSITION", hall) || failed("GET_CURRENT_POSITION", pos)) co_return;
  f.hall_before_deg = of(hall.value(), arm);
  f.position_before_deg = of(pos.value(), arm);
  if (failed("the open-loop move", co_await p.goto_relative(one_arm(arm, f.step_deg)))) co_return;
  hall = co_await p.read_hall_position();
  pos = co_await p.read_position();
  if (failed("GET_HALL_POSITION after the move", hall) || failed("GET_CURRENT_POSITION after the move", pos)) co_return;
  f.hall_after_deg = of(hall.value(), arm);
  f.position_after_deg = of(pos.value(), arm);
  failed("the move back", co_await p.goto_relative(one_arm(arm, -f.step_deg)));
}

void judge_hall(HallFinding& f, const HallTestOptions& o) {
  const double moved = std::abs(f.position_after_deg - f.position_before_deg);
  const double hall_moved = std::abs(f.hall_after_deg - f.hall_before_deg);
  f.tracking_error_deg = std::abs(f.hall_after_deg - f.position_after_deg);
  if (hall_moved < 0.1 * moved) {
    f.verdict = HallVerdict::no_hall_change;
    f.advice = "the hall reading did not follow the move. If the arm turned, the hall sensor is faulty (most likely a "
               "sensor wire came loose); if it did not, the motor is (a loose motor cable, a failed h-bridge) or the "
               "friction is too high to move: look at the robot. With a faulty sensor the arm still works in open loop "
               "without collision detection (121 / 125), with no collision detection and more power";
  } else if (f.tracking_error_deg > o.tolerance_deg) {
    f.verdict = HallVerdict::inaccurate;
    f.advice = fmt::format("the hall reading ends {:.3f} deg from the position (more than {:g}): the sensor is suspect",
                           f.tracking_error_deg, o.tolerance_deg);
  } else {
    f.verdict = HallVerdict::ok;
    f.advice = "sensor and motor work. If collisions are still reported at the start of moves, the rotor may slip while "
               "idle: raise the holding current (SET_HOLDING_CURRENT, 112)";
  }
}

}  // namespace

asio::awaitable<Result<HallTestReport>> hall_test(Array& array, const plan::CollisionModel& model, std::uint16_t id,
                                                  HallTestOptions o) {
  if (!(o.step_deg > 0.5 && o.step_deg <= 45))
    co_return Error(HostErrc::invalid_argument, "the hall test move must be above 0.5 deg and at most 45 deg");
  if (!(o.tolerance_deg > 0)) co_return Error(HostErrc::invalid_argument, "the tracking tolerance must be positive");
  if (auto admitted = array.admit_all(CommandId::go_to_relative_position, {id}); !admitted) co_return admitted.error();
  if (!model.index_of(id)) co_return Error(HostErrc::unknown_positioner, fmt::format("robot {} is not in the layout", id));
  auto found = array.positioner(id);
  if (!found) co_return found.error();
  Positioner& p = *found.value();
  HallTestReport report;
  for (const Arm arm : {Arm::alpha, Arm::beta}) {
    if ((arm == Arm::alpha && !o.alpha) || (arm == Arm::beta && !o.beta)) continue;
    HallFinding f;
    f.id = id;
    f.arm = arm_letter(arm);
    auto step = co_await clear_test_step(array, model, id, arm, o.step_deg);
    if (step) f.step_deg = step.value();
    else f.problem = step.error().message();
    report.arms.push_back(std::move(f));
  }
  // Both arms in open loop without detection for the whole test: a move of one arm also makes the
  // other do its precise approach, which a broken sensor there would take for a collision.
  auto open = co_await p.set_loop(Arm::both, Loop::open, false);
  for (auto& f : report.arms) {
    if (!f.problem.empty()) continue;
    if (!open) f.problem = "open loop without collision detection: " + open.error().message();
    else co_await open_loop_probe(p, f.arm == 'a' ? Arm::alpha : Arm::beta, o, f);
  }
  // Whatever happened: closed loop with collision detection and the usual speed again.
  auto back = co_await p.set_loop(Arm::both, Loop::closed, true);
  auto speed = co_await p.set_speed(o.restore_speed_rpm, o.restore_speed_rpm);
  for (auto& f : report.arms) {
    f.restored = back.has_value() && speed.has_value();
    if (!back && f.problem.empty()) f.problem = "closed loop with collision detection not restored: " + back.error().message();
    if (f.problem.empty()) judge_hall(f, o);
  }
  co_return report;
}

// ---- the history file -----------------------------------------------------------------------------

namespace {
constexpr const char* kHeader = "time_utc,robot,arm,stiction_percent,viscous_percent_per_krpm,rms_percent,move_ratio";
}

Result<std::vector<FrictionRecord>> load_friction_history(const std::string& path) {
  std::ifstream in(path);
  std::vector<FrictionRecord> out;
  if (!in) return out;
  std::string line;
  int n = 0;
  auto bad = [&](std::string_view why) {
    return Error(CoreErrc::config_bad_value, fmt::format("{}:{}: {} (expected {})", path, n, why, kHeader));
  };
  while (std::getline(in, line)) {
    ++n;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line.rfind("time_utc,", 0) == 0) continue;
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
    if (cells.size() != 7) return bad(fmt::format("{} fields", cells.size()));
    FrictionRecord r;
    r.time_utc = cells[0];
    try {
      std::size_t used = 0;
      const unsigned long id = std::stoul(cells[1], &used);
      if (used != cells[1].size() || id < 1 || id > 2047) return bad("robot must be 1..2047");
      r.id = static_cast<std::uint16_t>(id);
      double* fields[] = {&r.fit.stiction_percent, &r.fit.viscous_percent_per_krpm, &r.fit.rms_percent, &r.move_ratio};
      for (int k = 0; k < 4; ++k) {
        *fields[k] = std::stod(cells[static_cast<std::size_t>(3 + k)], &used);
        if (used != cells[static_cast<std::size_t>(3 + k)].size() || !std::isfinite(*fields[k])) return bad("not a number");
      }
    } catch (const std::exception&) {
      return bad("not a number");
    }
    const auto arm = arm_from_name(cells[2]);
    if (!arm) return bad("arm must be alpha or beta");
    r.arm = *arm;
    if (r.time_utc.size() != 20 || r.time_utc.back() != 'Z') return bad("time_utc must look like 2026-12-02T03:04:05Z");
    out.push_back(std::move(r));
  }
  return out;
}

Result<void> append_friction_history(const std::string& path, const std::vector<FrictionRecord>& records) {
  const bool fresh = !std::ifstream(path).good();
  std::ofstream out(path, std::ios::app);
  if (!out) return Error(CoreErrc::invalid_argument, fmt::format("cannot write {}", path));
  if (fresh) out << kHeader << "\n";
  for (const auto& r : records)
    out << fmt::format("{},{},{},{:.3f},{:.4f},{:.3f},{:.4f}\n", r.time_utc, r.id, arm_name(r.arm), r.fit.stiction_percent,
                       r.fit.viscous_percent_per_krpm, r.fit.rms_percent, r.move_ratio);
  out.flush();
  if (!out) return Error(CoreErrc::invalid_argument, fmt::format("cannot write {}", path));
  return ok();
}

}  // namespace axon::fps::host
