// Positioner: one robot, addressed through the command client of the bus it is on.
//
// Every call is a coroutine on the bus's executor. Reads return decoded values in physical units
// (degrees), settings take physical units and check them before sending (a value that does not fit
// its field is ProtocolErrc::value_out_of_range, nothing is sent). Motion commands (moves, datum
// search, calibrations, trajectory upload) are refused with HostErrc::locked while the lock of the
// client's array is held: the command client refuses them (motion_lock.hpp), whichever handle
// sends them.
//
// Waiting: after a move or calibration is accepted, the robot's status is polled every
// PositionerOptions::poll_interval until the flags the interface document names show the step
// finished (DISPLACEMENT_COMPLETED plus the step's own flags), a collision flag appears, the lock
// is taken, or the step's timeout passes. Moves then read the position back and check it against the
// target within PositionerOptions::position_tolerance (0.1 deg, as hosts in service do). A move,
// datum search or calibration the host gives up on (timeout, no status replies, bus lost) gets a
// TRAJECTORY_ABORT, so that no robot keeps moving unwatched; the error says whether it went out.
#pragma once

#include "axon/core/error.hpp"
#include "axon/fps/host/command_client.hpp"
#include "axon/fps/protocol/firmware_gates.hpp"
#include "axon/fps/protocol/firmware_version.hpp"
#include "axon/fps/protocol/payloads.hpp"
#include "axon/fps/protocol/status.hpp"
#include "axon/fps/protocol/trajectory.hpp"

#include <boost/asio/awaitable.hpp>

#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>

namespace axon::fps::host {

enum class Arm : std::uint8_t { alpha, beta, both };
const char* to_string(Arm a) noexcept;

enum class Loop : std::uint8_t { closed, open };

// Alpha and beta angles at the arms, degrees.
struct ArmAngles {
  double alpha = 0;
  double beta = 0;
  friend bool operator==(const ArmAngles&, const ArmAngles&) = default;
};

struct PositionerOptions {
  core::Duration poll_interval = 250ms;       // status polling while waiting for a step to finish
  double position_tolerance = 0.1;            // degrees, per arm, after a move
  core::Duration move_margin = 5s;            // added to the ETA the robot gives for a move
  core::Duration datum_timeout = 120s;        // go to datums
  core::Duration motor_calibration_timeout = 300s;
  core::Duration datum_calibration_timeout = 300s;
  core::Duration cogging_calibration_timeout = 3600s;  // the document allows up to 40 min
  std::size_t trajectory_window = 8;          // trajectory points in flight to one robot
  // How the robots order GET_FIRMWARE_VERSION's bytes (protocol/firmware_version.hpp).
  protocol::VersionByteOrder version_byte_order = protocol::VersionByteOrder::field;
  // Which commands a firmware version has (protocol/firmware_gates.hpp): a gated command is
  // refused with HostErrc::firmware_lacks before it is sent, once the robot's version is known.
  protocol::FirmwareHistory firmware_history = protocol::FirmwareHistory::document;
};

// Hears about collision flags a positioner finds while polling a robot (the backup for a lost
// collision frame): the Array locks and stops every robot. Whether a robot may move is not asked
// here: the command client decides that (motion_lock.hpp).
class MotionGate {
 public:
  virtual ~MotionGate() = default;
  virtual void collision_seen(std::uint16_t positioner, const protocol::PositionerStatus& status) = 0;
};

struct MoveResult {
  ArmAngles target;
  ArmAngles reached;
  protocol::ArmTimes eta;  // what the robot announced
};

// What the firmware answered to an upload, step by step.
struct UploadResult {
  enum class Stage : std::uint8_t { not_sent, new_trajectory, points, data_end, done };
  Stage stage = Stage::not_sent;      // the step that failed (done on success)
  std::optional<Arm> arm;             // for a rejected point: which arm ...
  std::optional<std::size_t> point;   // ... and its index within that arm
  std::size_t points_accepted = 0;
  std::optional<Error> error;

