// `correct` (mode 7): an additive position correction on top of the controller's own trajectory.
//
// The correction is given on the link side for each axis of one arm: a sine (amplitude and
// frequency per axis) or values over time from a CSV file (trajectory.hpp format: offsets, starting
// at 0). Each cycle the correction c(t) goes through the arm's K_r (the linear part of the
// link -> motor transform) and the reply carries its change since the previous cycle as D1: in
// mode 7 the controller adds each increment to the target it has already updated (manual 14.10).
//
// Continuity: an increment above max_motor_speed x period on any axis is refused (checked before
// starting from the sine's peak speed or the file's rows, and again every cycle).
// Ending: a sine runs until open_time (or a stop request) and then fades out over ramp_s so the
// correction returns to zero smoothly; a file ends at its last row (its last offset stays applied,
// as mode 7 accumulates). Then exit from open until the arm is back in mode 0 (through 7' / 7'').
//
// Live feed (sensor_feed.hpp): the correction follows the latest values an external sensor sent
// over UDP. A sensor's values jump from one measurement to the next, so here the motor-side
// correction slews towards them at max_motor_speed instead of refusing the step. If no datagram
// came for feed_timeout_s (or none yet), the target is zero: the correction returns to nothing
// until the sensor speaks again (counted in stale_cycles(), noted once per outage). Ending as for
// a sine: open_time or a stop request, then a fade over ramp_s, then exit from open.
#pragma once

#include "c4g/apps/app.hpp"
#include "c4g/apps/sensor_feed.hpp"
#include "c4g/apps/trajectory.hpp"

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
  // Re-arm: once done (the arm back in mode 0), wait for mode 7 again and correct anew from zero;
  // finished() then stays false.
  bool rearm = false;
};

class CorrectApp final : public App {
 public:
  enum class Phase : std::uint8_t { waiting, correcting, fading, exiting, done, refused };
  enum : std::int32_t { kNoteStarted = 1, kNoteFading, kNoteDone, kNoteFeedStale, kNoteFeedBack };

  explicit CorrectApp(CorrectOptions options);
  [[nodiscard]] std::string_view name() const noexcept override { return "correct"; }
  [[nodiscard]] std::string status() const override;
  [[nodiscard]] std::string summary() const override;
  [[nodiscard]] bool finished() const noexcept override { return !options_.rearm && phase() == Phase::done; }
  // Corrections started so far (any thread).
  [[nodiscard]] std::uint64_t runs() const noexcept { return runs_.load(std::memory_order_relaxed); }
  [[nodiscard]] Phase phase() const noexcept { return phase_.load(std::memory_order_acquire); }
  // Sum of the increments sent so far on the arm's axis j [motor turns] (any thread, relaxed).
  [[nodiscard]] double applied(std::size_t j) const noexcept { return applied_[j].load(std::memory_order_relaxed); }
  // Live feed: cycles spent without fresh values (any thread).
  [[nodiscard]] std::uint64_t stale_cycles() const noexcept { return stale_cycles_.load(std::memory_order_relaxed); }

 protected:
  void setup(const protocol::InitPacket& init, const protocol::AxisMap& axes) override;
  void step(const host::CycleContext& ctx, host::ReplyBuilder& reply) override;
  [[nodiscard]] std::string note_text(std::int32_t code) const override;

 private:
  void set_phase(Phase p) noexcept { phase_.store(p, std::memory_order_release); }
  // Link-side correction at time t with envelope env, into link (size n).
  void correction(double t, double env, protocol::ArmTransform::Vector& link) const noexcept;
  // Live feed: the link-side target from the latest fresh reading (zero when stale).
  void feed_target(double env, protocol::ArmTransform::Vector& link) noexcept;

  CorrectOptions options_;
  std::optional<ArmView> view_;
  std::atomic<Phase> phase_{Phase::waiting};
  std::array<std::atomic<double>, protocol::kAxesPerArm> applied_{};
  std::atomic<double> elapsed_{0};
  std::atomic<std::uint64_t> stale_cycles_{0};
  std::atomic<std::uint64_t> runs_{0};
  // Cycle thread.
  std::array<double, protocol::kAxesPerArm> amplitude_{}, frequency_{};
  std::array<double, protocol::kAxesPerArm> last_{};  // last motor-side correction
  double t_ = 0;
  std::uint64_t ticks_ = 0;
  double fade_start_ = 0;
  SensorFeed::Reading reading_;
  bool stale_ = false;
};

}  // namespace axon::c4g::apps
