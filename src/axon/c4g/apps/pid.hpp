// `pid` (modes 1 and 2): the PC closes the position and velocity loops and sends motor currents.
//
// Per axis of one arm, motor side (turns, turns/s, A), each cycle:
//   v_ref = v_target + kp (p_target - p_actual)            position loop (P)
//   u     = kv (v_ref - v_actual) + integral + feed-forward velocity loop (PI)
//   D5    = u clamped to the axis's current limit (initialization packet)
// Anti-windup: the integral only grows while the output is not saturated or the error drives it
// back out of saturation, and it never exceeds the limit on its own. The feed-forward is the
// controller's dynamic-model current (EXT1) unless disabled: in open modes that current no longer
// reaches the drive by itself (manual 14.12.4).
//
// Targets: mode 1 (the PC generates the trajectory) holds the position found when the mode starts,
// or tracks a sine (link-side amplitude and frequency per axis) around it, faded in and out over
// ramp_s; D1/D2 carry the target position and velocity (delta motor turns); it leaves with exit
// from open after open_time (or a stop request) and keeps holding through 1'. Mode 2 (the
// controller generates the trajectory) tracks the controller's D1/D2; the controller ends it.
// Velocities on the wire are per cycle: actual velocity = D4 / period.
//
// Soft control switching (manual, chapter 12): entering modes 1/2 the controller hands the axis over
// through T1, T2, T3 and back through 1'/2'. The app reads the switch's phase from the server
// (CycleContext::switching, inferred from the modes) and:
//   - holds the robot still until the switch into mode 1 is done (the sine and open_time start
//     afterwards; mode 2's motion is the robot program's, which waits T1 + T2 + T3);
//   - runs its velocity loop as a variable-gain regulator: the integrator advances at the reducer's
//     factor (eta entering, rho leaving) times its rate, so it holds while the PC's current does not
//     reach the drive (anti-windup: it cannot wind up against a reduced output);
//   - sends the full regulator current from the first packet of the mode (the manual's drive-on rule:
//     the first packet of a mode carries that mode's data) and lets the controller apply the reducer,
//     or, with reduce_in_pc, scales D5 by the factor itself (for a controller that does not);
//   - leaving mode 1, asks for the exit only once the faded trajectory has settled on the hold
//     position (every axis within 0.0002 turns and 0.02 turns/s, at most 1 s), so the switch back
//     starts from a still robot.
//
// Safety: the server's Safety layer checks the following error (508) and clamps D5 again; this app
// also tracks the largest following error for the status line.
#pragma once

#include "axon/c4g/apps/open_mode.hpp"
#include "axon/c4g/apps/correction_limits.hpp"

#include <vector>

namespace axon::c4g::apps {

// Defaults tuned on the simulator's six-axis robot at 2 ms (tests/c4g/apps/pid_sim_test.cpp): one
// set for every axis, so kv is bounded by the lightest axis (the wrist, about 295 turns/s^2 per A:
// kv 0.5 puts its velocity loop near 150 rad/s, what a 2 ms loop with one period of delay keeps
// stable) and kp by the heaviest (about 57 turns/s^2 per A: velocity loop near 30 rad/s, kp 20 keeps
// the cascade damped, zeta about 0.6). Measured: hold within 0.002 motor turns, a 0.5 deg / 1 Hz sine
// on every joint in mode 1 within 0.016 turns (the base axes: mode 1 has no acceleration
// feed-forward), the controller's 3 deg / 0.5 s move in mode 2 within 0.0006 turns. Per-axis gains
// (--kp/--kv/--ki) do better on a known robot.
struct PidGains {
  double kp = 20.0;  // [1/s]
  double kv = 0.5;   // [A / (turn/s)]
  double ki = 10.0;  // [1/s] integral rate of the velocity loop
};

struct PidOptions {
  std::size_t arm = 1;
  std::vector<PidGains> gains;  // per axis; one entry: every axis; empty: defaults
  std::vector<double> amplitude_rad;  // mode 1 sine, link side; empty: hold
  std::vector<double> frequency_hz;
  // The sine's bounds (an offset from the hold point, as a correction): an amplitude beyond max_abs
  // is refused when the app is built, a sine changing faster than max_step per cycle (fades
  // included) when the initialization packet gives the period.
  CorrectionLimits limits;
  bool dynamic_model_feedforward = true;
  double open_time_s = 0;  // mode 1: leave after this long (0: until a stop request)
  double ramp_s = 0.5;
  bool reduce_in_pc = false;  // scale D5 by the soft-switching factor here (the controller does not)
};

// One axis's loops: pure, for tests and for the app.
class AxisPid {
 public:
  void reset(double integral = 0) noexcept { integral_ = integral; }
  // Returns the saturated current; limit <= 0: no limit. `authority` in [0, 1] is the share of this
  // output that reaches the drive (the soft-switching reducer's factor): the integrator advances at
  // authority times its rate, so it holds while the output is reduced to nothing.
  double update(const PidGains& g, double p_target, double v_target, double p_actual, double v_actual, double feedforward,
                double limit, double dt, double authority = 1.0) noexcept;
  [[nodiscard]] double integral() const noexcept { return integral_; }
  [[nodiscard]] bool saturated() const noexcept { return saturated_; }

