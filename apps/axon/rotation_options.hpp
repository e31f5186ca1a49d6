// The options that put a size or age limit on a recording file (candump log, pcap capture, CSV),
// the same for every command that records: --NAME-max-size, --NAME-max-seconds, --NAME-keep.
#pragma once

#include "checks.hpp"
#include "axon/core/rotating_file.hpp"

#include <CLI/CLI.hpp>

#include <chrono>
#include <string>

namespace axon::app {

struct RotationArgs {
  std::uint64_t max_bytes = 0;
  double max_seconds = 0;
  unsigned keep = 10;

  [[nodiscard]] core::RotationLimits limits() const {
    core::RotationLimits l;
    l.max_bytes = max_bytes;
    l.max_age = std::chrono::duration_cast<core::Duration>(std::chrono::duration<double>(max_seconds));
    l.keep = keep;
    return l;
  }
};

// Adds the three options for the file option `file_option` (e.g. "--log"), which they need.
inline void add_rotation_options(CLI::App* cmd, RotationArgs& args, const std::string& name, const std::string& file_option) {
  cmd->add_option("--" + name + "-max-size", args.max_bytes,
                  "rotate " + file_option + " before it passes this size (bytes; k, M, G suffixes): the full file "
                  "becomes FILE.1, the older ones FILE.2 ...")
      ->transform(CLI::AsSizeValue(false))
      ->needs(file_option);
  cmd->add_option("--" + name + "-max-seconds", args.max_seconds, "rotate " + file_option + " once it is this many seconds old")
      ->check(positive())
      ->needs(file_option);
  cmd->add_option("--" + name + "-keep", args.keep, "rotated files kept, FILE.1 .. FILE.N (default 10; older ones are deleted)")
      ->check(between(1, 100000))
      ->needs(file_option);
}

}  // namespace axon::app
