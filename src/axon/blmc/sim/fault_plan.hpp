// Fault plans for a simulated board: faults the firmware detects at a given time, and a link that
// loses or stalls frames. Times are measured from the board's power-up.
//
// YAML (docs/blmc-simulator.md):
//   seed: 1
//   events:                       # the firmware raises the error at at_s
//     - { at_s: 2.0, kind: encoder }      # encoder | pos_converter | transmit | over_current | undocumented
//     - { at_s: 5.0, kind: over_current, duration_s: 1 }  # the cause lasts 1 s: recovery is refused meanwhile
//     - { at_s: 9.0, kind: pos_converter, persistent: true }  # until power-cycled
//   stalls:                       # the board's CAN link is dead for a window
//     - { from_s: 3.0, until_s: 3.5, direction: both }    # rx (hears nothing) | tx (sends nothing) | both
//   drops:                        # frames lost at random (seeded), within an optional window
//     - { direction: tx, probability: 0.01, from_s: 0, until_s: 10 }
//
// A host that is late is not a board fault: a test models it by not sending.
#pragma once

#include "axon/core/clock.hpp"
#include "axon/core/config.hpp"
#include "axon/core/error.hpp"

#include <cstdint>
#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

namespace axon::blmc::sim {

enum class FaultKind : std::uint8_t {
  encoder,        // error 1
  pos_converter,  // error 4
  transmit,       // reported as 7 (OTHER), ranked second
  over_current,   // the board has no code for it: reported as 7 (OTHER), ranked below the others
  undocumented,   // an error reported with code 6, which the spec does not define (a newer
                  // firmware's code, say): latched and disabling like any error, ranked last
};
std::string_view name(FaultKind k) noexcept;

struct FaultEvent {
  core::Duration at{0};
  FaultKind kind = FaultKind::encoder;
  // How long the cause lasts: 0 = a glitch (latched; the recovery sequence clears it), otherwise
  // ENABLE_SYS=1 is refused until at + duration.
  core::Duration duration{0};
  bool persistent = false;  // the cause lasts until the board is power-cycled
};

enum class LinkDirection : std::uint8_t { rx, tx, both };

struct StallWindow {
  core::Duration from{0};
  core::Duration until{0};
  LinkDirection direction = LinkDirection::both;
};

struct DropRule {
  LinkDirection direction = LinkDirection::both;
  double probability = 0.0;  // 0..1
  core::Duration from{0};
  core::Duration until = core::Duration::max();
};

struct BoardFaultPlan {
  std::vector<FaultEvent> events;
  std::vector<StallWindow> stalls;
  std::vector<DropRule> drops;
  std::uint64_t seed = 1;

  [[nodiscard]] bool empty() const noexcept { return events.empty() && stalls.empty() && drops.empty(); }
  [[nodiscard]] Result<void> validate() const;
  // Reads the format above; `extra_keys` are tolerated at the top level (for callers that add
  // their own, e.g. the CLI's `board`).
  static Result<BoardFaultPlan> from_config(const core::ConfigNode& node,
                                            std::initializer_list<std::string_view> extra_keys = {});
};

// The fault plan of each of `boards` boards (board i on bus can<i>) from a file: one plan (a map)
// or a list of plans; a plan with `board: N` applies to board N only, one without to every board.
// Several plans for one board add up (the last seed given wins). An empty path gives empty plans.
// Errors: the file's (CoreErrc::io, config_*), a board number outside 0..boards-1.
Result<std::vector<BoardFaultPlan>> load_fault_plans(const std::string& path, unsigned boards);

}  // namespace axon::blmc::sim
