// A histogram of durations with fixed-width buckets, allocated once at construction.
//
// One thread adds samples (the real-time cycle): add() costs a division and two relaxed atomic
// stores, never allocates, never locks. Any other thread may read counts and percentiles at the
// same time; a reading taken while samples arrive may lag by the samples in flight.
//
// Bucket 0 holds samples <= 0, bucket i (i >= 1) holds samples in ((i-1)*width, i*width], so a
// bucket's upper edge is the largest value it holds. Samples above the covered range land in an
// overflow bucket; the exact minimum and maximum
// are kept beside the buckets, so max() is exact whatever the range.
//
// One type serves every timing figure of the project: the c4g server's cycle and reply times, the
// c4g controller simulator's round trips and the blmc loop's jitter.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>

namespace axon::core {

class LatencyHistogram {
 public:
  // Covers samples up to bucket_width_ns * (buckets - 1); both must be positive.
  explicit LatencyHistogram(std::int64_t bucket_width_ns = 1'000, std::size_t buckets = 20'000);
  LatencyHistogram(const LatencyHistogram&) = delete;
  LatencyHistogram& operator=(const LatencyHistogram&) = delete;
  // Moving is for results handed back by value once the writer has stopped; the moved-from
  // histogram is left with no buckets and must not be used again.
  LatencyHistogram(LatencyHistogram&& other) noexcept;
  LatencyHistogram& operator=(LatencyHistogram&& other) noexcept;

  // Single writer. Negative samples (a clock step) count in bucket 0.
  void add(std::int64_t ns) noexcept;
  // Writer side, or when the writer is stopped.
  void reset() noexcept;

  [[nodiscard]] std::uint64_t count() const noexcept { return count_.load(std::memory_order_relaxed); }
  [[nodiscard]] std::uint64_t overflow() const noexcept { return overflow_.load(std::memory_order_relaxed); }
  [[nodiscard]] std::int64_t min() const noexcept;  // 0 when empty
  [[nodiscard]] std::int64_t max() const noexcept;  // 0 when empty
  [[nodiscard]] double mean() const noexcept;       // 0 when empty

  // Nearest-rank percentile (0 < p <= 100): the smallest bucket upper edge below which at least
  // p % of the samples lie (or on which they lie), never above max(). Resolution is one bucket width; a percentile that
  // falls in the overflow bucket reports max(). 0 when empty.
  [[nodiscard]] std::int64_t percentile(double p) const noexcept;
  // Samples above ns, overflow included; exact when ns is a multiple of the bucket width (else the
  // bucket holding ns counts whole).
  [[nodiscard]] std::uint64_t count_above(std::int64_t ns) const noexcept;

  [[nodiscard]] std::int64_t bucket_width_ns() const noexcept { return width_; }
  [[nodiscard]] std::size_t buckets() const noexcept { return buckets_; }
  [[nodiscard]] std::uint64_t bucket_count(std::size_t i) const noexcept { return counts_[i].load(std::memory_order_relaxed); }

 private:
  static void bump(std::atomic<std::uint64_t>& a) noexcept {
    a.store(a.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);  // single writer
  }

  std::int64_t width_;
  std::size_t buckets_;
  std::unique_ptr<std::atomic<std::uint64_t>[]> counts_;
  std::atomic<std::uint64_t> overflow_{0};
  std::atomic<std::uint64_t> count_{0};
  std::atomic<std::int64_t> min_{0};
  std::atomic<std::int64_t> max_{0};
  std::atomic<std::int64_t> sum_{0};
};

}  // namespace axon::core
