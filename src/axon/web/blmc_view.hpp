// web::BlmcView: the blmc page's data for the boards a host process drives: per board both motors'
// current, position and velocity as scope traces, the status flags, the error code with its
// meaning, the safety limits in force and how a safety stop ended a run; per loop the cycles,
// overruns and a jitter histogram (|period - nominal|).
//
// Where the data comes from: the control loop's CycleRecords, which the real-time thread already
// hands over through its lock-free queue and host::run_control drains on the bus thread
// (ControlHooks::record); or, without a control loop (`axon blmc monitor`), the board's latest
// Measurements at each refresh. Nothing here runs on the real-time thread. The traces are
// decimated here: at most sample_hz samples a second are kept, the last history_s seconds of them
// (a page that connects late still gets them), not the 1000 records a second of the loop.
//
// Errors by code count the status frames whose error code changed to a non-zero one (a new board
// error), per code; safety stops count the runs a host::Fault ended, by its kind (stale data,
// board error, ...).
//
// Threading: one thread, the owner's (the bus's event loop): it feeds the view and publishes to a
// Source (source.hpp), which hands the text to the web server's thread. Throws axon::Exception
// (CoreErrc::invalid_argument) for no boards, more than host::kMaxBoards, a sample rate or history
// that is not > 0.
#pragma once

#include "axon/blmc/host/control_loop.hpp"
#include "axon/blmc/host/measurements.hpp"
#include "axon/blmc/host/safety.hpp"
#include "axon/web/source.hpp"

#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace axon::web {

struct BlmcBoardInfo {
  std::string name;                          // e.g. the bus's short name, "can0"
  std::optional<blmc::host::SafetyLimits> limits;  // in force; none while only monitoring
};

struct BlmcViewOptions {
  std::vector<BlmcBoardInfo> boards;         // in the loop's order
  double sample_hz = 50;                     // scope samples per second kept
  double history_s = 12;                     // seconds of samples kept
  core::Duration nominal_period = std::chrono::milliseconds(1);  // the loop's
  std::string command;                       // what the process runs ("pd", "monitor"): shown on the page
};

class BlmcView {
 public:
  explicit BlmcView(BlmcViewOptions options);
  ~BlmcView();
  BlmcView(const BlmcView&) = delete;
  BlmcView& operator=(const BlmcView&) = delete;

  // Every record the loop produced, in order (ControlHooks::record). Samples are taken at
  // sample_hz of the records' own time; the loop counters and the jitter histogram see all.
  void add_record(const blmc::host::CycleRecord& record);
  // Without a control loop: board `board`'s latest measurements, `t_s` seconds after the start.
  void add_measurements(std::size_t board, double t_s, const blmc::host::Measurements& m);
  // Only the status byte of board `board` (after a run: the board's status as it goes on).
  void set_status(std::size_t board, std::uint8_t status_byte);
  // The run ended: its exact statistics and the fault that stopped it, if one did.
  void end_run(const blmc::host::LoopStats& stats, const std::optional<blmc::host::LoopFault>& fault);

  // What does not change: the boards and their limits, the status flags' and error codes' meanings,
  // the jitter histogram's buckets, the sample rate.
  [[nodiscard]] std::string info_json() const;
  // {t_s, command, running, loop: {...} or null, boards: [{name, status, error, tripped, fault,
  //  limits, samples: {t, i1, i2, p1, p2, v1, v2}}]} (A, motor rev, krpm).
  [[nodiscard]] std::string state_json() const;
  // Prometheus text (metrics_text.hpp): axon_blmc_* (docs/dashboard.md).
  [[nodiscard]] std::string metrics() const;

  // The state to `source`; the metrics too every `metrics_every`-th call.
  void publish(Source& source, unsigned metrics_every = 10);

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

// The meaning of a status error code (0..7, 6 the one the spec leaves undefined), for people.
[[nodiscard]] std::string_view blmc_error_meaning(std::uint8_t code) noexcept;

}  // namespace axon::web
