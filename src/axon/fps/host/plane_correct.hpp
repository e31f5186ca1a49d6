// Correction iterations on the robots of an Array (interface document, normal operation: after a
// move the fibres are measured; robots outside the required precision get a correction move).
//
// One round: read the commanded angles of every targeted robot (GET_CURRENT_POSITION, all at
// once), decide with plan_corrections() (correction.hpp), send GO_TO_ABSOLUTE_POSITION to every
// robot outside tolerance at once (all buses concurrently, Array::goto_absolute), wait for every
// one to arrive and report per robot: error before, correction sent, result.
//
// correct_positions() repeats rounds, each with the next measurement from a caller-supplied
// source, until every robot is within tolerance, a round has nothing left to send, or the source
// has no further measurement. At most `iterations` rounds send corrections; the measurement after
// the last of them is still read and reported (nothing more is sent).
#pragma once

#include "axon/fps/host/array.hpp"
#include "axon/fps/host/correction.hpp"

#include <boost/asio/awaitable.hpp>

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace axon::fps::host {

struct CorrectionRound {
  int round = 0;                               // 1-based
  std::string source;                          // the measurement's file name
  CorrectionPlan plan;
  std::map<std::int32_t, std::string> results; // per robot moved: "arrived" or the error
  std::map<std::int32_t, ArmAngles> reached;   // per robot that arrived
  bool evaluate_only = false;                  // the check after the last allowed iteration
  std::size_t sent = 0;
  std::size_t arrived = 0;

  [[nodiscard]] bool all_arrived() const noexcept { return arrived == sent; }
  // A header line, then one line per robot (error, correction, result) and the notes.
  [[nodiscard]] std::string to_text() const;
};

// One round. With `send` false the corrections are computed and reported but not sent (the check
// after the last allowed iteration). Errors only when nothing could be done (the array is locked).
asio::awaitable<Result<CorrectionRound>> correction_round(Array& array, const plan::CollisionModel& model,
                                                          std::span<const plan::Target> targets,
                                                          const MeasurementSet& measured,
                                                          const CorrectionOptions& options = {}, int round = 1,
                                                          bool send = true);

// Gives the measurement for round `round` (1-based); nullopt when there is none (the run ends).
using MeasurementSource = std::function<asio::awaitable<Result<std::optional<MeasurementSet>>>(int round)>;

// Waits (polling every 100 ms) until `path` exists and its size is the same on two polls in a row
// (a file still being written is not read), at most `wait_s` seconds; `on_waiting(path)` once when
// the file is not there at the first look. CoreErrc::invalid_argument, naming the file, at the end.
asio::awaitable<Result<void>> wait_for_file(const std::string& path, double wait_s,
                                            const std::function<void(const std::string&)>& on_waiting = {});

// Measurements from files, one a round, as `axon fps plane correct --measured` reads them: round k
// reads files[k-1] (load_measurements, robots outside `known_robots` refused), from the second
// round on after wait_for_file() (the instrument writes it after the moves); no more rounds after
// the last file.
MeasurementSource measurement_files(std::vector<std::string> files, std::vector<std::int32_t> known_robots,
                                    double wait_s, std::function<void(const std::string&)> on_waiting = {});

struct CorrectionRunOptions {
  CorrectionOptions correction;
  int iterations = 3;                                   // most correction moves (the document: 1..3)
  std::function<void(const CorrectionRound&)> on_round; // after each round
};

struct CorrectionRun {
  std::vector<CorrectionRound> rounds;
  bool converged = false;          // the last measurement had every targeted robot within tolerance
  bool verified = false;           // the last round read a measurement taken after the last correction
  std::optional<Error> stopped_by; // a measurement or round that failed
  std::string end;                 // why the run ended, one line

  // exit-code view: converged, or every correction arrived and nothing was unreachable
  [[nodiscard]] bool ok() const noexcept;
  [[nodiscard]] std::string summary() const;
};

asio::awaitable<CorrectionRun> correct_positions(Array& array, const plan::CollisionModel& model,
                                                 std::vector<plan::Target> targets, MeasurementSource next,
                                                 CorrectionRunOptions options = {});

}  // namespace axon::fps::host
