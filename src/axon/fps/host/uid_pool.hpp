// The uids of one (positioner, command) pair: 1..63, so at most 63 requests of one command can be
// in flight to one robot (uid 0 marks broadcasts and frames a robot sends on its own).
//
// Uids are handed out round-robin, so a uid comes back into use as late as possible: a stray or
// duplicated reply to an old request then finds no request with its uid instead of completing the
// wrong one. A uid whose request timed out is quarantined for a while, because its reply may still
// arrive; a reply for a quarantined uid is recognised as late, and ends the quarantine.
//
// Pure bookkeeping (no I/O, no waiting): the command client does the waiting.
#pragma once

#include "axon/core/clock.hpp"

#include <bitset>
#include <cstdint>
#include <optional>
#include <vector>

namespace axon::fps::host {

class UidPool {
 public:
  static constexpr std::uint8_t kFirst = 1;
  static constexpr std::uint8_t kLast = 63;
  static constexpr std::size_t kSize = kLast - kFirst + 1;

  // The next free uid after the last one handed out, skipping uids in use or still quarantined at
  // `now`; nullopt when none is free.
  std::optional<std::uint8_t> acquire(core::TimePoint now) noexcept;
  // The request with this uid is finished (reply arrived, send failed, cancelled).
  void release(std::uint8_t uid) noexcept;
  // The request with this uid timed out: the uid is free again only after `until` or once its late
  // reply arrives.
  void quarantine(std::uint8_t uid, core::TimePoint until) noexcept;
  // A reply came for `uid` and no request waits for it: true (and the quarantine ends) when the uid
  // was quarantined, i.e. the reply is a late one.
  bool take_late_reply(std::uint8_t uid, core::TimePoint now) noexcept;

  [[nodiscard]] bool in_use(std::uint8_t uid) const noexcept { return valid(uid) && busy_[uid]; }
  [[nodiscard]] bool quarantined(std::uint8_t uid, core::TimePoint now) const noexcept;
  [[nodiscard]] std::size_t busy_count() const noexcept { return busy_.count(); }
  // When the earliest quarantine ends (TimePoint::max() when nothing is quarantined after `now`).
  [[nodiscard]] core::TimePoint next_release(core::TimePoint now) const noexcept;
  // Nothing in use and nothing quarantined: the pool can be forgotten.
  [[nodiscard]] bool idle(core::TimePoint now) const noexcept;

 private:
  static constexpr bool valid(std::uint8_t uid) noexcept { return uid >= kFirst && uid <= kLast; }

  // Kept small: a client has one pool per (positioner, command) it ever used, and quarantines are
  // rare, so they live in a short list rather than a table per pool.
  struct Quarantine {
    std::uint8_t uid;
    core::TimePoint until;
  };
  void forget_expired(core::TimePoint now) noexcept;

  std::bitset<kLast + 1> busy_;
  std::vector<Quarantine> quarantine_;
  std::uint8_t last_ = 0;
};

}  // namespace axon::fps::host
