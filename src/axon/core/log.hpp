// Logging set-up. Code logs through spdlog directly (spdlog::info(...)); this sets the level and
// format once, from the command line. Never log inside a real-time cycle: hand data to a
// non-real-time thread through a lock-free queue instead.
#pragma once

#include <spdlog/spdlog.h>

namespace axon::core {

// verbosity: 0 = info (default), 1 = debug (-v), 2+ = trace (-vv), negative = warnings only (-q).
spdlog::level::level_enum level_for_verbosity(int verbosity) noexcept;

// Logs to stderr with a timestamp and level; safe to call again to change the level.
void init_logging(int verbosity);

}  // namespace axon::core
