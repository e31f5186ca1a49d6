// `contribute` (modes 8 and 9): an additive contribution on the controller's own loops.
//
// Mode 8 adds a velocity contribution at the input of the drive's velocity loop (D4, in motor turns
// per cycle on the wire; given here in motor turns/s and converted with the cycle period); mode 9
// adds a current contribution (D5, in A). Both are motor side, per axis of one arm: a sine
// A sin(2 pi f t) (one amplitude applies to every axis; missing axes get 0), faded in and out over
// ramp_s so the contribution starts and ends at zero. It runs for open_time (or until a stop
// request), then exit from open until the arm is back in mode 0. The robot program opens the mode
// (GO OPEN with mode 8 or 9); the server's Safety clamps mode-9 currents to the axis limits.
//
// The manual lists mode 8 as not available on today's controllers; the simulator implements it,
// so the app serves it for experiments and tests.
#pragma once

#include "axon/c4g/apps/open_mode.hpp"

#include <vector>

namespace axon::c4g::apps {

struct ContributeOptions {
  std::size_t arm = 1;
  int mode = 9;                       // 8 (velocity) or 9 (current)
  std::vector<double> amplitude;      // per axis: motor turns/s (mode 8) or A (mode 9)
  std::vector<double> frequency_hz;   // per axis; one value: every axis; none: 0.5 Hz
  double open_time_s = 0;             // 0: until a stop request
  double ramp_s = 0.5;
  // Mode 8: a velocity contribution above this [motor turns/s] is refused when the app is built
  // (mode 9 currents are saturated to the initialization packet's limits by the server's Safety).
  double max_motor_speed = 100.0;
};

class ContributeApp final : public OpenModeApp {
 public:
  explicit ContributeApp(ContributeOptions options);
  [[nodiscard]] std::string_view name() const noexcept override { return "contribute"; }
  [[nodiscard]] std::string status() const override;
  [[nodiscard]] std::string summary() const override;
  // The contribution sent last on the arm's axis j, in the option's units (any thread, relaxed).
  [[nodiscard]] double last(std::size_t j) const noexcept { return last_[j].load(std::memory_order_relaxed); }
  [[nodiscard]] double peak(std::size_t j) const noexcept { return peak_[j].load(std::memory_order_relaxed); }

 protected:
  void setup(const protocol::InitPacket& init, const protocol::AxisMap& axes) override;
  void step(const host::CycleContext& ctx, host::ReplyBuilder& reply) override;
  [[nodiscard]] std::string note_text(std::int32_t code) const override;

 private:
  ContributeOptions options_;
  std::array<std::atomic<double>, protocol::kAxesPerArm> last_{}, peak_{};
  // Cycle thread.
  std::size_t first_ = 0, count_ = 0;
  double period_s_ = 0.002;
  SineExcitation sine_;
};

}  // namespace axon::c4g::apps
