#include "axon/fps/host/trajectory_build.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <charconv>

namespace axon::fps::host {

Result<protocol::Trajectory> straight_trajectory(ArmAngles from, ArmAngles to, int points, double duration_s) {
  if (points < 1 || !(duration_s > 0))
    return Error(HostErrc::invalid_argument,
                 fmt::format("a straight move needs points >= 1 and a duration > 0 (got {} points, {:g} s)", points, duration_s));
  std::vector<protocol::ArmPoint> alpha, beta;
  for (int i = 1; i <= points; ++i) {
    const double f = static_cast<double>(i) / points;
    alpha.push_back({from.alpha + (to.alpha - from.alpha) * f, duration_s * f});
    beta.push_back({from.beta + (to.beta - from.beta) * f, duration_s * f});
  }
  return protocol::Trajectory::from_physical(alpha, beta);
}

Result<StraightMoves> straight_moves(const StatusTable& table, ArmAngles to, int points, double duration_s) {
  StraightMoves out;
  for (const auto& row : table.rows) {
    if (!row.position) {
      out.left_out.push_back(fmt::format("positioner {}: no position ({})", row.id, row.error));
      continue;
    }
    auto t = straight_trajectory(*row.position, to, points, duration_s);
    if (!t) return Error(t.error().code, fmt::format("positioner {}: {}", row.id, t.error().message()));
    out.starts[row.id] = *row.position;
    out.trajectories.emplace(row.id, std::move(t).value());
  }
  return out;
}

Result<Trajectories> plan_trajectories(const plan::CollisionModel& model, const plan::Plan& plan) {
  Trajectories out;
  for (std::size_t i = 0; i < model.size() && i < plan.trajectories.size(); ++i) {
    const auto& t = plan.trajectories[i];
    if (t.alpha.size() <= 1 && t.beta.size() <= 1) continue;  // does not move
    // The first point (0 s) is where the robot stands: the firmware adds it by itself.
    std::vector<protocol::ArmPoint> alpha, beta;
    for (std::size_t k = 1; k < t.alpha.size(); ++k) alpha.push_back({t.alpha[k].deg, t.alpha[k].t_s});
    for (std::size_t k = 1; k < t.beta.size(); ++k) beta.push_back({t.beta[k].deg, t.beta[k].t_s});
    const auto id = model.robot(i).id();
    auto tr = protocol::Trajectory::from_physical(alpha, beta);
    if (!tr) return Error(tr.error().code, fmt::format("robot {}: {}", id, tr.error().detail));
    out.emplace(static_cast<std::uint16_t>(id), std::move(tr).value());
  }
  return out;
}

namespace {

Error file_error(std::string text) { return Error(CoreErrc::invalid_argument, std::move(text)); }

// One arm's [[deg, s], ...] list.
Result<std::vector<protocol::ArmPoint>> arm_points(const YAML::Node& list, const std::string& where) {
  std::vector<protocol::ArmPoint> out;
  if (!list) return out;
  if (!list.IsSequence()) return file_error(fmt::format("{}: expected a list of [deg, s]", where));
  for (const auto& pt : list) {
    if (!pt.IsSequence() || pt.size() != 2) return file_error(fmt::format("{}: each point is [deg, s]", where));
    try {
      out.push_back(protocol::ArmPoint{pt[0].as<double>(), pt[1].as<double>()});
    } catch (const std::exception& e) {
      return file_error(fmt::format("{}: {}", where, e.what()));
    }
  }
  return out;
}

Result<std::uint16_t> robot_key(const std::string& file, const std::string& key) {
  unsigned v = 0;
  const auto* end = key.data() + key.size();
  auto [p, ec] = std::from_chars(key.data(), end, v);
  if (ec != std::errc() || p != end || v < 1 || v > 2047)
    return file_error(fmt::format("{}: key '{}' must be one robot id (1..2047)", file, key));
  return static_cast<std::uint16_t>(v);
}

}  // namespace

Result<Trajectories> load_trajectory_file(const std::string& file) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(file);
  } catch (const std::exception& e) {
    return file_error(fmt::format("{}: {}", file, e.what()));
  }
  if (!root.IsMap() || root.size() == 0) return file_error(fmt::format("{}: expected a map of robot id -> {{alpha, beta}}", file));
  Trajectories out;
  std::map<std::uint16_t, int> line_of;  // where each robot's entry starts (1-based)
  for (const auto& kv : root) {
    if (!kv.first.IsScalar())  // a map or a list as a key: as<std::string>() would throw
      return file_error(fmt::format("{}:{}: a robot id must be a plain number", file, kv.first.Mark().line + 1));
    const auto key = kv.first.as<std::string>();
    AXON_TRY(id, robot_key(file, key));
    const int line = kv.first.Mark().line + 1;
    if (auto [it, fresh] = line_of.emplace(id, line); !fresh)
      return file_error(fmt::format("{}:{}: robot {} listed twice (first at line {})", file, line, id, it->second));
    AXON_TRY(alpha, arm_points(kv.second["alpha"], fmt::format("{}: robot {} alpha", file, key)));
    AXON_TRY(beta, arm_points(kv.second["beta"], fmt::format("{}: robot {} beta", file, key)));
    auto t = protocol::Trajectory::from_physical(alpha, beta);
    if (!t) return Error(t.error().code, fmt::format("{}: robot {}{}{}", file, key, t.error().detail.empty() ? "" : ": ", t.error().detail));
    out.emplace(id, std::move(t).value());
  }
  return out;
}

}  // namespace axon::fps::host
