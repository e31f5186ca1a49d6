#include "axon/c4g/host/timing_stats.hpp"

#include <fmt/format.h>

#include <iterator>

namespace axon::c4g::host {

TimingStats::TimingStats(const TimingConfig& config)
    : config_(config),
      nominal_(config.nominal_period_ns > 0 ? config.nominal_period_ns : 0),
      cycle_hist_(config.bucket_width_ns, config.buckets),
      inter_hist_(config.bucket_width_ns, config.buckets) {}

void TimingStats::record(std::int64_t t1, std::int64_t t2) noexcept {
  const std::int64_t cycle = t2 - t1;
  const std::uint64_t n = load(cycles_);
  put(last_cycle_, cycle);
  if (n == 0 || cycle > load(worst_cycle_)) put(worst_cycle_, cycle);
  if (cycle > config_.deadline_ns) put(missed_, load(missed_) + 1);
  cycle_hist_.add(cycle);
  if (have_t1_) {
    const std::int64_t step = t1 - last_t1_;
    const std::uint64_t m = load(inter_steps_);
    put(last_inter_step_, step);
    if (m == 0 || step < load(min_inter_step_)) put(min_inter_step_, step);
    if (m == 0 || step > load(max_inter_step_)) put(max_inter_step_, step);
    inter_hist_.add(step);
    put(inter_steps_, m + 1);
  }
  have_t1_ = true;
  last_t1_ = t1;
  put(cycles_, n + 1);
}

void TimingStats::restart_inter_step() noexcept { have_t1_ = false; }

void TimingStats::reset() noexcept {
  have_t1_ = false;
  last_t1_ = 0;
  put(cycles_, std::uint64_t{0});
  put(last_cycle_, std::int64_t{0});
  put(worst_cycle_, std::int64_t{0});
  put(inter_steps_, std::uint64_t{0});
  put(last_inter_step_, std::int64_t{0});
  put(min_inter_step_, std::int64_t{0});
  put(max_inter_step_, std::int64_t{0});
  put(missed_, std::uint64_t{0});
  cycle_hist_.reset();
  inter_hist_.reset();
}

std::int64_t TimingStats::min_jitter_ns() const noexcept {
  return inter_steps() && nominal_known() ? min_inter_step_ns() - nominal_period_ns() : 0;
}
std::int64_t TimingStats::max_jitter_ns() const noexcept {
  return inter_steps() && nominal_known() ? max_inter_step_ns() - nominal_period_ns() : 0;
}
double TimingStats::min_percent_jitter() const noexcept {
  return nominal_known() ? static_cast<double>(min_jitter_ns()) / static_cast<double>(nominal_period_ns()) * 100.0 : 0.0;
}
double TimingStats::max_percent_jitter() const noexcept {
  return nominal_known() ? static_cast<double>(max_jitter_ns()) / static_cast<double>(nominal_period_ns()) * 100.0 : 0.0;
}

namespace {
double s(std::int64_t ns) { return static_cast<double>(ns) * 1e-9; }
}  // namespace

std::string TimingStats::summary() const {
  std::string out;
  auto it = std::back_inserter(out);
  if (nominal_known())
    fmt::format_to(it, "Nominal inter-packet period       = {:.9f} s\n", s(nominal_period_ns()));
  else
    fmt::format_to(it, "Nominal inter-packet period       = unknown (no initialization packet)\n");
  fmt::format_to(it, "Cycles                            = {}\n", cycles());
  fmt::format_to(it, "Worst cycle time                  = {:.9f} s\n", s(worst_cycle_time_ns()));
  if (inter_steps() == 0) {
    fmt::format_to(it, "Measured inter-packet period range = (needs two cycles)\n");
  } else {
    fmt::format_to(it, "Measured inter-packet period range = [{:+.9f}; {:+.9f}] s\n", s(min_inter_step_ns()), s(max_inter_step_ns()));
    if (nominal_known()) {
      fmt::format_to(it, "Jitter range                      = [{:+.9f}; {:+.9f}] s\n", s(min_jitter_ns()), s(max_jitter_ns()));
      fmt::format_to(it, "Percentage jitter range           = [{:+.9f}; {:+.9f}] %\n", min_percent_jitter(), max_percent_jitter());
    }
  }
  auto pct = [&](const char* name, const core::LatencyHistogram& h) {
    fmt::format_to(it, "{:<34}= p50 {:.6f} p99 {:.6f} p99.9 {:.6f} max {:.6f} ms (n {})\n", name,
         static_cast<double>(h.percentile(50)) * 1e-6, static_cast<double>(h.percentile(99)) * 1e-6,
         static_cast<double>(h.percentile(99.9)) * 1e-6, static_cast<double>(h.max()) * 1e-6, h.count());
  };
  pct("Cycle time", cycle_hist_);
  pct("Inter-step time", inter_hist_);
  fmt::format_to(it, "Missed deadlines (> {:.6f} ms)   = {}\n", static_cast<double>(config_.deadline_ns) * 1e-6, missed_deadlines());
  return out;
}

}  // namespace axon::c4g::host
