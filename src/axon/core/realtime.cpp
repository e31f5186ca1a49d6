#include "axon/core/realtime.hpp"

#include <fmt/format.h>
#include <pthread.h>
#include <sched.h>
#include <spdlog/spdlog.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace axon::core {

bool RealtimeReport::all_granted() const noexcept {
  for (const auto& s : steps)
    if (!s.granted) return false;
  return true;
}

std::string RealtimeReport::summary() const {
  std::string out;
  for (const auto& s : steps) {
    if (s.granted) out += fmt::format("{}: granted\n", s.name);
    else out += fmt::format("{}: refused ({})\n", s.name, s.reason);
  }
  return out;
}

namespace {
std::string explain(int err, const char* hint) { return fmt::format("{}; {}", std::strerror(err), hint); }
}  // namespace

RealtimeReport apply_realtime(const RealtimeRequest& req) {
  RealtimeReport report;
  if (req.fifo_priority > 0) {
    RealtimeStep step{fmt::format("SCHED_FIFO {}", req.fifo_priority), false, {}};
    const int lo = sched_get_priority_min(SCHED_FIFO), hi = sched_get_priority_max(SCHED_FIFO);
    if (req.fifo_priority < lo || req.fifo_priority > hi) {
      step.reason = fmt::format("priority must be within {}..{}", lo, hi);
    } else {
      sched_param p{};
      p.sched_priority = req.fifo_priority;
      const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p);
      step.granted = rc == 0;
      if (rc != 0)
        step.reason = explain(rc, "run as root, grant CAP_SYS_NICE, or raise 'rtprio' in /etc/security/limits.conf");
    }
    report.steps.push_back(std::move(step));
  }
  if (req.lock_memory) {
    RealtimeStep step{"mlockall", false, {}};
    if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
      step.granted = true;
    } else {
      step.reason = explain(errno, "run as root, grant CAP_IPC_LOCK, or raise 'memlock' in /etc/security/limits.conf");
    }
    report.steps.push_back(std::move(step));
  }
  if (!req.cpus.empty()) {
    std::string list;
    cpu_set_t set;
    CPU_ZERO(&set);
    const long ncpu = sysconf(_SC_NPROCESSORS_CONF);
    bool bad = false;
    for (int c : req.cpus) {
      if (!list.empty()) list += ',';
      list += std::to_string(c);
      if (c < 0 || c >= ncpu || c >= CPU_SETSIZE) bad = true; else CPU_SET(c, &set);
    }
    RealtimeStep step{"affinity " + list, false, {}};
    if (bad) {
      step.reason = fmt::format("this machine has CPUs 0..{}", ncpu - 1);
    } else {
      const int rc = pthread_setaffinity_np(pthread_self(), sizeof(set), &set);
      step.granted = rc == 0;
      if (rc != 0) step.reason = explain(rc, "check the CPU list against the cpuset this process may use");
    }
    report.steps.push_back(std::move(step));
  }
  for (const auto& s : report.steps) {
    if (!s.granted) spdlog::warn("real-time set-up: {} refused: {} (continuing without it)", s.name, s.reason);
    else spdlog::debug("real-time set-up: {} granted", s.name);
  }
  return report;
}

}  // namespace axon::core
