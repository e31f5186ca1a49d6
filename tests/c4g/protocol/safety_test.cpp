#include "axon/c4g/protocol/safety.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>

using namespace axon::c4g::protocol;

TEST(C4gSafety, FollowingErrorAgainstThreshold) {
  EXPECT_FALSE(following_error_exceeded(10.0, 3.0, 7.5));
  EXPECT_FALSE(following_error_exceeded(10.0, 2.5, 7.5));  // exactly at the threshold is fine
  EXPECT_TRUE(following_error_exceeded(10.0, 2.4, 7.5));
  EXPECT_TRUE(following_error_exceeded(-10.0, 0.0, 7.5));
  EXPECT_FALSE(following_error_exceeded(100.0, 0.0, 0.0));  // 0: not checked
  EXPECT_TRUE(following_error_exceeded(std::nan(""), 0.0, 7.5));
}

TEST(C4gSafety, FirstAxisOverItsThreshold) {
  Packet p;
  p.count = 3;
  p.axes[0].d1 = 1.0f;
  p.axes[0].d3 = 1.5f;
  p.axes[1].d1 = 9.0f;
  p.axes[1].d3 = 0.0f;
  p.axes[2].d1 = 20.0f;
  const std::array<float, 3> th{7.5f, 7.5f, 7.5f};
  EXPECT_EQ(first_following_error(p, th), 1u);
  const std::array<float, 3> off{7.5f, 0.0f, 30.0f};
  EXPECT_EQ(first_following_error(p, off), std::nullopt);
}

TEST(C4gSafety, CurrentSaturation) {
  EXPECT_EQ(saturate_current(30.0f, 24.5f), 24.5f);
  EXPECT_EQ(saturate_current(-30.0f, 24.5f), -24.5f);
  EXPECT_EQ(saturate_current(3.0f, 9.5f), 3.0f);
  EXPECT_EQ(saturate_current(3.0f, 0.0f), 0.0f);
  EXPECT_EQ(saturate_current(std::nanf(""), 9.5f), 0.0f);
  Packet r;
  r.count = 2;
  r.axes[0].d5 = 12.0f;
  r.axes[1].d5 = -1.0f;
  const std::array<float, 2> lim{9.5f, 9.5f};
  EXPECT_EQ(saturate_currents(r, lim), 1u);
  EXPECT_EQ(r.axes[0].d5, 9.5f);
  EXPECT_EQ(r.axes[1].d5, -1.0f);
}
