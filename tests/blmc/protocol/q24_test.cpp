#include "axon/blmc/protocol/q24.hpp"

#include "axon/blmc/protocol/error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using namespace axon::blmc::protocol;

TEST(BlmcQ24, ConvertsBothWays) {
  EXPECT_EQ(to_q24(1.0).value(), 1 << 24);
  EXPECT_EQ(to_q24(-0.5).value(), -(1 << 23));
  EXPECT_EQ(to_q24(0.0).value(), 0);
  EXPECT_DOUBLE_EQ(from_q24(1 << 24), 1.0);
  EXPECT_DOUBLE_EQ(from_q24(-(1 << 23)), -0.5);
  EXPECT_DOUBLE_EQ(from_q24(std::numeric_limits<std::int32_t>::min()), -128.0);
}

TEST(BlmcQ24, RoundsToTheNearestStep) {
  const double step = 1.0 / 16777216.0;
  EXPECT_EQ(to_q24(0.4 * step).value(), 0);
  EXPECT_EQ(to_q24(0.6 * step).value(), 1);
  EXPECT_EQ(to_q24(-0.6 * step).value(), -1);
  EXPECT_EQ(to_q24(0.1).value(), 1677722);  // 0.1 * 2^24 = 1677721.6
}

TEST(BlmcQ24, EdgesOfTheRange) {
  EXPECT_EQ(to_q24(-128.0).value(), std::numeric_limits<std::int32_t>::min());
  EXPECT_EQ(to_q24(kQ24Max).value(), std::numeric_limits<std::int32_t>::max());
  EXPECT_DOUBLE_EQ(from_q24(to_q24(kQ24Max).value()), kQ24Max);
}

TEST(BlmcQ24, OutOfRangeIsAnErrorNeverWrapped) {
  for (double v : {128.0, -128.0 - 1.0 / 16777216.0, 1e9, -1e9, std::numeric_limits<double>::infinity(),
                   -std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN()}) {
    auto r = to_q24(v);
    ASSERT_FALSE(r) << v;
    EXPECT_EQ(r.error(), ProtocolErrc::value_out_of_range) << v;
  }
}
