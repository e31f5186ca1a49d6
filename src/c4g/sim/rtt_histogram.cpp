#include "c4g/sim/rtt_histogram.hpp"

#include <algorithm>
#include <cmath>

namespace axon::c4g::sim {

void RttHistogram::add(std::int64_t ns) noexcept {
  if (ns < 0) ns = 0;
  const auto bin = std::min<std::size_t>(static_cast<std::size_t>(ns / kBinNs), kBins);
  ++bins_[bin];
  ++count_;
  sum_ += ns;
  max_ = std::max(max_, ns);
  min_ = std::min(min_, ns);
}

std::int64_t RttHistogram::percentile(double p) const noexcept {
  if (count_ == 0) return 0;
  const auto need = static_cast<std::uint64_t>(std::ceil(std::clamp(p, 0.0, 1.0) * static_cast<double>(count_)));
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < bins_.size(); ++i) {
    seen += bins_[i];
    if (seen >= std::max<std::uint64_t>(need, 1)) {
      if (i == kBins) return max_;
      return std::min(max_, static_cast<std::int64_t>(i + 1) * kBinNs);  // upper edge of the bin
    }
  }
  return max_;
}

std::uint64_t RttHistogram::count_at_or_above(std::int64_t ns) const noexcept {
  const auto first = std::min<std::size_t>(static_cast<std::size_t>(std::max<std::int64_t>(ns, 0) / kBinNs), kBins);
  std::uint64_t n = 0;
  for (std::size_t i = first; i < bins_.size(); ++i) n += bins_[i];
  return n;
}

}  // namespace axon::c4g::sim
