// One simulated fiber positioner: the firmware's state machine, pure and deterministic.
//
// The model does no I/O and reads no clock. handle() answers one request the way the firmware
// would (interface document 5.2 and 5.3: response codes, payloads, state changes); advance() moves
// the arms to the given simulated time and returns what the robot sends on its own (collision
// reports). Both take the current simulated time; time never runs backwards (an earlier time is
// treated as the latest one seen). Every output is a protocol::Message from this robot.
//
// Frames of reference: the physical angle of an arm is measured from its true datum (0 at the
// zero found at the lower hard stop, stops at -lower and 360 + upper). The firmware's own idea of
// that angle (its step counter, "belief") can be wrong: when the datum was lost, after SET_CURRENT
// _POSITION, or after steps were lost driving open loop against a stop. Reported positions are the
// belief minus the arm's offset (SET_OFFSETS). Range checks use the belief; collisions with the
// hard stops use the physical angle.
//
// Persistent state (the flash: saved calibration, the position saved at power-down, firmware
// images) survives power_off()/power_on(); everything else is reset when the application starts.
#pragma once

#include "axon/fps/protocol/bootloader_status.hpp"
#include "axon/fps/protocol/commands.hpp"
#include "axon/fps/protocol/message.hpp"
#include "axon/fps/protocol/status.hpp"
#include "axon/fps/sim/arm_path.hpp"
#include "axon/fps/sim/positioner_config.hpp"
#include "axon/fps/sim/sim_time.hpp"

#include <boost/container/small_vector.hpp>

#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

namespace axon::fps::sim {

// What the robot sends in answer to one call: usually one reply, sometimes unsolicited frames first.
using Outbox = boost::container::small_vector<protocol::Message, 2>;

enum class RunState : std::uint8_t {
  off,          // no power: silent, frames are lost
  booting,      // power-up of the application (PositionerConfig::boot_time): silent
  bootloader,   // sync line was low at power-up: bootloader commands only
  application,  // the main application runs
  failed_boot,  // the main image does not boot: silent until the watchdog restores the backup
};
std::string_view to_string(RunState s) noexcept;

// A broken sensor or motor phase on one arm (interface document 9.4.3).
enum class HallFault : std::uint8_t {
  none,
  stuck,       // the hall reading no longer changes (a sensor wire came loose); the motor still turns
  motor_dead,  // the arm does not turn (a loose motor cable, a failed h-bridge); the sensor is fine
};
std::string_view to_string(HallFault f) noexcept;
// "none", "stuck", "motor_dead" or its short form "dead"; nullopt for anything else.
std::optional<HallFault> hall_fault_from(std::string_view name) noexcept;

enum class Activity : std::uint8_t {
  idle,
  go_to,                // GO_TO_ABSOLUTE/RELATIVE_POSITION
  trajectory,           // START_TRAJECTORY or the sync line
  datum_search,         // GO_TO_DATUMS (20..22)
  datum_calibration,    // CALIBRATE_DATUM (23..25): three hits of the hard stop
  motor_calibration,    // CALIBRATE_MOTORS (26..28)
  cogging_calibration,  // CALIBRATE_COGGING (47..49): drive to the stop, then a long sweep
};
std::string_view to_string(Activity a) noexcept;

// What SAVE_CALIBRATION writes to flash (and what the application loads at start-up).
struct Calibration {
  PerArm<bool> motor{};
  PerArm<bool> datum{};
  PerArm<bool> cogging{};
  PerArm<double> offset_deg{};                 // SET_OFFSETS
  PerArm<std::uint32_t> holding_current{{0, 30}};
  PerArm<std::int32_t> motor_error{};          // GET_MOTOR_CALIBRATION_ERROR, degrees
  PerArm<std::int32_t> datum_error{};          // GET_DATUM_CALIBRATION_ERROR, motor degrees
  PerArm<double> zero_error_deg{};             // where the calibrated zero sits against the true datum
  friend bool operator==(const Calibration&, const Calibration&) = default;
};

struct FirmwareSlot {
  protocol::FirmwareVersion version;
  bool bootable = true;
  std::uint32_t crc32 = 0;
  friend bool operator==(const FirmwareSlot&, const FirmwareSlot&) = default;
};

// Non-volatile memory.
struct Flash {
  Calibration calibration;
  bool position_saved = false;            // a position was stored at the last power-down
  PerArm<double> counter_error_deg{};     // the stored belief minus the physical angle
  PerArm<bool> initialized{};             // datum state at that power-down
  bool position_estimated = false;        // the power went while the arms moved
  FirmwareSlot main;                      // the main application
  FirmwareSlot backup;                    // restored by the watchdog when main does not boot
  bool main_booted = false;               // main has started since it was written
};

struct ModelCounters {
  std::uint64_t requests = 0;           // requests answered
  std::uint64_t rejected = 0;           // of which with a non-zero response code
  std::uint64_t ignored = 0;            // frames not answered (no power, booting, another robot's id)
  std::uint64_t collisions = 0;         // collision reports sent
  std::uint64_t firmware_received = 0;  // images that passed their CRC
  std::uint64_t firmware_rejected = 0;  // images that failed it
  std::uint64_t watchdog_resets = 0;
  std::uint64_t sync_starts = 0;        // second looks at the sync line that found it high
  std::uint64_t sync_glitches = 0;      // rising edges the second look found gone (nothing started)
};

class PositionerModel {
 public:
  // Starts as if switched on long ago (no boot delay): in the application, or in the bootloader
  // when config.sync_line_low_at_power_on. Throws axon::Exception for an invalid config.
  explicit PositionerModel(PositionerConfig config, SimTime now = {});
  // The same without exceptions.
  static Result<PositionerModel> make(PositionerConfig config, SimTime now = {});

