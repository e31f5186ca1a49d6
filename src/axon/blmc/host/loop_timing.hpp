// Timing bookkeeping of a periodic loop: period, jitter (|period - nominal|), wake-up lateness,
// compute time and overruns. Pure and allocation-free: the loop feeds it time stamps from its
// clock, tests feed it a manual clock.
//
// Jitter percentiles come from a core::LatencyHistogram of 1 us buckets up to 5 ms, allocated at
// construction (larger values land in its overflow bucket and read as the exact maximum).
#pragma once

#include "axon/core/clock.hpp"
#include "axon/core/latency_histogram.hpp"

#include <cstdint>

namespace axon::blmc::host {

struct LoopStats {
  std::uint64_t cycles = 0;
  std::uint64_t overruns = 0;  // cycles that finished after the next cycle's deadline
  std::uint64_t missed = 0;    // deadlines skipped to catch up after an overrun
  core::Duration nominal{0};
  core::Duration period_min{0}, period_max{0}, period_mean{0};
  core::Duration jitter_max{0}, jitter_p50{0}, jitter_p99{0};  // |period - nominal|
  core::Duration late_max{0}, late_mean{0};                    // wake-up after the deadline
  core::Duration compute_max{0}, compute_mean{0};              // start to end of a cycle
};

class LoopTiming {
 public:
  static constexpr std::size_t kBuckets = 5000;  // 1 us each

  explicit LoopTiming(core::Duration nominal) : nominal_(nominal), jitter_(1000, kBuckets) {}

  // A cycle began at `actual`; it was due at `deadline`.
  void cycle_started(core::TimePoint deadline, core::TimePoint actual) noexcept;
  // The cycle that began last ended at `end`; the next one is due at `next_deadline`.
  void cycle_finished(core::TimePoint end, core::TimePoint next_deadline) noexcept;
  // `n` deadlines were skipped.
  void skipped(std::uint64_t n) noexcept { missed_ += n; }

  [[nodiscard]] LoopStats stats() const noexcept;
  [[nodiscard]] std::uint64_t cycles() const noexcept { return cycles_; }
  [[nodiscard]] std::uint64_t overruns() const noexcept { return overruns_; }
  [[nodiscard]] core::Duration last_period() const noexcept { return last_period_; }

 private:
  core::Duration nominal_;
  std::uint64_t cycles_ = 0, periods_ = 0, overruns_ = 0, missed_ = 0;
  core::TimePoint prev_start_{};
  core::Duration last_period_{0};
  core::Duration period_min_ = core::Duration::max(), period_max_{0};
  core::Duration period_sum_{0}, jitter_max_{0}, late_max_{0}, late_sum_{0}, compute_max_{0}, compute_sum_{0};
  core::LatencyHistogram jitter_;  // ns
};

}  // namespace axon::blmc::host
