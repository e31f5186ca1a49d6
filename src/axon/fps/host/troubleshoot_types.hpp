// The results and settings of the troubleshooting diagnostics (host/troubleshoot.hpp): plain
// values, no Asio, shared by the coroutine API, fps::Client, the CLI and the Python module.
//
// Interface document 9.4.2: a robot whose gear has grown stiffer reports collisions it did not
// have. Its current against speed follows a stiction plus viscous model, and the trend of that
// curve over the robot's life tells friction apart from a real obstacle. 9.4.3: when raising the
// collision margin does not help, a test in open loop without collision detection tells a broken
// hall sensor or motor phase from a working one.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace axon::fps::host {

// ---- Friction (9.4.2) ------------------------------------------------------------------------

// The arm's current at one motor speed, from GET_POSITION_AND_CURRENT readings taken while the
// arm was between 10 % and 90 % of a test move (the ends, where it accelerates or makes its
// precise approach, are left out).
struct FrictionPoint {
  double speed_rpm = 0;        // at the motor
  double current_percent = 0;  // median of the readings
  int readings = 0;
  double move_s = 0;           // the test moves' wall time there and back, start to DISPLACEMENT_COMPLETED
  double eta_s = 0;            // what the robot announced for them
};

// current = stiction + viscous * rpm / 1000, least squares.
struct FrictionFit {
  double stiction_percent = 0;
  double viscous_percent_per_krpm = 0;
  double rms_percent = 0;  // residual
  [[nodiscard]] double at(double rpm) const noexcept { return stiction_percent + viscous_percent_per_krpm * rpm / 1000.0; }
};

// Fits the points (nullopt with fewer than two distinct speeds).
std::optional<FrictionFit> fit_friction(std::span<const FrictionPoint> points);

// One line of a robot's friction history: one arm's fit at one time.
struct FrictionRecord {
  std::string time_utc;  // 2026-12-02T03:04:05Z: the records of an arm sort by it
  std::uint16_t id = 0;
  char arm = 'a';        // 'a' alpha, 'b' beta
  FrictionFit fit;
  double move_ratio = 0;  // the test moves' time over the robot's announced time (0: not measured)
};

enum class FrictionVerdict : std::uint8_t {
  ok,         // within the growth limit of the arm's first record
  increased,  // grown beyond it: more friction than when the history began
  baseline,   // no earlier record: this one starts the history
  failed,     // not measured (problem says why)
};
const char* to_string(FrictionVerdict v) noexcept;

struct FrictionFinding {
  std::uint16_t id = 0;
  char arm = 'a';
  FrictionVerdict verdict = FrictionVerdict::failed;
  std::vector<FrictionPoint> points;
  std::optional<FrictionFit> fit;
  double move_ratio = 0;
  std::optional<FrictionRecord> baseline;  // the arm's oldest record
  double growth = 0;       // current at the reference speed: now over the baseline, minus 1
  double move_growth = 0;  // move_ratio: now over the baseline's, minus 1 (0 when either is missing)
  double step_deg = 0;     // the test move used (signed)
  std::string problem;     // failed: why
  std::string advice;      // increased or failed: what to do
};

struct FrictionOptions {
  std::vector<double> speeds_rpm{1000, 2000, 3000, 4000};  // motor speeds of the test moves
  double step_deg = 10;          // each test move, at the arm; the sign that is clear of everything
  double reference_rpm = 3000;   // the speed the trend compares the fitted current at
  double growth_limit = 0.25;    // verdict increased beyond this growth
  std::uint32_t restore_speed_rpm = 2000;  // SET_SPEED afterwards (a robot's speed cannot be read)
  bool alpha = true;
  bool beta = true;
  std::vector<FrictionRecord> history;  // earlier records (load_friction_history)
  std::string time_utc;                 // stamped on the new records; empty: now
};

struct FrictionReport {
  std::string time_utc;               // when the survey ran (its records carry it)
  std::vector<FrictionFinding> arms;  // per robot, alpha then beta
  // Nothing increased or failed.
  [[nodiscard]] bool ok() const noexcept;
  // The new fits, for the history file.
  [[nodiscard]] std::vector<FrictionRecord> records() const;
  // One line per arm, then the advice.
  [[nodiscard]] std::string summary() const;
};

// The verdict of one measured arm (points, fit, move_ratio filled) against the history: pure.
FrictionFinding judge_friction(FrictionFinding measured, std::span<const FrictionRecord> history,
                               const FrictionOptions& options);

// ---- Hall sensors and motors (9.4.3) ---------------------------------------------------------

enum class HallVerdict : std::uint8_t {
  ok,              // the hall reading followed the move within the tolerance of the position
  no_hall_change,  // the step counter moved, the hall reading did not: sensor or motor
  inaccurate,      // the hall reading moved but ends farther than the tolerance from the position
  failed,          // not tested (problem says why)
};
const char* to_string(HallVerdict v) noexcept;

struct HallFinding {
  std::uint16_t id = 0;
  char arm = 'a';
  HallVerdict verdict = HallVerdict::failed;
  double step_deg = 0;  // the open-loop test move (signed)
  double hall_before_deg = 0, hall_after_deg = 0;          // GET_HALL_POSITION (44)
  double position_before_deg = 0, position_after_deg = 0;  // GET_CURRENT_POSITION (32)
  double tracking_error_deg = 0;  // |hall - position| after the move
  bool restored = false;          // closed loop with collision detection again afterwards
  std::string problem;
  std::string advice;
};

struct HallTestOptions {
  double step_deg = 5;               // a few degrees
  std::uint32_t speed_rpm = 1000;    // low speed, as the document says
  double tolerance_deg = 0.04;       // the document's tracking bound
  std::uint32_t restore_speed_rpm = 2000;
  bool alpha = true;
  bool beta = true;
};

struct HallTestReport {
  std::vector<HallFinding> arms;
  [[nodiscard]] bool ok() const noexcept;  // every arm ok
  [[nodiscard]] std::string summary() const;
};

}  // namespace axon::fps::host