  // Answers one request (after advancing to `now`). Requests for another positioner id are ignored.
  Outbox handle(const protocol::Message& request, SimTime now);
  // Moves to `now`; returns unsolicited frames (collision reports) produced on the way.
  Outbox advance(SimTime now);
  // The next time at which advance() has something to do (nullopt: nothing scheduled).
  [[nodiscard]] std::optional<SimTime> next_event() const noexcept;

  // Power. power_off stops the arms where they are; with save_position the firmware stores its
  // position in flash (what the hold-up capacitors allow), without it the datum is lost.
  // power_on with the sync line low enters the bootloader; otherwise the main application starts
  // after PositionerConfig::boot_time.
  void power_off(SimTime now, bool save_position = true);
  void power_on(SimTime now, bool sync_line_low = false);
  void power_cycle(SimTime now, bool sync_line_low = false);

  // The sync line's level (interface document 6). A rising edge seen by the application arms a
  // second look config.sync_recheck later: if the line is still high then, the loaded trajectory
  // starts as with START_TRAJECTORY and the robot answers with that command's response code, uid
  // 0 (advance() returns the reply at that instant); a pulse shorter than the recheck (jitter)
  // starts nothing. An edge while a look is pending does not arm another. Returns what advancing
  // to `now` produced.
  Outbox set_sync_line(bool high, SimTime now);
  [[nodiscard]] bool sync_line() const noexcept { return sync_high_; }
  // When the pending second look is due (nullopt: none).
  [[nodiscard]] std::optional<SimTime> sync_check_at() const noexcept { return sync_check_at_; }

  // Fault injection: a collision of `arm` now, whatever the geometry and detection settings (the
  // robot stops, sets the flag and reports with command 18, uid 0). Nothing outside the application.
  Outbox inject_collision(Arm arm, SimTime now);
  // Fault injection: extra friction on an arm (interface document 9.4.2). While `level` exceeds the
  // arm's collision margin (SET_COLLISION_MARGIN, -30..30) and detection is on, every move of that
  // arm ends in a false collision shortly after it starts; raising the margin above the level cures
  // it. A positive level also raises the arm's closed-loop current while it turns: by `level`
  // percent of stiction and level / 5 percent per 1000 rpm of viscous friction (9.4.2's model), so a
  // friction trend sees it before the false collisions start. nullopt removes the fault.
  void set_friction_fault(Arm arm, std::optional<std::int32_t> level) noexcept { friction_[arm] = level; }
  // Fault injection: a hall sensor or motor fault on `arm` (9.4.3). In closed loop, or with
  // collision detection on, the firmware sees no motion and every move of that arm ends in a false
  // collision shortly after it starts; in open loop without detection a stuck sensor's arm turns
  // while GET_HALL_POSITION stays where it was, and a dead motor's arm stands still while the step
  // counter (GET_CURRENT_POSITION) runs on. HallFault::none repairs it. Returns what advancing to
  // `now` produced.
  Outbox set_hall_fault(Arm arm, HallFault fault, SimTime now);
  [[nodiscard]] HallFault hall_fault(Arm arm) const noexcept { return hall_fault_[arm]; }
  // The closed-loop current of `arm` turning at `motor_rpm`, percent (stiction + viscous + fault).
  [[nodiscard]] double friction_current_percent(Arm arm, double motor_rpm) const noexcept;

