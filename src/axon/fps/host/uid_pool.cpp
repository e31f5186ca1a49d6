#include "axon/fps/host/uid_pool.hpp"

#include <algorithm>

namespace axon::fps::host {

void UidPool::forget_expired(core::TimePoint now) noexcept {
  std::erase_if(quarantine_, [&](const Quarantine& q) { return q.until <= now; });
}

bool UidPool::quarantined(std::uint8_t uid, core::TimePoint now) const noexcept {
  return std::any_of(quarantine_.begin(), quarantine_.end(),
                     [&](const Quarantine& q) { return q.uid == uid && q.until > now; });
}

std::optional<std::uint8_t> UidPool::acquire(core::TimePoint now) noexcept {
  forget_expired(now);
  std::uint8_t uid = last_;
  for (std::size_t i = 0; i < kSize; ++i) {
    uid = uid >= kLast ? kFirst : static_cast<std::uint8_t>(uid + 1);
    if (!busy_[uid] && !quarantined(uid, now)) {
      busy_[uid] = true;
      last_ = uid;
      return uid;
    }
  }
  return std::nullopt;
}

void UidPool::release(std::uint8_t uid) noexcept {
  if (valid(uid)) busy_[uid] = false;
}

void UidPool::quarantine(std::uint8_t uid, core::TimePoint until) noexcept {
  if (!valid(uid)) return;
  busy_[uid] = false;
  for (auto& q : quarantine_) {
    if (q.uid == uid) {
      q.until = std::max(q.until, until);
      return;
    }
  }
  quarantine_.push_back({uid, until});
}

bool UidPool::take_late_reply(std::uint8_t uid, core::TimePoint now) noexcept {
  if (!quarantined(uid, now)) return false;
  std::erase_if(quarantine_, [&](const Quarantine& q) { return q.uid == uid; });
  return true;
}

core::TimePoint UidPool::next_release(core::TimePoint now) const noexcept {
  core::TimePoint t = core::TimePoint::max();
  for (const auto& q : quarantine_) {
    if (q.until > now) t = std::min(t, q.until);
  }
  return t;
}

bool UidPool::idle(core::TimePoint now) const noexcept {
  return busy_.none() && next_release(now) == core::TimePoint::max();
}

}  // namespace axon::fps::host
