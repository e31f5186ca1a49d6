// Fault plans: which frames a simulated medium or device mistreats, and how.
// A rule matches frames with a Filter, lets `skip` matching frames through, then applies its
// action to the next `count` matching frames, each with `probability` (seeded, reproducible).
#pragma once

#include "axon/can/bus.hpp"
#include "axon/core/config.hpp"

#include <cstdint>
#include <limits>
#include <random>
#include <vector>

namespace axon::can {

struct FaultRule {
  enum class Action : std::uint8_t {
    drop,       // the frame never reaches anyone (as if lost; counted by the medium)
    delay,      // delivered `delay` later
    duplicate,  // delivered twice
    corrupt,    // delivered with payload bits flipped (a misbehaving device: CRC can't save you)
  };
  Action action = Action::drop;
  Filter match{};  // default: every frame
  std::uint64_t skip = 0;
  std::uint64_t count = std::numeric_limits<std::uint64_t>::max();
  double probability = 1.0;
  core::Duration delay{0};
  std::uint8_t corrupt_xor = 0xFF;  // bits flipped in every payload byte
};

struct FaultPlan {
  std::vector<FaultRule> rules;
  std::uint64_t seed = 1;

  // YAML: { seed: 1, rules: [ { action: drop, id: 0x123, mask: 0x7FF, format: standard, skip: 2,
  //         count: 1, probability: 1.0 } ] }
  // action (required): drop | delay | duplicate | corrupt. id alone matches exactly that id
  // (mask 0x1FFFFFFF); neither id nor mask matches every frame; format: any | standard | extended.
  // delay_ms (> 0, fractions allowed) is required with delay and refused elsewhere; xor (1..0xFF,
  // default 0xFF) only with corrupt. Unknown keys and out-of-range values are errors that name
  // file:line:column and the key path (e.g. rules[2].probability).
  static Result<FaultPlan> from_config(const core::ConfigNode& node);
};

// Applies a plan to a stream of frames (keeps the per-rule counters and the random generator).
class FaultInjector {
 public:
  struct Decision {
    bool drop = false;
    bool duplicate = false;
    bool corrupted = false;
    core::Duration delay{0};
    Frame frame;  // possibly corrupted
  };
  FaultInjector() = default;
  explicit FaultInjector(FaultPlan plan);
  // What happens to this frame; the first matching rule that fires decides, and the rules after
  // it do not see the frame. A corrupt rule ignores frames without payload (remote or empty).
  Decision apply(const Frame& frame);
  [[nodiscard]] bool empty() const noexcept { return plan_.rules.empty(); }

 private:
  FaultPlan plan_;
  std::vector<std::uint64_t> seen_;
  std::mt19937_64 rng_{1};
};

}  // namespace axon::can
