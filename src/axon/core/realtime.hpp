// Real-time set-up for the calling thread: SCHED_FIFO priority, locked memory, CPU affinity.
// Each step reports whether the kernel granted it. A refusal is a warning, not a failure: the
// program still runs, with worse timing, and the report says why.
#pragma once

#include <string>
#include <vector>

namespace axon::core {

struct RealtimeRequest {
  int fifo_priority = 0;     // 1..99 asks for SCHED_FIFO; 0 leaves the policy alone
  bool lock_memory = false;  // mlockall(MCL_CURRENT | MCL_FUTURE)
  std::vector<int> cpus;     // pin the thread to these CPUs; empty leaves affinity alone
};

struct RealtimeStep {
  std::string name;    // "SCHED_FIFO 80", "mlockall", "affinity 1"
  bool granted = false;
  std::string reason;  // why it was refused, and what to do
};

struct RealtimeReport {
  std::vector<RealtimeStep> steps;
  [[nodiscard]] bool all_granted() const noexcept;
  [[nodiscard]] std::string summary() const;  // one line per step
};

// Applies the request to the calling thread and logs a warning for each refused step.
RealtimeReport apply_realtime(const RealtimeRequest& request);

}  // namespace axon::core