  [[nodiscard]] bool ok() const noexcept { return stage == Stage::done; }
  [[nodiscard]] std::string describe() const;
};
const char* to_string(UploadResult::Stage s) noexcept;

struct CalibrationPlan {
  bool motors = true;
  bool datums = true;
  bool cogging = false;  // long (up to 40 min) and not essential
  bool save = true;
  Arm arm = Arm::both;
};
struct CalibrationReport {
  std::optional<protocol::ArmValues> motor_error;  // degrees, after motor calibration
  std::optional<protocol::ArmValues> datum_error;  // degrees, after datum calibration
  protocol::PositionerStatus final_status;
  bool saved = false;
};

enum class CoggingTable : std::uint8_t { positive, negative, angles };

class Positioner {
 public:
  Positioner(CommandClient& client, std::uint16_t id, PositionerOptions options = {}, MotionGate* gate = nullptr);

  [[nodiscard]] std::uint16_t id() const noexcept { return id_; }
  [[nodiscard]] CommandClient& client() const noexcept { return *client_; }
  [[nodiscard]] const PositionerOptions& options() const noexcept { return options_; }
  void set_options(PositionerOptions o) { options_ = std::move(o); }

  // What the last reads found (empty until read).
  [[nodiscard]] const std::optional<protocol::FirmwareVersion>& firmware() const noexcept { return firmware_; }
  [[nodiscard]] const std::optional<protocol::PositionerStatus>& last_status() const noexcept { return status_; }
  [[nodiscard]] const std::optional<protocol::BootloaderStatus>& last_bootloader_status() const noexcept {
    return boot_status_;
  }
  [[nodiscard]] bool in_bootloader() const noexcept { return firmware_ && firmware_->is_bootloader(); }

  // --- reads -----------------------------------------------------------------------------------
  // Decoded in PositionerOptions::version_byte_order; the version then gates what is sent.
  asio::awaitable<Result<protocol::FirmwareVersion>> read_firmware_version();
  // Main application status. A 4-byte answer means the bootloader runs: HostErrc::not_ready.
  // Application firmware known to predate the 64-bit status word: HostErrc::firmware_lacks, not sent.
  asio::awaitable<Result<protocol::PositionerStatus>> read_status();
  // Bootloader status. An 8-byte answer means the main application runs: HostErrc::not_in_bootloader.
  asio::awaitable<Result<protocol::BootloaderStatus>> read_bootloader_status();
  asio::awaitable<Result<ArmAngles>> read_position();
  asio::awaitable<Result<ArmAngles>> read_offsets();
  asio::awaitable<Result<ArmAngles>> read_hall_position();
  asio::awaitable<Result<protocol::ArmValues>> read_datum_calibration_error();
  asio::awaitable<Result<protocol::ArmValues>> read_motor_calibration_error();
  asio::awaitable<Result<protocol::ArmValues>> read_currents();
  asio::awaitable<Result<protocol::ArmValues>> read_torques();
  asio::awaitable<Result<protocol::PositionAndValue>> read_position_and_current(Arm arm);  // alpha or beta
  asio::awaitable<Result<protocol::PositionAndValue>> read_position_and_torque(Arm arm);
  asio::awaitable<Result<protocol::ArmCurrents>> read_holding_current();
  asio::awaitable<Result<std::uint32_t>> read_raw_temperature();
  asio::awaitable<Result<std::uint32_t>> read_cogging_vector_length();
  asio::awaitable<Result<protocol::ArmValues>> read_cogging(CoggingTable table, std::uint32_t alpha_index,
                                                            std::uint32_t beta_index);

  // --- settings --------------------------------------------------------------------------------
  asio::awaitable<Result<void>> set_speed(std::int64_t alpha_rpm, std::int64_t beta_rpm);  // at the motor
  asio::awaitable<Result<void>> set_current(std::int64_t alpha_percent, std::int64_t beta_percent);
  asio::awaitable<Result<void>> set_holding_current(std::int64_t alpha_percent, std::int64_t beta_percent);
  asio::awaitable<Result<void>> set_collision_margin(std::int64_t alpha, std::int64_t beta);  // -30..30
  asio::awaitable<Result<void>> set_offsets(ArmAngles offsets);
  // SET_CURRENT_POSITION: redefines where the robot thinks it is. Dangerous (see the document's
  // warning): follow it with a datum search near the hard stops.
  asio::awaitable<Result<void>> set_position(ArmAngles position);
  // Commands 118..125: control loop and collision detection per arm (Arm::both sends both).
  asio::awaitable<Result<void>> set_loop(Arm arm, Loop loop, bool collision_detection);
  // 128..131; gated (PositionerOptions::firmware_history): HostErrc::firmware_lacks, not sent.
  asio::awaitable<Result<void>> set_precise_move(Arm arm, bool on);
  asio::awaitable<Result<void>> set_led(bool on);                    // 126 / 127
  // 116 / 117. After switching on, the sensors take about 5 s to wake; moves before then are
  // refused with HALL_SENSORS_DISABLED.
  asio::awaitable<Result<void>> set_hall(bool on);

