#include "axon/blmc/protocol/frames.hpp"

#include "axon/blmc/protocol/error.hpp"

#include <gtest/gtest.h>

#include <vector>

using namespace axon::blmc::protocol;
using axon::can::Frame;

namespace {
Frame std_frame(std::uint32_t id, std::vector<std::uint8_t> bytes) { return Frame::standard(id, bytes).value(); }
std::vector<std::uint8_t> bytes_of(const Frame& f) { return {f.payload().begin(), f.payload().end()}; }
}  // namespace

TEST(BlmcFrames, EnableSystemExampleFromTheSpec) {
  const auto f = encode(Command::parse("ENABLE_SYS=1").value()).value();
  EXPECT_EQ(f.id(), 0x000u);
  EXPECT_FALSE(f.is_extended());
  EXPECT_EQ(bytes_of(f), (std::vector<std::uint8_t>{0, 0, 0, 1, 0, 0, 0, 1}));
  EXPECT_EQ(decode_command(f).value().to_string(), "ENABLE_SYS=1");
}

TEST(BlmcFrames, EnableMotor1Example) {
  // "To enable motor 1, set MDH = 2 and MDL = 1."
  const auto f = encode(Command::flag(CommandCode::enable_mtr1, true).value()).value();
  EXPECT_EQ(bytes_of(f), (std::vector<std::uint8_t>{0, 0, 0, 1, 0, 0, 0, 2}));
}

TEST(BlmcFrames, HalvesAreBigEndianQ24) {
  // Iq ref motor 1 = 1.5 A (0x01800000), motor 2 = -0.25 A (0xFFC00000).
  const auto f = encode_iq_ref({1.5, -0.25}).value();
  EXPECT_EQ(f.id(), 0x005u);
  EXPECT_EQ(bytes_of(f), (std::vector<std::uint8_t>{0x01, 0x80, 0x00, 0x00, 0xFF, 0xC0, 0x00, 0x00}));
  EXPECT_EQ(decode_pair(MessageId::iq_ref, f).value(), (MotorPair{1.5, -0.25}));
  const auto t = encode(Command::recv_timeout_ms(0x01020304)).value();
  EXPECT_EQ(bytes_of(t), (std::vector<std::uint8_t>{1, 2, 3, 4, 0, 0, 0, 0x1E}));
}

TEST(BlmcFrames, BoardMessagesDecode) {
  const auto pos = decode_from_board(std_frame(0x030, {0x00, 0x80, 0x00, 0x00, 0xFE, 0x00, 0x00, 0x00})).value();
  EXPECT_EQ(std::get<PairMessage>(pos), (PairMessage{MessageId::position, {0.5, -2.0}}));
  const auto st = decode_from_board(std_frame(0x010, {0x47})).value();
  EXPECT_EQ(std::get<Status>(st).error, ErrorCode::can_recv_timeout);
  EXPECT_TRUE(std::get<Status>(st).motor1_ready);
  const auto idx = decode_from_board(std_frame(0x060, {0x00, 0x40, 0x00, 0x00, 0x01})).value();
  EXPECT_EQ(std::get<EncoderIndex>(idx), (EncoderIndex{0.25, 1}));
  EXPECT_EQ(to_string(idx), "ENCODER_INDEX motor2 pos=0.25");
  const auto adc = decode_from_board(std_frame(0x050, {0x00, 0x80, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00})).value();
  EXPECT_EQ(std::get<PairMessage>(adc).values, (MotorPair{0.5, 1.0}));
}

TEST(BlmcFrames, EveryMessageRoundTrips) {
  std::vector<FromBoard> from = {Status{.system_enabled = true, .motor2_ready = true, .error = ErrorCode::encoder},
                                 PairMessage{MessageId::current, {3.25, -1}},
                                 PairMessage{MessageId::position, {99.5, -99.5}},
                                 PairMessage{MessageId::velocity, {0.125, -6}},
                                 PairMessage{MessageId::adc6, {0, 1}},
                                 EncoderIndex{-42.75, 0}};
  for (const auto& m : from) {
    const auto f = encode(m).value();
    EXPECT_EQ(decode_from_board(f).value(), m) << to_string(m);
    EXPECT_EQ(decode_to_board(f).error(), ProtocolErrc::unknown_id) << to_string(m);
  }
  std::vector<ToBoard> to = {Command::parse("SEND_ALL=1").value(), PairMessage{MessageId::iq_ref, {1, 2}},
                             PairMessage{MessageId::kp, {0.5, 0.5}}, PairMessage{MessageId::kd, {0.0078125, 0}},
                             PairMessage{MessageId::pos_ref, {-3, 3}}, PairMessage{MessageId::vel_ref, {1, -1}}};
  for (const auto& m : to) {
    const auto f = encode(m).value();
    EXPECT_EQ(decode_to_board(f).value(), m) << to_string(m);
    EXPECT_EQ(decode_from_board(f).error(), ProtocolErrc::unknown_id) << to_string(m);
  }
}

