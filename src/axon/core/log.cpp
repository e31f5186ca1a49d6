#include "axon/core/log.hpp"

#include <spdlog/sinks/stdout_color_sinks.h>

namespace axon::core {

spdlog::level::level_enum level_for_verbosity(int verbosity) noexcept {
  if (verbosity < 0) return spdlog::level::warn;
  if (verbosity == 0) return spdlog::level::info;
  if (verbosity == 1) return spdlog::level::debug;
  return spdlog::level::trace;
}

void init_logging(int verbosity) {
  static bool initialised = false;
  if (!initialised) {
    auto logger = spdlog::stderr_color_mt("axon");
    spdlog::set_default_logger(logger);
    spdlog::set_pattern("%H:%M:%S.%e %^%-5l%$ %v");
    initialised = true;
  }
  spdlog::set_level(level_for_verbosity(verbosity));
}

}  // namespace axon::core
