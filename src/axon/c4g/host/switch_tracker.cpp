#include "axon/c4g/host/switch_tracker.hpp"

namespace axon::c4g::host {

namespace P = protocol;

namespace {
bool loop_mode(std::int32_t m) noexcept { return m == 1 || m == 2; }
bool loop_standby(std::int32_t m) noexcept { return m == 11 || m == 12; }
}  // namespace

void SwitchTracker::reset() noexcept {
  count_ = 0;
  prev_mode_ = {};
  packets_ = {};
  seen_ = {};
  samples_ = {};
}

void SwitchTracker::update(const P::Packet& request, double period_s) noexcept {
  count_ = request.count < P::kMaxAxes ? request.count : P::kMaxAxes;
  for (std::size_t i = 0; i < count_; ++i) {
    const std::int32_t m = request.axes[i].mode;
    const std::int32_t prev = seen_[i] ? prev_mode_[i] : 0;
    P::SwitchSample& s = samples_[i];
    if (loop_mode(m) || loop_standby(m)) {
      // A new switch when the mode just appeared: 1/2 from anything but itself and its standby
      // (which never goes back), 1'/2' from anything else.
      const bool fresh = !seen_[i] || prev != m;
      const auto dir = loop_mode(m) ? P::SwitchDirection::to_pc : P::SwitchDirection::to_drive;
      if (fresh) packets_[i] = 0;
      else ++packets_[i];
      s = P::linear_switch(times_, dir, static_cast<double>(packets_[i]) * period_s);
    } else {
      s = P::SwitchSample{};
      packets_[i] = 0;
    }
    prev_mode_[i] = m;
    seen_[i] = true;
  }
}

}  // namespace axon::c4g::host