TEST(BlmcFrames, WrongDirectionOrKindIsRejectedOnEncode) {
  EXPECT_EQ(encode(FromBoard{PairMessage{MessageId::iq_ref, {}}}).error(), ProtocolErrc::wrong_id);
  EXPECT_EQ(encode(ToBoard{PairMessage{MessageId::current, {}}}).error(), ProtocolErrc::wrong_id);
  EXPECT_EQ(encode(PairMessage{MessageId::status, {}}).error(), ProtocolErrc::wrong_id);
  EXPECT_EQ(encode_iq_ref({200, 0}).error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(encode(PairMessage{MessageId::adc6, {1.5, 0}}).error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(encode(EncoderIndex{0, 2}).error(), ProtocolErrc::value_out_of_range);
}

TEST(BlmcFrames, MalformedFramesGetTypedErrors) {
  const std::vector<std::uint8_t> eight(8, 0);
  // Extended and remote frames with a blmc identifier.
  EXPECT_EQ(decode_command(Frame::extended(0x000, std::vector<std::uint8_t>{0, 0, 0, 1, 0, 0, 0, 1}).value()).error(),
            ProtocolErrc::not_standard_frame);
  EXPECT_EQ(decode_from_board(Frame::remote(0x010, axon::can::IdFormat::standard, 1).value()).error(),
            ProtocolErrc::not_standard_frame);
  // Wrong identifier for the decoder asked.
  EXPECT_EQ(decode_status(std_frame(0x020, eight)).error(), ProtocolErrc::wrong_id);
  EXPECT_EQ(decode_pair(MessageId::current, std_frame(0x030, eight)).error(), ProtocolErrc::wrong_id);
  EXPECT_EQ(decode_pair(MessageId::status, std_frame(0x010, {0})).error(), ProtocolErrc::wrong_id);
  // Identifiers that are not blmc (OptoForce 0x100 included).
  EXPECT_EQ(decode_from_board(std_frame(0x100, eight)).error(), ProtocolErrc::unknown_id);
  EXPECT_EQ(decode_to_board(std_frame(0x001, eight)).error(), ProtocolErrc::unknown_id);
  // Wrong lengths.
  EXPECT_EQ(decode_from_board(std_frame(0x010, {})).error(), ProtocolErrc::wrong_length);
  EXPECT_EQ(decode_from_board(std_frame(0x010, {0, 0})).error(), ProtocolErrc::wrong_length);
  EXPECT_EQ(decode_from_board(std_frame(0x020, {0, 0, 0, 0, 0, 0, 0})).error(), ProtocolErrc::wrong_length);
  EXPECT_EQ(decode_from_board(std_frame(0x060, eight)).error(), ProtocolErrc::wrong_length);
  EXPECT_EQ(decode_to_board(std_frame(0x000, {0, 0, 0, 1})).error(), ProtocolErrc::wrong_length);
  // Bad content.
  EXPECT_EQ(decode_to_board(std_frame(0x000, {0, 0, 0, 1, 0, 0, 0, 0x06})).error(), ProtocolErrc::unknown_command);
  EXPECT_EQ(decode_to_board(std_frame(0x000, {0, 0, 0, 1, 0, 0, 1, 0x01})).error(), ProtocolErrc::unknown_command);
  EXPECT_EQ(decode_to_board(std_frame(0x000, {0, 0, 0, 2, 0, 0, 0, 0x01})).error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(decode_from_board(std_frame(0x010, {0xC0})).error(), ProtocolErrc::unknown_error_code);
  EXPECT_EQ(decode_from_board(std_frame(0x060, {0, 0, 0, 0, 2})).error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(decode_from_board(std_frame(0x050, {0xFF, 0xFF, 0xFF, 0xFF, 0, 0, 0, 0})).error(),
            ProtocolErrc::value_out_of_range);  // ADC -2^-24
  EXPECT_EQ(decode_from_board(std_frame(0x050, {0, 0, 0, 0, 0x01, 0, 0, 1})).error(),
            ProtocolErrc::value_out_of_range);  // ADC just above 1
}

TEST(BlmcFrames, LogLines) {
  EXPECT_EQ(to_string(ToBoard{Command::parse("ENABLE_SYS=1").value()}), "COMMAND ENABLE_SYS=1");
  EXPECT_EQ(to_string(ToBoard{PairMessage{MessageId::iq_ref, {0.5, -1}}}), "IQ_REF m1=0.5 m2=-1");
}
