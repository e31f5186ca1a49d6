#pragma once
// SIGINT/SIGTERM/SIGHUP for commands whose main thread polls instead of running an io_context (the
// c4g server and controller simulator: their loops run on plain threads). While a StopSignals object
// lives, each signal bumps a counter, raises a flag and is recorded (received_stop_signal(), for the
// exit code 128+N); from the destructor on, stop signals are ignored (the command is ending:
// ignore_late_stop_signals).
#include "exit_codes.hpp"

#include <atomic>
#include <csignal>

namespace axon::app {

class StopSignals {
 public:
  StopSignals() {
    count_().store(0);
    flag_().store(false);
    struct sigaction sa{};
    sa.sa_handler = &StopSignals::on_signal;
    sigemptyset(&sa.sa_mask);
    for (int s : kStopSignals) sigaction(s, &sa, nullptr);
  }
  ~StopSignals() { ignore_late_stop_signals(); }
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

  // How many signals arrived (a second one usually means "stop now, skip the clean-up").
  int count() const noexcept { return count_().load(); }
  // The first signal's number (0: none yet).
  int signo() const noexcept { return received_stop_signal().load(); }
  // Raised by the first signal; loops that take an atomic<bool>* stop flag can watch it directly.
  std::atomic<bool>* flag() noexcept { return &flag_(); }

 private:
  static std::atomic<int>& count_() noexcept {
    static std::atomic<int> n{0};
    return n;
  }
  static std::atomic<bool>& flag_() noexcept {
    static std::atomic<bool> f{false};
    return f;
  }
  static void on_signal(int signo) noexcept {
    record_stop_signal(signo);
    count_().fetch_add(1);
    flag_().store(true);
  }
};

}  // namespace axon::app
