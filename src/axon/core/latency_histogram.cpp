#include "axon/core/latency_histogram.hpp"

#include <cmath>
#include <stdexcept>
#include <utility>

namespace axon::core {

LatencyHistogram::LatencyHistogram(std::int64_t bucket_width_ns, std::size_t buckets)
    : width_(bucket_width_ns), buckets_(buckets) {
  if (bucket_width_ns <= 0 || buckets == 0)
    throw std::invalid_argument("LatencyHistogram: bucket width and count must be positive");
  counts_ = std::make_unique<std::atomic<std::uint64_t>[]>(buckets);
  reset();
}

LatencyHistogram::LatencyHistogram(LatencyHistogram&& other) noexcept : width_(other.width_), buckets_(0) {
  *this = std::move(other);
}

LatencyHistogram& LatencyHistogram::operator=(LatencyHistogram&& other) noexcept {
  if (this == &other) return *this;
  width_ = other.width_;
  buckets_ = other.buckets_;
  counts_ = std::move(other.counts_);
  auto take = [](auto& to, auto& from) { to.store(from.load(std::memory_order_relaxed), std::memory_order_relaxed); };
  take(overflow_, other.overflow_);
  take(min_, other.min_);
  take(max_, other.max_);
  take(sum_, other.sum_);
  take(count_, other.count_);
  other.buckets_ = 0;
  other.count_.store(0, std::memory_order_relaxed);
  return *this;
}

void LatencyHistogram::add(std::int64_t ns) noexcept {
  const std::uint64_t n = count_.load(std::memory_order_relaxed);
  if (n == 0 || ns < min_.load(std::memory_order_relaxed)) min_.store(ns, std::memory_order_relaxed);
  if (n == 0 || ns > max_.load(std::memory_order_relaxed)) max_.store(ns, std::memory_order_relaxed);
  sum_.store(sum_.load(std::memory_order_relaxed) + ns, std::memory_order_relaxed);
  const std::int64_t index = ns <= 0 ? 0 : (ns + width_ - 1) / width_;
  if (static_cast<std::uint64_t>(index) >= buckets_) bump(overflow_);
  else bump(counts_[static_cast<std::size_t>(index)]);
  // Published last: a reader that sees the count also sees a bucket for it (mostly; see header).
  count_.store(n + 1, std::memory_order_release);
}

void LatencyHistogram::reset() noexcept {
  for (std::size_t i = 0; i < buckets_; ++i) counts_[i].store(0, std::memory_order_relaxed);
  overflow_.store(0, std::memory_order_relaxed);
  min_.store(0, std::memory_order_relaxed);
  max_.store(0, std::memory_order_relaxed);
  sum_.store(0, std::memory_order_relaxed);
  count_.store(0, std::memory_order_release);
}

std::int64_t LatencyHistogram::min() const noexcept { return count() ? min_.load(std::memory_order_relaxed) : 0; }
std::int64_t LatencyHistogram::max() const noexcept { return count() ? max_.load(std::memory_order_relaxed) : 0; }

double LatencyHistogram::mean() const noexcept {
  const auto n = count();
  return n ? static_cast<double>(sum_.load(std::memory_order_relaxed)) / static_cast<double>(n) : 0.0;
}

std::int64_t LatencyHistogram::percentile(double p) const noexcept {
  const std::uint64_t n = count_.load(std::memory_order_acquire);
  if (n == 0) return 0;
  if (p > 100.0) p = 100.0;
  // Nearest rank: the ceil(p/100 * n)-th smallest sample, at least the first.
  // The small allowance keeps decimal percentages exact (99.9 % of 1000 is rank 999, not 1000).
  auto rank = static_cast<std::uint64_t>(std::ceil(p / 100.0 * static_cast<double>(n) - 1e-6));
  if (rank < 1) rank = 1;
  const std::int64_t top = max();
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < buckets_; ++i) {
    seen += counts_[i].load(std::memory_order_relaxed);
    if (seen >= rank) {
      const std::int64_t edge = static_cast<std::int64_t>(i) * width_;
      return edge < top ? edge : top;
    }
  }
  return top;  // in the overflow bucket
}

std::uint64_t LatencyHistogram::count_above(std::int64_t ns) const noexcept {
  // Bucket i holds ((i-1)w, iw]: the first bucket with anything above ns is floor(ns/w) + 1.
  if (ns < 0) return count();
  const std::int64_t first = ns / width_ + 1;
  std::uint64_t n = overflow();
  for (auto i = static_cast<std::size_t>(first); i < buckets_; ++i) n += counts_[i].load(std::memory_order_relaxed);
  return n;
}

}  // namespace axon::core
