#include "axon/fps/host/trajectory_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>

namespace axon::fps::host {

const char* to_string(RobotState s) noexcept {
  switch (s) {
    case RobotState::pending: return "pending";
    case RobotState::not_ready: return "not-ready";
    case RobotState::upload_failed: return "upload-failed";
    case RobotState::loaded: return "loaded";
    case RobotState::withdrawn: return "withdrawn";
    case RobotState::still_loaded: return "still-loaded";
    case RobotState::not_started: return "not-started";
    case RobotState::started: return "started";
    case RobotState::stopped: return "stopped";
    case RobotState::collided: return "collided";
    case RobotState::timeout: return "timeout";
    case RobotState::position_mismatch: return "position-mismatch";
    case RobotState::completed: return "completed";
  }
  return "?";
}

bool TrajectoryReport::all(RobotState s) const noexcept {
  return std::all_of(robots.begin(), robots.end(), [&](const RobotRun& r) { return r.state == s; });
}

std::vector<std::uint16_t> TrajectoryReport::in_state(RobotState s) const {
  std::vector<std::uint16_t> out;
  for (const auto& r : robots) {
    if (r.state == s) out.push_back(r.id);
  }
  return out;
}

const RobotRun* TrajectoryReport::find(std::uint16_t id) const noexcept {
  auto it = std::find_if(robots.begin(), robots.end(), [&](const RobotRun& r) { return r.id == id; });
  return it == robots.end() ? nullptr : &*it;
}

std::string TrajectoryReport::summary() const {
  std::string out = outcome + "\n";
  constexpr std::array kStates{RobotState::pending,     RobotState::not_ready, RobotState::upload_failed,
                               RobotState::loaded,      RobotState::withdrawn, RobotState::still_loaded, RobotState::not_started,
                               RobotState::started,     RobotState::stopped,     RobotState::collided,  RobotState::timeout,
                               RobotState::position_mismatch, RobotState::completed};
  std::string counts;
  for (auto s : kStates) {
    const auto n = in_state(s).size();
    if (n) counts += fmt::format("{}{} {}", counts.empty() ? "" : ", ", n, to_string(s));
  }
  out += counts + "\n";
  for (const auto& r : robots) {
    if (r.state == RobotState::completed || r.state == RobotState::loaded) continue;
    out += fmt::format("  positioner {}: {}{}{}\n", r.id, to_string(r.state), r.detail.empty() ? "" : ": ", r.detail);
  }
  return out;
}

}  // namespace axon::fps::host
