// The uid pool on its own: round-robin order, 63 at most, quarantine after a timeout.
#include "axon/fps/host/uid_pool.hpp"

#include <gtest/gtest.h>

using namespace axon;
using namespace axon::fps::host;
using namespace std::chrono_literals;

TEST(UidPool, HandsOutOneToSixtyThreeRoundRobin) {
  UidPool p;
  const core::TimePoint t{};
  for (int i = 1; i <= 63; ++i) EXPECT_EQ(p.acquire(t), std::optional<std::uint8_t>(i));
  EXPECT_EQ(p.acquire(t), std::nullopt);
  EXPECT_EQ(p.busy_count(), 63u);
  p.release(40);
  p.release(2);
  EXPECT_EQ(p.acquire(t), std::optional<std::uint8_t>(2));  // the next free after 63 wraps to 1..
  EXPECT_EQ(p.acquire(t), std::optional<std::uint8_t>(40));
  EXPECT_EQ(p.acquire(t), std::nullopt);
}

TEST(UidPool, ReleasedUidsComeBackAsLateAsPossible) {
  UidPool p;
  const core::TimePoint t{};
  auto a = p.acquire(t);
  p.release(*a);
  EXPECT_EQ(p.acquire(t), std::optional<std::uint8_t>(2));  // not 1 again at once
}

TEST(UidPool, QuarantinedUidsWaitForTheirLateReplyOrTheDeadline) {
  UidPool p;
  const core::TimePoint t0{};
  for (int i = 1; i <= 63; ++i) (void)p.acquire(t0);
  p.quarantine(5, t0 + 1s);
  EXPECT_FALSE(p.in_use(5));
  EXPECT_TRUE(p.quarantined(5, t0));
  EXPECT_EQ(p.acquire(t0), std::nullopt);
  EXPECT_EQ(p.next_release(t0), t0 + 1s);
  EXPECT_EQ(p.acquire(t0 + 1s), std::optional<std::uint8_t>(5));  // deadline passed

  p.quarantine(6, t0 + 10s);
  EXPECT_FALSE(p.take_late_reply(7, t0));  // 7 is not quarantined: not a late reply
  EXPECT_TRUE(p.take_late_reply(6, t0));   // the late reply ends the quarantine
  EXPECT_FALSE(p.quarantined(6, t0));
  EXPECT_EQ(p.acquire(t0), std::optional<std::uint8_t>(6));
  EXPECT_FALSE(p.idle(t0));
}

TEST(UidPool, IgnoresUidZeroAndOutOfRange) {
  UidPool p;
  p.release(0);
  p.quarantine(0, core::TimePoint::max());
  p.quarantine(64, core::TimePoint::max());
  EXPECT_TRUE(p.idle(core::TimePoint{}));
  EXPECT_EQ(p.acquire(core::TimePoint{}), std::optional<std::uint8_t>(1));
}
