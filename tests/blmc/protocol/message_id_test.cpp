#include "axon/blmc/protocol/message_id.hpp"

#include <gtest/gtest.h>

using namespace axon::blmc::protocol;

TEST(BlmcMessageId, TheSpecTable) {
  EXPECT_EQ(static_cast<unsigned>(MessageId::command), 0x000u);
  EXPECT_EQ(static_cast<unsigned>(MessageId::iq_ref), 0x005u);
  EXPECT_EQ(static_cast<unsigned>(MessageId::vel_ref), 0x009u);
  EXPECT_EQ(static_cast<unsigned>(MessageId::status), 0x010u);
  EXPECT_EQ(static_cast<unsigned>(MessageId::adc6), 0x050u);
  EXPECT_EQ(static_cast<unsigned>(MessageId::encoder_index), 0x060u);
  EXPECT_EQ(all_message_ids().size(), 12u);
  for (MessageId id : all_message_ids()) {
    EXPECT_LE(static_cast<unsigned>(id), 0x7FFu);
    EXPECT_EQ(message_id_from_raw(static_cast<unsigned>(id)), id);
  }
}

TEST(BlmcMessageId, DirectionSizeAndOptional) {
  EXPECT_EQ(direction(MessageId::command), Direction::to_board);
  EXPECT_EQ(direction(MessageId::vel_ref), Direction::to_board);
  EXPECT_EQ(direction(MessageId::status), Direction::from_board);
  EXPECT_EQ(direction(MessageId::encoder_index), Direction::from_board);
  EXPECT_EQ(payload_size(MessageId::status), 1u);
  EXPECT_EQ(payload_size(MessageId::encoder_index), 5u);
  EXPECT_EQ(payload_size(MessageId::current), 8u);
  EXPECT_TRUE(is_optional(MessageId::kp));
  EXPECT_TRUE(is_optional(MessageId::vel_ref));
  EXPECT_FALSE(is_optional(MessageId::iq_ref));
  EXPECT_EQ(name(MessageId::encoder_index), "ENCODER_INDEX");
}

TEST(BlmcMessageId, UnknownIdentifiers) {
  for (unsigned raw : {0x001u, 0x00Au, 0x011u, 0x070u, 0x100u, 0x101u, 0x7FFu, 0x1000u}) {
    EXPECT_FALSE(message_id_from_raw(raw)) << raw;
  }
}
