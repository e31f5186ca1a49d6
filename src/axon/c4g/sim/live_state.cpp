#include "axon/c4g/sim/live_state.hpp"

#include <algorithm>

namespace axon::c4g::sim {

namespace live_copy {

template <std::size_t N>
void copy_cut(std::string_view from, std::array<char, N>& to) noexcept {
  const auto n = std::min(from.size(), N - 1);
  std::copy_n(from.begin(), n, to.begin());
  to[n] = '\0';
}

}  // namespace live_copy

void capture(const Controller& c, LiveState& out) noexcept {
  out.time_s = c.time_s();
  out.phase = c.phase();
  out.communication_error = c.communication_error();
  out.axis_count = std::min(c.axis_count(), out.axes.size());
  const auto& map = c.axis_map();
  for (std::size_t i = 0; i < out.axis_count; ++i) {
    const auto logical = map.logical(i);
    out.axes[i] = {static_cast<std::uint8_t>(logical.arm), static_cast<std::uint8_t>(logical.axis), c.axis_mode(i),
                   c.axis_pc_request(i), c.axis_position(i), c.axis_reference(i), c.axis_current(i)};
  }
  for (std::size_t arm = 1; arm <= protocol::kMaxArms; ++arm) {
    LiveArm& a = out.arms[arm];
    a.present = map.arm_count(arm) > 0;
    a.drives_on = c.drives_on(arm);
    a.program_mode = c.arm_program_mode(arm);
    a.joints = c.link_degrees(arm, false, a.joint_deg);
    c.link_degrees(arm, true, a.target_deg);
  }
  const auto& steps = c.scenario().steps;
  out.steps = steps.size();
  out.step = std::min(c.step_index(), steps.size());
  out.step_kind = out.step < steps.size() ? steps[out.step].kind : StepKind::run;
  out.scenario_done = c.scenario_done();
  out.scenario_failed = c.scenario_failed();
  out.stats = c.stats();
  out.consecutive_misses = c.consecutive_misses();
}

LiveEvent live_event(const Event& e) noexcept {
  LiveEvent out;
  out.time_s = e.time_s;
  out.cycle = e.cycle;
  out.level = e.level;
  live_copy::copy_cut(e.name, out.name);
  live_copy::copy_cut(e.text, out.text);
  return out;
}

}  // namespace axon::c4g::sim
