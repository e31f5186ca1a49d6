// `stream` (mode 4 or 5): plays a joint trajectory (trajectory.hpp) on one arm.
//
// Set-up (initialization packet): the trajectory must have one column per axis of the arm (logical
// 1..n, all open); it is sampled once per controller period and converted to motor turns through
// the arm's ArmTransform, so the cycle only reads a table. Continuity check: no step between two
// cycles may exceed max_motor_speed x period on any axis; a trajectory that does is refused before
// anything moves.
//
// Cycle (the phases of open_mode.hpp):
//   - waiting: until every axis of the arm is in the chosen mode. Then the start-point check: the
//     robot's actual position (D3, converted to the link side) must match the trajectory's first
//     row within start_tolerance (or, with `relative`, the trajectory is taken as offsets from that
//     position and its first row must be zero). A mismatch refuses: nothing moves, exit from open.
//   - playing (Phase::running): one table row per cycle. Mode 4 sends the absolute target (D1)
//     and the change since the previous cycle (D2, delta motor turns); mode 5 sends that change as
//     the position increment (D1) and as velocity (D2): the controller integrates it.
//   - holding: the last point for hold_s, then exit from open until the controller is back in
//     mode 0 (through 4' / 5'), which finishes the app.
//   - a stop request slows the playback down to rest over stop_ramp_s (along the path), then exits
//     from open the same way.
// Leaving the mode during the trajectory (drive off, another program) is an error.
// Segments (instead of one trajectory): the robot program picks a trajectory through the arm's
// motion type (its CMD byte, CycleContext::motion_type). On entering the mode, and whenever the
// motion type changes while in it, the segment of that motion type starts from its first row with
// the start-point check of a normal start (a relative segment starts from the last commanded
// position, so relative segments chain). After a segment's last row the point is held (no exit)
// until the motion type changes again; a motion type without a segment holds and is noted; motion
// type 0 after a segment was played (the program cleared it) ends the stream: exit from open.
// Every segment is sampled and checked for continuity at set-up like a single trajectory.
// With `rearm`, every later entry into the mode plays the trajectory again (a robot program that
// opens the same mode several times; `--app handover` uses it).
#pragma once

#include "axon/c4g/apps/open_mode.hpp"
#include "axon/c4g/apps/trajectory.hpp"

#include <memory>
#include <numbers>
#include <vector>

namespace axon::c4g::apps {

// A trajectory played while the robot program has set this motion type (CMD byte of the arm).
struct StreamSegment {
  std::uint8_t motion_type = 1;  // 1..255
  std::shared_ptr<const Trajectory> trajectory;
};

struct StreamOptions {
  std::shared_ptr<const Trajectory> trajectory;  // one trajectory, whatever the motion type
  // Segments by motion type instead of `trajectory` (see the header comment).
  std::vector<StreamSegment> segments;
  int mode = 4;  // 4 or 5
  std::size_t arm = 1;
  bool relative = false;
  // The trajectories' clock counts controller cycles, not seconds: row k of a table one step apart
  // (Trajectory::from_table with row_step 1) is played at cycle k, whatever the controller's period.
  bool per_cycle = false;
  double start_tolerance_rad = 0.5 * std::numbers::pi / 180.0;
  double max_motor_speed = 100.0;  // [motor turns/s] continuity limit
  double hold_s = 0.1;
  double stop_ramp_s = 0.3;
  // Re-arm: once done (the arm back in mode 0), wait for the mode again and play the trajectory
  // anew from the start (start-point check included); finished() then stays false.
  bool rearm = false;
};

// Phases (open_mode.hpp): running while playing the table, holding its last point, idle while a
// motion type without a segment holds the last command.
class StreamApp final : public OpenModeApp {
 public:
  // Note codes (segments: base + motion type).
  enum : std::int32_t {
    kNoteEnded = kFirstAppNote, kNoteStopping, kNoteTypeCleared,
    kNoteSegment = 1000, kNoteUnknownType = 2000,
  };

  explicit StreamApp(StreamOptions options);
  [[nodiscard]] std::string_view name() const noexcept override { return "stream"; }
  [[nodiscard]] std::string status() const override;
  [[nodiscard]] std::string summary() const override;
  [[nodiscard]] std::size_t table_rows() const noexcept { return rows_shown_.load(std::memory_order_relaxed); }
  // Motion type of the segment played last (0: none yet, or no segments); any thread.
  [[nodiscard]] std::uint8_t segment() const noexcept { return segment_.load(std::memory_order_relaxed); }
  // Progress through the table in rows (any thread).
  [[nodiscard]] double progress() const noexcept { return progress_.load(std::memory_order_relaxed); }

 protected:
  void setup(const protocol::InitPacket& init, const protocol::AxisMap& axes) override;
  void step(const host::CycleContext& ctx, host::ReplyBuilder& reply) override;
  void silence() noexcept override;
  [[nodiscard]] std::string note_text(std::int32_t code) const override;

 private:
  // Entering the mode (Turn::start): the table of the motion type, or idle without one.
  void enter(const host::CycleContext& ctx) noexcept;
  // A new motion type while in the mode (segments).
  void change_segment(const host::CycleContext& ctx, std::uint8_t type) noexcept;
  // Advances the playback one cycle (stop ramp, end of table, hold time).
  void advance_playback() noexcept;
  // Motor position of the arm's axis j at fractional row s (base included).
  double command(std::size_t j, double s) const noexcept;
  // Samples one trajectory into a table (set-up); false after fail().
  bool build(const Trajectory& traj, std::vector<double>& table, std::size_t& rows);
  // Start-point check and start of table idx; from_command: relative to the last command (a
  // segment change) instead of the actual position. False (refused) on a failed check.
  bool start(std::size_t idx, const protocol::Packet& req, bool from_command) noexcept;
  // Index of the table for a motion type (segments), or npos.
  [[nodiscard]] std::size_t find(std::uint8_t type) const noexcept;

  struct Table {
    std::uint8_t motion_type = 0;
    std::shared_ptr<const Trajectory> trajectory;
    std::vector<double> motor;  // rows x axes: linear part of the motor position K_r q / 2 pi [turns]
    std::size_t rows = 0;
  };
  StreamOptions options_;
  std::optional<ArmView> view_;
  std::vector<Table> tables_;
  const double* table_ = nullptr;  // the current table
  std::size_t rows_ = 0;           // its rows (cycle thread)
  std::atomic<std::size_t> rows_shown_{0};  // the same, for the other threads (status, summary)
  std::atomic<std::uint8_t> segment_{0};
  std::uint8_t type_ = 0;          // motion type seen last (segments)
  bool played_ = false;            // a segment was played in this entry
  bool hold_last_ = false;         // no segment: hold the last command
  std::atomic<double> progress_{0};
  std::atomic<double> period_{0.001};  // for status()
  // Cycle thread.
  std::array<double, protocol::kAxesPerArm> base_{};  // motor offset: calibration, or start position
  std::array<double, protocol::kAxesPerArm> last_{};  // last commanded motor position
  double s_ = 0;
  double rate_ = 1;
  std::size_t hold_cycles_ = 0;
  std::size_t held_ = 0;
};

}  // namespace axon::c4g::apps