  // --- motion ----------------------------------------------------------------------------------
  // Stops whatever runs. abort keeps collision flags, stop clears them. Never refused.
  asio::awaitable<Result<void>> abort();
  asio::awaitable<Result<void>> stop();
  // Sends the move and returns the robot's ETA without waiting.
  asio::awaitable<Result<protocol::ArmTimes>> start_goto(ArmAngles position, bool relative);
  // Moves, waits for DISPLACEMENT_COMPLETED, reads the position back and checks it.
  asio::awaitable<Result<MoveResult>> goto_absolute(ArmAngles target);
  asio::awaitable<Result<MoveResult>> goto_relative(ArmAngles delta);
  // Polls until DISPLACEMENT_COMPLETED (collision flag: HostErrc::collision).
  asio::awaitable<Result<protocol::PositionerStatus>> wait_until_idle(core::Duration timeout);

  // Datum search (20, 21, 22); waits for DATUM_<arm>_INITIALIZED and the end of the search. The
  // arms drive into their hard stops: make sure nothing is in the way.
  asio::awaitable<Result<protocol::PositionerStatus>> go_to_datums(Arm arm = Arm::both);
  // Calibrations (26..28, 23..25, 47..49); each waits for DISPLACEMENT_COMPLETED, the end of its
  // calibration mode and its calibrated flags. save_calibration writes everything to flash (53).
  asio::awaitable<Result<protocol::PositionerStatus>> calibrate_motors(Arm arm = Arm::both);
  asio::awaitable<Result<protocol::PositionerStatus>> calibrate_datums(Arm arm = Arm::both);
  asio::awaitable<Result<protocol::PositionerStatus>> calibrate_cogging(Arm arm = Arm::both);
  asio::awaitable<Result<void>> save_calibration();
  // The sequence of the document's calibration chapter: motors, datums, cogging, save.
  asio::awaitable<Result<CalibrationReport>> calibrate(CalibrationPlan plan);

  // Uploads a trajectory (SEND_NEW_TRAJECTORY, every point with its reply checked, at most
  // trajectory_window in flight, TRAJECTORY_DATA_END). Does not start it. Refused while locked
  // (stage not_sent, error HostErrc::locked).
  asio::awaitable<UploadResult> upload_trajectory(const protocol::Trajectory& trajectory);

  // Waits until `done(status)` holds, polling; fails on a collision flag (and tells the gate), on
  // the lock being held (when `motion`: HostErrc::locked), or after `timeout`. `what` names the
  // step in errors.
  asio::awaitable<Result<protocol::PositionerStatus>> wait_for(
      std::function<bool(const protocol::PositionerStatus&)> done, core::Duration timeout, std::string what,
      bool motion = true);

 private:
  // HostErrc::locked while the client's lock is held (a motion step under way ends).
  Result<void> still_free() const;
  asio::awaitable<Result<void>> simple(protocol::CommandId c);
  // HostErrc::firmware_lacks when the robot's known application version lacks `c` (or, for
  // GET_STATUS, the status layout).
  [[nodiscard]] Result<void> firmware_gate(protocol::CommandId c) const;
  asio::awaitable<Result<MoveResult>> move(ArmAngles value, bool relative);
  // wait_for a step the robot runs; stops the robot when the host gives up on it.
  asio::awaitable<Result<protocol::PositionerStatus>> watch_motion(std::function<bool(const protocol::PositionerStatus&)> done,
                                                                   core::Duration timeout, std::string what);
  asio::awaitable<Result<protocol::PositionerStatus>> run_step(protocol::CommandId c, core::Duration timeout,
                                                               std::function<bool(const protocol::PositionerStatus&)> done,
                                                               std::string what);

  CommandClient* client_;
  std::uint16_t id_;
  PositionerOptions options_;
  MotionGate* gate_;
  std::optional<protocol::FirmwareVersion> firmware_;
  std::optional<protocol::PositionerStatus> status_;
  std::optional<protocol::BootloaderStatus> boot_status_;
};

}  // namespace axon::fps::host
