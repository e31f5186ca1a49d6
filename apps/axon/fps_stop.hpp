// Commands that move fps robots: SIGINT, SIGTERM and SIGHUP stop every robot of the array (the
// library's Array::request_stop, with the signal as the reason), the command then finishes its
// report and exits 128+N (run.hpp); what the stop reached is printed on stderr.
#pragma once

#include "exit_codes.hpp"
#include "axon/fps/host/array.hpp"

#include <fmt/format.h>

#include <cstdio>
#include <functional>

namespace axon::app {

// The stop's reason for a signal: "SIGINT (Ctrl-C) received".
inline std::string signal_stop_reason(int signo) { return fmt::format("{} received", signal_name(signo)); }

// Hands the run_command's signal hook (the body's second argument) a stop of `array`.
inline void stop_robots_on_signal(const std::function<void(std::function<void()>)>& set_on_signal, fps::host::Array& array) {
  set_on_signal([&array] { array.request_stop(signal_stop_reason(received_stop_signal().load())); });
}

// After the array closed (its stops have finished): what a signal's stop did, on stderr.
inline void report_signal_stop(const fps::host::Array& array) {
  const int signo = received_stop_signal().load();
  if (signo == 0 || !array.last_stop()) return;
  std::fprintf(stderr, "axon: %s", array.last_stop()->to_text().c_str());
  std::fflush(stderr);
}

// The exit code of a command that moved robots: 0 done, 4 when a safety stop (collision, lost
// link) locked the array, else 1. A signal's 128+N is run_command's.
inline int motion_exit_code(bool completed, const fps::host::Array& array) {
  if (completed) return exit_code_value::ok;
  return array.locked() ? exit_code_value::safety_stop : exit_code_value::failed;
}

}  // namespace axon::app