  // Observers.
  [[nodiscard]] std::uint16_t id() const noexcept { return config_.id; }
  [[nodiscard]] const PositionerConfig& config() const noexcept { return config_; }
  [[nodiscard]] SimTime now() const noexcept { return now_; }
  [[nodiscard]] RunState run_state() const noexcept { return run_; }
  [[nodiscard]] bool listening() const noexcept {
    return run_ == RunState::application || run_ == RunState::bootloader;
  }
  [[nodiscard]] Activity activity() const noexcept { return activity_; }
  [[nodiscard]] bool moving() const noexcept { return activity_ != Activity::idle; }
  [[nodiscard]] bool arm_moving(Arm a) const noexcept { return arms_[a].moving; }
  // The application's status word at the current time (what GET_STATUS answers).
  [[nodiscard]] protocol::PositionerStatus status() const noexcept;
  [[nodiscard]] protocol::BootloaderStatus bootloader_status() const noexcept { return boot_.status; }
  // Reported position (GET_CURRENT_POSITION), physical angle and hall reading, degrees.
  [[nodiscard]] double reported_deg(Arm a) const noexcept;
  [[nodiscard]] double physical_deg(Arm a) const noexcept;
  [[nodiscard]] double hall_deg(Arm a) const noexcept;
  // The version the robot answers GET_FIRMWARE_VERSION with right now.
  [[nodiscard]] protocol::FirmwareVersion running_version() const noexcept;
  [[nodiscard]] bool led_on() const noexcept { return led_; }
  // Motor speed set for an arm (SET_SPEED), rpm at the motor.
  [[nodiscard]] std::uint32_t speed_rpm(Arm a) const noexcept { return arms_[a].speed_rpm; }
  [[nodiscard]] bool collision_detection(Arm a) const noexcept { return arms_[a].detection; }
  [[nodiscard]] const Flash& flash() const noexcept { return flash_; }
  [[nodiscard]] const Calibration& calibration() const noexcept { return cal_; }
  [[nodiscard]] const ModelCounters& counters() const noexcept { return counters_; }

 private:
  struct ArmState {
    double theta = 0;      // physical angle (datum frame) when not moving
    double datum_err = 0;  // firmware zero minus the true zero
    double slip = 0;       // steps lost driving open loop against a stop
    bool initialized = false;
    bool collided = false;
    bool closed_loop = true;
    bool detection = true;
    bool precise = true;
    std::uint32_t speed_rpm = 0;
    std::uint32_t drive_current = 0;
    std::int32_t margin = 0;
    // Motion in progress.
    bool moving = false;
    ArmPath cmd;                          // firmware position (datum frame) over time
    ArmPath phys;                         // physical angle over time
    bool follows_hall = true;             // closed loop: the firmware counts what the arm does
    double err0 = 0;                      // belief minus physical when the motion started
    std::optional<SimTime> collision_at;  // the path runs into a hard stop with detection on
  };
  struct TimedPoint {
    SimDuration t{};
    double deg = 0;  // reported frame (offset applied when the trajectory starts)
  };
  struct Upload {
    bool receiving = false;  // SEND_NEW_TRAJECTORY accepted, TRAJECTORY_DATA_END not yet
    bool loaded = false;     // validated, waiting for the start
    bool bad = false;        // a point was refused
    PerArm<std::uint32_t> expected{};
    PerArm<std::vector<TimedPoint>> points;
  };
  struct BootSession {
    protocol::BootloaderStatus status;
    bool receiving = false;
    std::uint32_t size = 0;
    std::uint32_t crc32 = 0;
    std::vector<std::uint8_t> image;
  };

