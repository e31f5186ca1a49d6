// The version gates host and simulator share (protocol/firmware_gates.hpp).
#include "axon/fps/protocol/firmware_gates.hpp"

#include <gtest/gtest.h>

namespace axon::fps::protocol {
namespace {

TEST(FirmwareGates, ThePreciseMoveSwitchesFollowTheChosenHistory) {
  for (auto c : {CommandId::switch_on_precise_move_alpha, CommandId::switch_off_precise_move_alpha,
                 CommandId::switch_on_precise_move_beta, CommandId::switch_off_precise_move_beta}) {
    EXPECT_TRUE(firmware_takes(c, {4, 1, 13}, FirmwareHistory::document));
    EXPECT_FALSE(firmware_takes(c, {4, 1, 16}, FirmwareHistory::field));
    EXPECT_TRUE(firmware_takes(c, {4, 1, 17}, FirmwareHistory::field));
  }
  EXPECT_TRUE(firmware_takes(CommandId::go_to_absolute_position, {4, 1, 0}, FirmwareHistory::field));
  EXPECT_EQ(firmware_lacks(CommandId::switch_on_precise_move_beta, {4, 1, 16}, FirmwareHistory::field),
            "firmware 04.01.16 lacks SWITCH_ON_PRECISE_MOVE_BETA (130): it has it from 04.01.17 on");
  EXPECT_EQ(firmware_lacks(CommandId::switch_on_precise_move_beta, {4, 1, 17}, FirmwareHistory::field), "");
}

TEST(FirmwareGates, OnlyVersionsFrom040100HaveTheStatusLayoutDecoded) {
  EXPECT_EQ(status_layout_unknown({4, 1, 0}), "");
  EXPECT_EQ(status_layout_unknown({5, 0, 0}), "");
  EXPECT_NE(status_layout_unknown({4, 0, 99}).find("firmware 04.00.99 predates 04.01.00"), std::string::npos);
}

}  // namespace
}  // namespace axon::fps::protocol
