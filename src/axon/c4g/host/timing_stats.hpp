// Cycle timing of the PC side, as the manual's "PC calculated timing" chapter defines it.
//
// For cycle k the server notes t1(k), when the controller's packet has been received, and t2(k),
// when the answer has been sent. From these:
//   cycle time        = t2(k) - t1(k)          (how long the PC took to answer)
//   worst cycle time  = max over k of the cycle time
//   inter-step time   = t1(k) - t1(k-1)        (from the second cycle on)
//   inter-packet period range = [min, max] of the inter-step time
//   jitter range      = that range minus the nominal inter-packet period
//   percentage jitter = jitter / nominal period * 100
// On top of the manual's figures: fixed-bucket histograms of the cycle time and the inter-step
// time (percentiles p50/p99/p99.9 and max) and a count of cycles whose cycle time exceeded a
// configurable deadline (the manual's T_CYCLE1, 500-600 us).
//
// The nominal period is the controller's (1 or 2 ms, from its initialization packet): the Server
// sets it when that packet arrives (set_nominal_period_ns), the configuration only gives the value
// to use until then (0: unknown). The measured times are kept raw, so every figure relative to the
// nominal period (jitter, percentage jitter) is computed when read, against the period in force.
//
// record() is for one thread (the cycle thread): no allocation, no lock. Everything else may be
// read from any thread while it runs.
#pragma once

#include "axon/core/latency_histogram.hpp"

#include <atomic>
#include <cstdint>
#include <string>

namespace axon::c4g::host {

struct TimingConfig {
  std::int64_t nominal_period_ns = 0;          // the controller's inter-packet period; 0: unknown until set
  std::int64_t deadline_ns = 500'000;          // answer deadline counted as missed above this
  std::int64_t bucket_width_ns = 1'000;        // histogram resolution
  std::size_t buckets = 20'000;                // histogram range = width * buckets (20 ms)
};

class TimingStats {
 public:
  explicit TimingStats(const TimingConfig& config = {});

  // One cycle: t1 = request received, t2 = answer sent, both on one monotonic clock (ns).
  void record(std::int64_t t1_ns, std::int64_t t2_ns) noexcept;
  // The next cycle starts a new inter-step series (after a planned pause, e.g. a freeze).
  void restart_inter_step() noexcept;
  // Writer side, or while the writer is stopped.
  void reset() noexcept;

  [[nodiscard]] const TimingConfig& config() const noexcept { return config_; }
  // Any thread. ns <= 0: unknown (the jitter figures are then 0 and the summary says so).
  void set_nominal_period_ns(std::int64_t ns) noexcept { put(nominal_, ns > 0 ? ns : std::int64_t{0}); }
  [[nodiscard]] std::int64_t nominal_period_ns() const noexcept { return load(nominal_); }
  [[nodiscard]] bool nominal_known() const noexcept { return nominal_period_ns() > 0; }
  [[nodiscard]] std::uint64_t cycles() const noexcept { return load(cycles_); }
  [[nodiscard]] std::int64_t last_cycle_time_ns() const noexcept { return load(last_cycle_); }
  [[nodiscard]] std::int64_t worst_cycle_time_ns() const noexcept { return load(worst_cycle_); }
  [[nodiscard]] std::uint64_t inter_steps() const noexcept { return load(inter_steps_); }
  [[nodiscard]] std::int64_t last_inter_step_ns() const noexcept { return load(last_inter_step_); }
  [[nodiscard]] std::int64_t min_inter_step_ns() const noexcept { return load(min_inter_step_); }
  [[nodiscard]] std::int64_t max_inter_step_ns() const noexcept { return load(max_inter_step_); }
  // Relative to the nominal period; 0 while it is unknown or before two cycles.
  [[nodiscard]] std::int64_t min_jitter_ns() const noexcept;
  [[nodiscard]] std::int64_t max_jitter_ns() const noexcept;
  [[nodiscard]] double min_percent_jitter() const noexcept;
  [[nodiscard]] double max_percent_jitter() const noexcept;
  [[nodiscard]] std::uint64_t missed_deadlines() const noexcept { return load(missed_); }

  [[nodiscard]] const core::LatencyHistogram& cycle_times() const noexcept { return cycle_hist_; }
  [[nodiscard]] const core::LatencyHistogram& inter_step_times() const noexcept { return inter_hist_; }

  // Multi-line report in seconds, in the manual's layout, followed by percentiles and misses.
  [[nodiscard]] std::string summary() const;

 private:
  template <class T>
  static T load(const std::atomic<T>& a) noexcept {
    return a.load(std::memory_order_relaxed);
  }
  template <class T>
  static void put(std::atomic<T>& a, T v) noexcept {
    a.store(v, std::memory_order_relaxed);
  }

  TimingConfig config_;
  std::atomic<std::int64_t> nominal_{0};
  bool have_t1_ = false;  // writer only
  std::int64_t last_t1_ = 0;
  std::atomic<std::uint64_t> cycles_{0};
  std::atomic<std::int64_t> last_cycle_{0};
  std::atomic<std::int64_t> worst_cycle_{0};
  std::atomic<std::uint64_t> inter_steps_{0};
  std::atomic<std::int64_t> last_inter_step_{0};
  std::atomic<std::int64_t> min_inter_step_{0};
  std::atomic<std::int64_t> max_inter_step_{0};
  std::atomic<std::uint64_t> missed_{0};
  core::LatencyHistogram cycle_hist_;
  core::LatencyHistogram inter_hist_;
};

}  // namespace axon::c4g::host
