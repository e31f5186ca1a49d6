#include "axon/c4g/protocol/soft_switch.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace axon::c4g::protocol {

Result<void> validate(const SwitchTimes& t) {
  const double v[] = {t.t1_s, t.t2_s, t.t3_s};
  const char* names[] = {"T1", "T2", "T3"};
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(v[i]) || v[i] < 0)
      return Error(CoreErrc::invalid_argument, fmt::format("soft switching {} = {} s: must be a time >= 0", names[i], v[i]));
  return ok();
}

std::string_view to_string(SwitchInterval i) noexcept {
  switch (i) {
    case SwitchInterval::none: return "none";
    case SwitchInterval::pre: return "T1";
    case SwitchInterval::switching: return "T2";
    case SwitchInterval::post: return "T3";
    case SwitchInterval::done: return "done";
  }
  return "?";
}

std::string_view to_string(SwitchDirection d) noexcept {
  return d == SwitchDirection::to_pc ? "drive->pc" : "pc->drive";
}

SwitchSample linear_switch(const SwitchTimes& times, SwitchDirection direction, double elapsed_s) noexcept {
  SwitchSample s;
  s.direction = direction;
  // Elapsed time to the nanosecond: times computed as differences of clock readings and as packet
  // counts x period then fall into the same interval at the boundaries.
  s.elapsed_s = std::max(0.0, std::round(elapsed_s * 1e9) * 1e-9);
  const double t = s.elapsed_s;
  const double t1 = std::max(0.0, times.t1_s), t2 = std::max(0.0, times.t2_s), t3 = std::max(0.0, times.t3_s);
  if (t < t1) {
    s.interval = SwitchInterval::pre;
    s.chi = 0;
  } else if (t < t1 + t2) {
    s.interval = SwitchInterval::switching;
    s.chi = std::clamp((t - t1) / t2, 0.0, 1.0);
  } else if (t < t1 + t2 + t3) {
    s.interval = SwitchInterval::post;
    s.chi = 1;
  } else {
    s.interval = SwitchInterval::done;
    s.chi = 1;
  }
  s.eta = s.chi;
  s.rho = 1.0 - s.chi;
  return s;
}

double limit_current(double current, double factor, double i_max, double i_min) noexcept {
  const double threshold = std::max(0.0, factor) * std::max(0.0, std::fabs(i_max) - std::fabs(i_min));
  return std::clamp(current, -threshold, threshold);
}

}  // namespace axon::c4g::protocol
