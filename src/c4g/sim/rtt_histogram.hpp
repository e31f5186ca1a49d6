// Round-trip times of the cycle (send to accepted reply), as a fixed histogram: 1 us bins up to
// 20 ms plus an overflow bin; exact minimum and maximum. No allocation after construction.
#pragma once

#include <cstdint>
#include <vector>

namespace axon::c4g::sim {

class RttHistogram {
 public:
  RttHistogram() : bins_(kBins + 1, 0) {}
  void add(std::int64_t ns) noexcept;
  [[nodiscard]] std::uint64_t count() const noexcept { return count_; }
  // The smallest value v [ns] with at least p (0..1) of the samples <= v (bin resolution: 1 us).
  [[nodiscard]] std::int64_t percentile(double p) const noexcept;
  [[nodiscard]] std::int64_t max() const noexcept { return max_; }
  // Samples at or above ns (bin resolution: 1 us; ns is rounded down to its bin).
  [[nodiscard]] std::uint64_t count_at_or_above(std::int64_t ns) const noexcept;
  [[nodiscard]] std::int64_t min() const noexcept { return count_ ? min_ : 0; }
  [[nodiscard]] double mean() const noexcept { return count_ ? static_cast<double>(sum_) / static_cast<double>(count_) : 0.0; }

 private:
  static constexpr std::int64_t kBinNs = 1000;
  static constexpr std::size_t kBins = 20000;
  std::vector<std::uint64_t> bins_;
  std::uint64_t count_ = 0;
  std::int64_t sum_ = 0, max_ = 0, min_ = INT64_MAX;
};

}  // namespace axon::c4g::sim
