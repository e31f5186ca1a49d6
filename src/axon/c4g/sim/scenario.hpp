// The robot program the simulated controller plays: a YAML list of steps, run one after the other
// (each blocks until it is done, like the PDL2 statements it stands for).
//
//   steps:
//     - drive_on                         # DRIVE ON (mode 501 meanwhile); optional {arms: [1]}
//     - go_open: {type: A, mode: 4, arms: [1]}   # GO OPEN TYPE A|B in the mode ("4", "0'", "mode7", 9)
//                                        #   mode 2' (12) in mode 2: the program leaves mode 2 (blocks
//                                        #   until the arm is back in mode 0)
//     - wait_for_pc                      # WAIT FOR PC: until the PC's exit-from-open sequence ends
//                                        #   optional {arms: [1], timeout: 10}
//     - move: {arm: 1, deg: [10, 0, 0, 0, 0, 0], duration: 2}    # joint targets [deg] at the link
//     - delay: 0.5                       # seconds
//     - cmd: {arm: 1, value: 3}          # motion type byte of CMD ($ARM_DATA[arm].C4GOPEN_CMD[1])
//     - drive_off                        # optional {arms: [1]}
//     - freeze_passive: 0.2              # mode 502, no packets for 0.2 s, then 503 and mode 0
//     - restart                          # mode 506: a new initialization packet, then the cycle
//     - exit_open                        # mode 504: the exchange ends for good (last step only)
//     - selector: prog                   # the state selector to PROG (or auto): an arm in an open
//                                        #   mode is forced to mode 0 (ERR_C4GOPEN_SET_0_MODALITY)
//     - override: 50                     # general override [%] ($GEN_OVR): scales mode 5's increments
//     - run                              # keep running until the simulator is stopped
//
// Errors name the file, line and column (core::ConfigNode).
#pragma once

#include "axon/core/config.hpp"
#include "axon/core/error.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace axon::c4g::sim {

enum class StepKind { drive_on, drive_off, go_open, wait_for_pc, move, delay, cmd, freeze_passive, restart, exit_open, run, selector, general_override };
std::string_view to_string(StepKind k) noexcept;

enum class OpenType { a, b };

struct Step {
  StepKind kind{};
  std::vector<int> arms;                 // empty: every arm with open axes
  int arm = 1;                           // move, cmd
  std::int32_t mode = 0;                 // go_open
  OpenType type = OpenType::a;           // go_open
  std::vector<std::optional<double>> deg;  // move: per logical axis, nullopt keeps the axis where it is
  double seconds = 0;                    // move duration, delay, freeze_passive, wait_for_pc timeout (0: none)
  int value = 0;                         // cmd byte; selector: 1 PROG, 0 AUTO; override: percent
  std::string where;                     // "file:line:col" of the step, for messages
};

struct Scenario {
  std::string name;
  std::vector<Step> steps;

  static Result<Scenario> from_config(const core::ConfigNode& root);
  static Result<Scenario> load_file(const std::string& path);
  static Result<Scenario> parse(std::string_view yaml, std::string name = "<scenario>");
  // Drive on, mode 0, a move out and back, then run.
  static Scenario default_scenario();
  static std::string_view default_yaml() noexcept;
};

}  // namespace axon::c4g::sim
