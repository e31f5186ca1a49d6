// The exit codes of every axon command (documented in docs/getting-started.md), and the record of
// the signal that asked a command to stop. One scheme for all commands, parse errors included.
#pragma once

#include <atomic>
#include <csignal>

namespace axon::app {

namespace exit_code_value {
inline constexpr int ok = 0;           // the command did what it was asked
inline constexpr int failed = 1;       // it ran and failed: a device refused, a check failed, not all done
inline constexpr int usage = 2;        // bad command line, option value or input file: nothing was done
inline constexpr int internal = 3;     // a bug in axon (an unexpected exception)
inline constexpr int safety_stop = 4;  // a safety check stopped the devices (collision, limit, lost link)
// 128 + N: stopped by signal N (130 SIGINT, 143 SIGTERM, 129 SIGHUP), after the devices were made safe.
inline constexpr int signal_base = 128;
}  // namespace exit_code_value

// The signals that ask a command to stop (the terminal's Ctrl-C, a service manager, a closed terminal).
inline constexpr int kStopSignals[] = {SIGINT, SIGTERM, SIGHUP};

// The first stop signal this process received (0: none). Set from signal handlers: lock-free atomic.
inline std::atomic<int>& received_stop_signal() noexcept {
  static std::atomic<int> signo{0};
  return signo;
}
inline void record_stop_signal(int signo) noexcept {
  int none = 0;
  received_stop_signal().compare_exchange_strong(none, signo);
}

// Once a command's work is over (its devices made safe, its report being printed, the process on its
// way out), a stop signal has nothing left to stop: it is ignored from then on, so that the exit
// code stays the run's. The default action would kill the process mid-exit (exit 143 for a server
// whose run ended 0, as a service manager or a script's clean-up signals it). SIGKILL and SIGQUIT
// still end a clean-up that hangs.
inline void ignore_late_stop_signals() noexcept {
  for (int s : kStopSignals) std::signal(s, SIG_IGN);
}

// "SIGINT (Ctrl-C)", "SIGTERM", "SIGHUP": for messages that say why devices were stopped.
inline const char* signal_name(int signo) noexcept {
  switch (signo) {
    case SIGINT: return "SIGINT (Ctrl-C)";
    case SIGTERM: return "SIGTERM";
    case SIGHUP: return "SIGHUP";
    case SIGQUIT: return "SIGQUIT";
    default: return "a signal";
  }
}

inline int signal_exit_code(int signo) noexcept { return exit_code_value::signal_base + signo; }

}  // namespace axon::app
