#include "axon/blmc/host/loop_timing.hpp"

#include <algorithm>

namespace axon::blmc::host {

void LoopTiming::cycle_started(core::TimePoint deadline, core::TimePoint actual) noexcept {
  if (cycles_ > 0) {
    const core::Duration p = actual - prev_start_;
    last_period_ = p;
    period_min_ = std::min(period_min_, p);
    period_max_ = std::max(period_max_, p);
    period_sum_ += p;
    const core::Duration j = p > nominal_ ? p - nominal_ : nominal_ - p;
    jitter_max_ = std::max(jitter_max_, j);
    jitter_.add(std::chrono::duration_cast<std::chrono::nanoseconds>(j).count());
    ++periods_;
  }
  const core::Duration late = actual > deadline ? actual - deadline : core::Duration{0};
  late_max_ = std::max(late_max_, late);
  late_sum_ += late;
  prev_start_ = actual;
  ++cycles_;
}

void LoopTiming::cycle_finished(core::TimePoint end, core::TimePoint next_deadline) noexcept {
  const core::Duration c = end - prev_start_;
  compute_max_ = std::max(compute_max_, c);
  compute_sum_ += c;
  if (end > next_deadline) ++overruns_;
}

LoopStats LoopTiming::stats() const noexcept {
  LoopStats s;
  s.cycles = cycles_;
  s.overruns = overruns_;
  s.missed = missed_;
  s.nominal = nominal_;
  if (periods_ > 0) {
    s.period_min = period_min_;
    s.period_max = period_max_;
    s.period_mean = period_sum_ / static_cast<std::int64_t>(periods_);
    s.jitter_max = jitter_max_;
    s.jitter_p50 = std::chrono::nanoseconds(jitter_.percentile(50));
    s.jitter_p99 = std::chrono::nanoseconds(jitter_.percentile(99));
  }
  if (cycles_ > 0) {
    s.late_max = late_max_;
    s.late_mean = late_sum_ / static_cast<std::int64_t>(cycles_);
    s.compute_max = compute_max_;
    s.compute_mean = compute_sum_ / static_cast<std::int64_t>(cycles_);
  }
  return s;
}

}  // namespace axon::blmc::host
