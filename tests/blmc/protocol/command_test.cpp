#include "axon/blmc/protocol/command.hpp"

#include "axon/blmc/protocol/error.hpp"

#include <gtest/gtest.h>

using namespace axon::blmc::protocol;

TEST(BlmcCommand, CodeTable) {
  EXPECT_EQ(command_table().size(), 17u);
  EXPECT_EQ(name(CommandCode::enable_sys), "ENABLE_SYS");
  EXPECT_EQ(name(CommandCode::send_enc_index), "SEND_ENC_INDEX");
  EXPECT_EQ(static_cast<unsigned>(CommandCode::send_enc_index), 0x10u);
  EXPECT_EQ(static_cast<unsigned>(CommandCode::set_can_recv_timeout), 0x1Eu);
  EXPECT_EQ(find_command(0x2Bu)->name, "CAN_CMD_D_CONTROLLER_LIMIT_IQ_MTR2");
  EXPECT_TRUE(find_command(0x2Bu)->optional);
  EXPECT_FALSE(info(CommandCode::enable_mtr1).optional);
  EXPECT_EQ(info(CommandCode::enable_sys).default_raw, 1u);
  EXPECT_EQ(find_command(0x06u), nullptr);
  EXPECT_EQ(find_command(0x101u), nullptr);  // a code byte 0x01 with garbage above it
  EXPECT_EQ(find_command("enable_mtr2")->code, CommandCode::enable_mtr2);
  EXPECT_EQ(find_command("ENABLE"), nullptr);
}

TEST(BlmcCommand, ParseAndPrintTheNomenclature) {
  const auto c = Command::parse("ENABLE_SYS=1").value();
  EXPECT_EQ(c.code(), CommandCode::enable_sys);
  EXPECT_EQ(c.raw_value(), 1u);
  EXPECT_EQ(c.to_string(), "ENABLE_SYS=1");
  EXPECT_EQ(Command::parse(" set_can_recv_timeout = 100 ").value().to_string(), "SET_CAN_RECV_TIMEOUT=100");
  EXPECT_EQ(Command::parse("SET_CAN_RECV_TIMEOUT=4294967295").value().raw_value(), 4294967295u);
  const auto lim = Command::parse("CAN_CMD_P_CONTROLLER_LIMIT_IQ_MTR1=2.5").value();
  EXPECT_EQ(lim.raw_value(), 2.5 * (1 << 24));
  EXPECT_DOUBLE_EQ(lim.value(), 2.5);
  EXPECT_EQ(lim.to_string(), "CAN_CMD_P_CONTROLLER_LIMIT_IQ_MTR1=2.5");
  EXPECT_EQ(Command::parse("CAN_CMD_D_CONTROLLER_LIMIT_IQ_MTR2=-0.1").value().to_string(),
            "CAN_CMD_D_CONTROLLER_LIMIT_IQ_MTR2=-0.10000002384185791");  // nearest Q24 step
}

TEST(BlmcCommand, EveryTableEntryRoundTripsThroughText) {
  for (const auto& ci : command_table()) {
    const auto c = Command::from_raw(ci.code, ci.kind == ValueKind::flag ? 1u : 123456789u).value();
    EXPECT_EQ(Command::parse(c.to_string()).value(), c) << c.to_string();
  }
}

TEST(BlmcCommand, MalformedText) {
  EXPECT_EQ(Command::parse("ENABLE_SYS").error(), ProtocolErrc::bad_command_text);
  EXPECT_EQ(Command::parse("ENABLE_SYS=").error(), ProtocolErrc::bad_command_text);
  EXPECT_EQ(Command::parse("ENABLE_SYS=yes").error(), ProtocolErrc::bad_command_text);
  EXPECT_EQ(Command::parse("ENABLE_SYS=-1").error(), ProtocolErrc::bad_command_text);
  EXPECT_EQ(Command::parse("ENABLE_SYS=2").error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(Command::parse("SET_CAN_RECV_TIMEOUT=4294967296").error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(Command::parse("FOO=1").error(), ProtocolErrc::unknown_command);
  EXPECT_EQ(Command::parse("=1").error(), ProtocolErrc::unknown_command);
  EXPECT_EQ(Command::parse("CAN_CMD_P_CONTROLLER_LIMIT_IQ_MTR1=200").error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(Command::parse("CAN_CMD_P_CONTROLLER_LIMIT_IQ_MTR1=nan").error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(Command::parse("CAN_CMD_P_CONTROLLER_LIMIT_IQ_MTR1=1.5A").error(), ProtocolErrc::bad_command_text);
}

TEST(BlmcCommand, FactoriesCheckTheValueKind) {
  EXPECT_EQ(Command::flag(CommandCode::send_all, true).value().raw_value(), 1u);
  EXPECT_EQ(Command::flag(CommandCode::set_can_recv_timeout, true).error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(Command::current_limit(CommandCode::enable_sys, 1.0).error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(Command::recv_timeout_ms(250).to_string(), "SET_CAN_RECV_TIMEOUT=250");
}