 private:
  double integral_ = 0;
  bool saturated_ = false;
};

class PidApp final : public OpenModeApp {
 public:

  explicit PidApp(PidOptions options);
  [[nodiscard]] std::string_view name() const noexcept override { return "pid"; }
  [[nodiscard]] std::string status() const override;
  [[nodiscard]] std::string summary() const override;
  [[nodiscard]] bool drive_off_on_error() const noexcept override { return true; }
  [[nodiscard]] double max_following_error() const noexcept { return max_error_.load(std::memory_order_relaxed); }
  [[nodiscard]] std::uint64_t saturated_cycles() const noexcept { return saturated_cycles_.load(std::memory_order_relaxed); }
  // Largest |D1 - D3| [motor turns] and |D5| [A] over the packets of a soft switch (T1..T3).
  [[nodiscard]] double max_switch_error() const noexcept { return max_switch_error_.load(std::memory_order_relaxed); }
  [[nodiscard]] double max_switch_current() const noexcept { return max_switch_current_.load(std::memory_order_relaxed); }
  // The reducer factor applied to axis 1 of the arm in the last cycle.
  [[nodiscard]] double reducer_factor() const noexcept { return factor_.load(std::memory_order_relaxed); }

 protected:
  void setup(const protocol::InitPacket& init, const protocol::AxisMap& axes) override;
  void step(const host::CycleContext& ctx, host::ReplyBuilder& reply) override;
  [[nodiscard]] std::string note_text(std::int32_t code) const override;

 private:
  // Mode 1: the hold point plus the faded sine; leaving, the exit once the robot has settled.
  void advance_mode1(const protocol::Packet& req) noexcept;
  // Every axis's loops for this cycle into the reply.
  void control(const host::CycleContext& ctx, host::ReplyBuilder& reply) noexcept;

  PidOptions options_;
  std::optional<ArmView> view_;
  std::atomic<double> max_error_{0};
  std::atomic<std::uint64_t> saturated_cycles_{0};
  std::atomic<double> max_switch_error_{0};
  std::atomic<double> max_switch_current_{0};
  std::atomic<double> factor_{0};
  std::atomic<int> active_mode_{0};
  // Cycle thread.
  std::array<PidGains, protocol::kAxesPerArm> gains_{};
  std::array<double, protocol::kAxesPerArm> limit_{};
  SineExcitation sine_;
  std::array<AxisPid, protocol::kAxesPerArm> loops_{};
  std::array<double, protocol::kAxesPerArm> hold_{};      // motor position when mode 1 started
  std::array<double, protocol::kAxesPerArm> last_ref_{};  // last mode-1 target
  double env_ = 0;
  double settle_s_ = 0;  // time spent at the end of the fade waiting for the robot to settle
  static constexpr double kSettleTurns = 2e-4, kSettleTurnsPerS = 0.02, kMaxSettle_s = 1.0;
  std::int32_t mode_ = 0;  // 1 or 2 while controlling
};

}  // namespace axon::c4g::apps
