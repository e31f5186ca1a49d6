// Builds one of the built-in applications from settings in the units a person types (degrees,
// file names, "MOTION_TYPE=FILE.csv" segments): what `axon c4g serve --app NAME ...` runs, for a
// program, a configuration file or a binding that picks the application by name.
//
// The applications themselves take their own option structs (stream.hpp, correct.hpp, pid.hpp,
// contribute.hpp, handover.hpp) in SI units; use those directly when writing C++.
// Errors: make_app throws axon::Exception (CoreErrc::invalid_argument, or the file's error) saying
// which setting is wrong.
#pragma once

#include "axon/c4g/apps/app.hpp"
#include "axon/c4g/apps/correction_limits.hpp"
#include "axon/c4g/apps/stream.hpp"
#include "axon/c4g/apps/trajectory.hpp"

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace axon::c4g::apps {

struct AppConfig {
  std::string app;  // monitor, echo, stream, correct, pid, handover, contribute
  // stream / correct / handover
  std::string file;                   // stream: trajectory CSV; correct: correction values CSV
  // stream: a trajectory already in memory (a table from a binding) instead of `file`; per_cycle:
  // its clock counts controller cycles (StreamOptions::per_cycle).
  std::shared_ptr<const Trajectory> trajectory;
  bool per_cycle = false;
  std::string correct_file;           // handover: correction values CSV for mode 7
  std::vector<std::string> segments;  // stream/handover: MOTION_TYPE=FILE.csv
  // stream/handover: segments already in memory (tables from a binding), played as `segments`
  // (their clocks count cycles with per_cycle); with `segments` files too, each motion type once.
  std::vector<StreamSegment> segment_tables;
  int mode = 4;                       // stream: 4 or 5; contribute: 8 or 9
  std::string units;                  // angles in the CSV files: rad or deg (empty: the file's)
  bool relative = false;
  bool rearm = false;
  double start_tolerance_deg = 0.5;
  double max_motor_speed = 100.0;     // [motor turns/s]
  std::size_t arm = 1;
  std::vector<double> amplitude;      // correct/pid: [deg, link side]; contribute: [turns/s] or [A]
  std::vector<double> frequency_hz;
  double open_time_s = 0;
  double ramp_s = 0.5;
  // correct: a live feed over UDP
  std::string feed;                   // HOST:PORT to listen on (empty: none)
  std::string feed_from;              // only this sensor HOST[:PORT]
  std::size_t feed_axes = 6;
  double feed_timeout_ms = 100;
  std::vector<double> max_correction_deg{kDefaultMaxCorrectionDeg};
  std::vector<double> max_correction_step_deg{kDefaultMaxCorrectionStepDeg};
  // pid
  std::vector<double> kp, kv, ki;
  bool no_dynamic_model = false;
  bool reduce_in_pc = false;
};

// Builds the application; `say` receives notices for the operator (e.g. where a feed listens).
std::unique_ptr<App> make_app(const AppConfig& config, const std::function<void(const std::string&)>& say = {});

}  // namespace axon::c4g::apps