  // Time and power (positioner_model.cpp).
  void run_until(SimTime t, Outbox& out);
  void fire(SimTime t, Outbox& out);
  void enter_bootloader(SimTime t);
  void boot_application(SimTime t, SimDuration delay);
  void start_application(SimTime t);
  void sync_recheck(Outbox& out);

  // Motion (positioner_model.cpp).
  [[nodiscard]] double lower_stop(Arm a) const noexcept { return -config_.hard_stop_lower_deg[a]; }
  [[nodiscard]] double upper_stop(Arm a) const noexcept { return 360.0 + config_.hard_stop_upper_deg[a]; }
  [[nodiscard]] double arm_speed(Arm a) const noexcept;  // deg/s at the arm from the set speed
  [[nodiscard]] double max_arm_speed() const noexcept;
  [[nodiscard]] double belief(Arm a) const noexcept;  // firmware position, datum frame
  [[nodiscard]] double physical_at(Arm a, SimTime t) const noexcept;
  [[nodiscard]] double belief_at(Arm a, SimTime t) const noexcept;
  [[nodiscard]] bool hall_unavailable() const noexcept;
  // Commands the firmware position along `cmd` (datum frame); stops checked per the arm's mode.
  void start_commanded(Arm a, ArmPath cmd);
  // Moves the arm physically along `phys` (datum searches, calibrations: no stop checks).
  void start_physical(Arm a, ArmPath phys);
  void settle(Arm a, SimTime t);
  void stop_motion(SimTime t);
  void finish_arm(Arm a, SimTime t);
  void collide(Arm a, SimTime t, Outbox& out);
  [[nodiscard]] double noise() noexcept;  // deterministic, uniform in [0, 1)

  // Requests (application_commands.cpp, bootloader_commands.cpp).
  void handle_application(const protocol::Message& m, const protocol::CommandInfo& c, Outbox& out);
  void handle_bootloader(const protocol::Message& m, const protocol::CommandInfo& c, Outbox& out);
  protocol::ResponseCode motion_check(Activity kind, PerArm<bool> arms) const noexcept;
  protocol::ResponseCode start_trajectory(SimTime t);
  void start_activity(Activity kind, PerArm<bool> arms, SimTime t);
  void reply(const protocol::Message& m, protocol::ResponseCode code, Outbox& out,
             const protocol::Payload& payload = {});

  PositionerConfig config_;
  SimTime now_{};
  RunState run_ = RunState::off;
  std::optional<SimTime> boot_done_at_;
  std::optional<SimTime> bootloader_deadline_;
  std::optional<SimTime> watchdog_at_;
  bool sync_high_ = false;
  std::optional<SimTime> sync_check_at_;
  Flash flash_;
  Calibration cal_;
  PerArm<ArmState> arms_;
  Activity activity_ = Activity::idle;
  PerArm<std::int32_t> pending_spread_{};    // datum calibration results, applied when it ends
  PerArm<double> pending_zero_error_{};
  Upload upload_;
  BootSession boot_;
  bool hall_on_ = true;                      // SWITCH_ON_HALL / SWITCH_OFF_HALL
  bool hall_sleeping_ = false;               // asleep (off and idle)
  std::optional<SimTime> hall_ready_at_;     // waking up until then
  PerArm<double> hall_frozen_{};             // reading while asleep
  bool led_ = false;
  std::optional<SimTime> led_off_at_;
  bool position_restored_ = false;
  bool position_estimated_ = false;
  std::uint64_t noise_counter_ = 0;
  PerArm<std::optional<std::int32_t>> friction_{};
  PerArm<HallFault> hall_fault_{};
  PerArm<double> hall_stuck_deg_{};          // what a stuck sensor keeps reading
  ModelCounters counters_;
};

}  // namespace axon::fps::sim
