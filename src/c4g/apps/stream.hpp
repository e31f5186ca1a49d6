// `stream` (mode 4 or 5): plays a joint trajectory (trajectory.hpp) on one arm.
//
// Set-up (initialization packet): the trajectory must have one column per axis of the arm (logical
// 1..n, all open); it is sampled once per controller period and converted to motor turns through
// the arm's ArmTransform, so the cycle only reads a table. Continuity check: no step between two
// cycles may exceed max_motor_speed x period on any axis; a trajectory that does is refused before
// anything moves.
//
// Cycle:
//   - waiting: until every axis of the arm is in the chosen mode. Then the start-point check: the
//     robot's actual position (D3, converted to the link side) must match the trajectory's first
//     row within start_tolerance (or, with `relative`, the trajectory is taken as offsets from that
//     position and its first row must be zero). A mismatch refuses: nothing moves, exit from open.
//   - playing: one table row per cycle. Mode 4 sends the absolute target (D1) and the change since
//     the previous cycle (D2, delta motor turns); mode 5 sends that change as the position increment
//     (D1) and as velocity (D2): the controller integrates it.
//   - holding: the last point for hold_s, then exit from open until the controller is back in
//     mode 0 (through 4' / 5'), which finishes the app.
//   - a stop request slows the playback down to rest over stop_ramp_s (along the path), then exits
//     from open the same way.
// Leaving the mode during the trajectory (drive off, another program) is an error.
// With `rearm`, every later entry into the mode plays the trajectory again (a robot program that
// opens the same mode several times; `--app handover` uses it).
#pragma once

#include "c4g/apps/app.hpp"
#include "c4g/apps/trajectory.hpp"

#include <memory>
#include <numbers>
#include <vector>

namespace axon::c4g::apps {

struct StreamOptions {
  std::shared_ptr<const Trajectory> trajectory;
  int mode = 4;  // 4 or 5
  std::size_t arm = 1;
  bool relative = false;
  double start_tolerance_rad = 0.5 * std::numbers::pi / 180.0;
  double max_motor_speed = 100.0;  // [motor turns/s] continuity limit
  double hold_s = 0.1;
  double stop_ramp_s = 0.3;
  // Re-arm: once done (the arm back in mode 0), wait for the mode again and play the trajectory
  // anew from the start (start-point check included); finished() then stays false.
  bool rearm = false;
};

class StreamApp final : public App {
 public:
  enum class Phase : std::uint8_t { waiting, playing, holding, exiting, done, refused };
  // Note codes.
  enum : std::int32_t { kNoteStarted = 1, kNoteEnded, kNoteDone, kNoteStopping };

  explicit StreamApp(StreamOptions options);
  [[nodiscard]] std::string_view name() const noexcept override { return "stream"; }
  [[nodiscard]] std::string status() const override;
  [[nodiscard]] std::string summary() const override;
  [[nodiscard]] bool finished() const noexcept override { return !options_.rearm && phase() == Phase::done; }
  // Runs the trajectory played so far (any thread).
  [[nodiscard]] std::uint64_t runs() const noexcept { return runs_.load(std::memory_order_relaxed); }
  [[nodiscard]] Phase phase() const noexcept { return phase_.load(std::memory_order_acquire); }
  [[nodiscard]] std::size_t table_rows() const noexcept { return rows_; }
  // Progress through the table in rows (any thread).
  [[nodiscard]] double progress() const noexcept { return progress_.load(std::memory_order_relaxed); }

 protected:
  void setup(const protocol::InitPacket& init, const protocol::AxisMap& axes) override;
  void step(const host::CycleContext& ctx, host::ReplyBuilder& reply) override;
  void silence() noexcept override;
  [[nodiscard]] std::string note_text(std::int32_t code) const override;

 private:
  void set_phase(Phase p) noexcept { phase_.store(p, std::memory_order_release); }
  // Motor position of the arm's axis j at fractional row s (base included).
  double command(std::size_t j, double s) const noexcept;

  StreamOptions options_;
  std::optional<ArmView> view_;
  std::vector<double> table_;  // rows_ x axes: linear part of the motor position K_r q / 2 pi [turns]
  std::size_t rows_ = 0;
  std::atomic<Phase> phase_{Phase::waiting};
  std::atomic<double> progress_{0};
  std::atomic<double> period_{0.001};  // for status()
  std::atomic<std::uint64_t> runs_{0};
  // Cycle thread.
  std::array<double, protocol::kAxesPerArm> base_{};  // motor offset: calibration, or start position
  std::array<double, protocol::kAxesPerArm> last_{};  // last commanded motor position
  double s_ = 0;
  double rate_ = 1;
  std::size_t hold_cycles_ = 0;
  std::size_t held_ = 0;
};

}  // namespace axon::c4g::apps
