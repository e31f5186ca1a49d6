// `correct` (mode 7): an additive position correction on top of the controller's own trajectory.
//
// The correction is given on the link side for each axis of one arm: a sine (amplitude and
// frequency per axis) or values over time from a CSV file (trajectory.hpp format: offsets, starting
// at 0). Each cycle the correction c(t) goes through the arm's K_r (the linear part of the
// link -> motor transform) and the reply carries its change since the previous cycle as D1: in
// mode 7 the controller adds each increment to the target it has already updated (manual 14.10).
//
// Bounds (CorrectionLimits, link side, per axis): the correction never exceeds max_abs, and it never
// changes by more than max_step from one cycle to the next. A sine whose amplitude or a file whose
// values exceed max_abs are refused when the app is built (an exception: a usage error); a sine or
// a file whose per-cycle change (fades included) can exceed max_step is refused when the
// initialization packet gives the period. Every cycle both bounds are checked again before a
// correction goes out; a breach refuses the correction and leaves the open mode.
// Continuity: an increment above max_motor_speed x period on any motor is refused too (checked
// before starting from the sine's peak speed or the file's rows, and again every cycle).
// Ending: a sine runs until open_time (or a stop request) and then fades out over ramp_s so the
// correction returns to zero smoothly; a file ends at its last row (its last offset stays applied,
// as mode 7 accumulates). Then exit from open until the arm is back in mode 0 (through 7' / 7'').
//
// Live feed (sensor_feed.hpp): the correction follows the latest values an external sensor sent
// over UDP. A sensor's values jump from one measurement to the next, so here the correction slews
// towards them at max_step per cycle (and the motors at max_motor_speed) instead of refusing the
// step. A reading with a value beyond max_abs (or not finite) is refused, counted
// (refused_samples()) and never applied: the correction keeps following the last good reading,
// and returns to zero when no good one came for feed_timeout_s. If no datagram
// came for feed_timeout_s (or none yet), the target is zero: the correction returns to nothing
// until the sensor speaks again (counted in stale_cycles(), noted once per outage). Ending as for
// a sine: open_time or a stop request, then a fade over ramp_s, then exit from open.
#pragma once

#include "axon/c4g/apps/open_mode.hpp"
#include "axon/c4g/apps/correction_limits.hpp"
#include "axon/c4g/apps/sensor_feed.hpp"
#include "axon/c4g/apps/trajectory.hpp"

#include <memory>
#include <vector>

namespace axon::c4g::apps {

struct CorrectOptions {
  std::size_t arm = 1;
  std::vector<double> amplitude_rad;  // per axis, link side; missing axes: 0; one value: every axis
  std::vector<double> frequency_hz;   // per axis; one value: every axis
  std::shared_ptr<const Trajectory> values;  // instead of the sine
  std::shared_ptr<const SensorFeed> feed;     // instead of the sine or the file
  double feed_timeout_s = 0.1;        // older feed values count as none
  double open_time_s = 0;             // 0: until a stop request (sine) / the file's end
  double ramp_s = 0.5;
  double max_motor_speed = 100.0;     // [motor turns/s]
  CorrectionLimits limits;
  // Re-arm: once done (the arm back in mode 0), wait for mode 7 again and correct anew from zero;
  // finished() then stays false.
  bool rearm = false;
};

class CorrectApp final : public OpenModeApp {
 public:
  enum : std::int32_t { kNoteFeedStale = kFirstAppNote, kNoteFeedBack, kNoteFeedRefused };

  explicit CorrectApp(CorrectOptions options);
  [[nodiscard]] std::string_view name() const noexcept override { return "correct"; }
  [[nodiscard]] std::string status() const override;
  [[nodiscard]] std::string summary() const override;
  // Sum of the increments sent so far on the arm's axis j [motor turns] (any thread, relaxed).
  [[nodiscard]] double applied(std::size_t j) const noexcept { return applied_[j].load(std::memory_order_relaxed); }
  // Live feed: cycles spent without fresh values (any thread).
  [[nodiscard]] std::uint64_t stale_cycles() const noexcept { return stale_cycles_.load(std::memory_order_relaxed); }
  // Live feed: readings refused for a value beyond the limit (any thread); never applied.
  [[nodiscard]] std::uint64_t refused_samples() const noexcept { return refused_samples_.load(std::memory_order_relaxed); }
  // Cycles whose slew towards the feed's target was cut to max_step on some axis (any thread).
  [[nodiscard]] std::uint64_t slewed_cycles() const noexcept { return slewed_cycles_.load(std::memory_order_relaxed); }

 protected:
  void setup(const protocol::InitPacket& init, const protocol::AxisMap& axes) override;
  void step(const host::CycleContext& ctx, host::ReplyBuilder& reply) override;
  [[nodiscard]] std::string note_text(std::int32_t code) const override;

 private:
  // Link-side correction at time t with envelope env, into link (size n).
  void correction(double t, double env, protocol::ArmTransform::Vector& link) const noexcept;
  // Live feed: the link-side target from the latest fresh reading (zero when stale).
  void feed_target(double env, protocol::ArmTransform::Vector& link) noexcept;
  // Live feed: takes a new reading if its values are within max_abs, else counts it.
  void take_reading() noexcept;
  // Live feed: moves link towards its target by at most max_step per axis from the last cycle.
  void slew(protocol::ArmTransform::Vector& link) noexcept;
  // The axis whose correction breaks a bound (-1: none), from the last cycle's link_last_.
  [[nodiscard]] int out_of_bounds(const protocol::ArmTransform::Vector& link) const noexcept;
  // At setup: the largest change per cycle of the sine or the file against max_step; fails if above.
  bool check_steps(double period) noexcept;
  // Builds this cycle's correction (envelope env), checks it against every bound and sends its
  // increment; with the feed, may move an exiting phase back to fading until the correction is zero.
  void emit(double env, host::ReplyBuilder& reply) noexcept;
  // A new correction from zero (Turn::start).
  void restart() noexcept;
  // Refuses and leaves mode 7 with zero increments.
  void refuse_now(host::ReplyBuilder& reply) noexcept;

  CorrectOptions options_;
  std::optional<ArmView> view_;
  std::array<std::atomic<double>, protocol::kAxesPerArm> applied_{};
  std::atomic<std::uint64_t> stale_cycles_{0};
  std::atomic<std::uint64_t> refused_samples_{0};
  std::atomic<std::uint64_t> slewed_cycles_{0};
  std::atomic<int> refused_axis_{0};        // last refused reading: its axis (0-based) and value [rad]
  std::atomic<double> refused_value_{0};
  // Cycle thread.
  SineExcitation sine_;
  std::array<double, protocol::kAxesPerArm> last_{};  // last motor-side correction
  std::array<double, protocol::kAxesPerArm> link_last_{};  // last link-side correction [rad]
  SensorFeed::Reading reading_;       // the last reading within the limits
  SensorFeed::Reading incoming_;      // the feed's latest, before the check
  std::uint64_t seen_sequence_ = 0;
  bool refusing_ = false;             // the last reading was refused (one note per series)
  bool stale_ = false;
};

}  // namespace axon::c4g::apps
