#include "axon/blmc/protocol/status.hpp"

#include "axon/blmc/protocol/error.hpp"

#include <gtest/gtest.h>

using namespace axon::blmc::protocol;

TEST(BlmcStatus, BitsFollowTheSpecLayout) {
  EXPECT_EQ(Status{.system_enabled = true}.to_byte(), 0x01);
  EXPECT_EQ(Status{.motor1_enabled = true}.to_byte(), 0x02);
  EXPECT_EQ(Status{.motor1_ready = true}.to_byte(), 0x04);
  EXPECT_EQ(Status{.motor2_enabled = true}.to_byte(), 0x08);
  EXPECT_EQ(Status{.motor2_ready = true}.to_byte(), 0x10);
  EXPECT_EQ(Status{.error = ErrorCode::encoder}.to_byte(), 0x20);
  EXPECT_EQ(Status{.error = ErrorCode::other}.to_byte(), 0xE0);
  const auto s = Status::from_byte(0x5F).value();  // error 2, everything enabled and ready
  EXPECT_TRUE(s.system_enabled && s.motor1_enabled && s.motor1_ready && s.motor2_enabled && s.motor2_ready);
  EXPECT_EQ(s.error, ErrorCode::can_recv_timeout);
}

TEST(BlmcStatus, EveryDefinedByteRoundTrips) {
  for (int b = 0; b < 256; ++b) {
    auto s = Status::from_byte(static_cast<std::uint8_t>(b));
    if ((b >> 5) == 6) {
      ASSERT_FALSE(s);
      EXPECT_EQ(s.error(), ProtocolErrc::unknown_error_code);
      continue;
    }
    ASSERT_TRUE(s) << b;
    EXPECT_EQ(s.value().to_byte(), b);
  }
}

TEST(BlmcStatus, ErrorCodeNames) {
  EXPECT_EQ(name(ErrorCode::none), "NONE");
  EXPECT_EQ(name(ErrorCode::can_recv_timeout), "CAN_RECV_TIMEOUT");
  EXPECT_EQ(name(ErrorCode::pos_rollover), "POS_ROLLOVER");
  EXPECT_EQ(error_code_from_raw(9).error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(Status::from_byte(0x03).value().to_string(), "SYS MTR1(enabled) MTR2(-) error=NONE");
}

TEST(BlmcStatus, ErrorPrecedence) {
  EXPECT_EQ(reported_error({}), ErrorCode::none);
  EXPECT_EQ(reported_error({.encoder = true, .transmit = true, .recv_timeout = true}), ErrorCode::encoder);
  EXPECT_EQ(reported_error({.transmit = true, .recv_timeout = true}), ErrorCode::other);
  EXPECT_EQ(reported_error({.recv_timeout = true, .pos_converter = true}), ErrorCode::can_recv_timeout);
  EXPECT_EQ(reported_error({.pos_converter = true, .pos_rollover = true}), ErrorCode::pos_converter);
  EXPECT_EQ(reported_error({.pos_rollover = true}), ErrorCode::pos_rollover);
}
