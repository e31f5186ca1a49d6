// Logging set-up. Code logs through spdlog directly (spdlog::info(...)); this sets the level and
// format once, from the command line. Never log inside a real-time cycle: hand data to a
// non-real-time thread through a lock-free queue instead.
#pragma once

#include <spdlog/spdlog.h>

#include <cstdint>

namespace axon::core {

// verbosity: 0 = info (default), 1 = debug (-v), 2+ = trace (-vv), negative = warnings only (-q).
spdlog::level::level_enum level_for_verbosity(int verbosity) noexcept;

// Logs to stderr with a timestamp and level; safe to call again to change the level.
void init_logging(int verbosity);

// Whether the count-th event of a kind (1, 2, ...) is logged when a flood of them is logged on the
// first and every n-th after it: a hostile peer cannot fill the log, and the count says how many.
[[nodiscard]] constexpr bool first_or_every(std::uint64_t count, std::uint64_t n) noexcept {
  return n != 0 && count % n == 1 % n;
}

}  // namespace axon::core
