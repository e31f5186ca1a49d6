#include "axon/fps/protocol/identifier.hpp"

#include "axon/fps/protocol/error.hpp"
#include "axon/fps/protocol/message.hpp"

#include <gtest/gtest.h>

#include <array>

using namespace axon::fps::protocol;

TEST(FpsIdentifier, PacksFieldsAtTheDocumentedBits) {
  // positioner bits 28..18, command 17..10, uid 9..4, response 3..0
  EXPECT_EQ(encode_identifier({1, 0, 0, ResponseCode::accepted}).value(), 1u << 18);
  EXPECT_EQ(encode_identifier({0, 1, 0, ResponseCode::accepted}).value(), 1u << 10);
  EXPECT_EQ(encode_identifier({0, 0, 1, ResponseCode::accepted}).value(), 1u << 4);
  EXPECT_EQ(encode_identifier({0, 0, 0, ResponseCode::value_out_of_range}).value(), 1u);
  EXPECT_EQ(encode_identifier({2047, 255, 63, ResponseCode::hall_sensors_disabled}).value(), 0x1FFFFFFFu);
  // positioner 17, GO_TO_ABSOLUTE_POSITION (30), uid 3, accepted
  EXPECT_EQ(encode_identifier({17, 30, 3, ResponseCode::accepted}).value(), 0x00447830u);
}

TEST(FpsIdentifier, DecodesEveryField) {
  const auto id = decode_identifier(0x00447839u).value();
  EXPECT_EQ(id.positioner, 17);
  EXPECT_EQ(id.command, 30);
  EXPECT_EQ(id.uid, 3);
  EXPECT_EQ(id.response, ResponseCode::beta_collision);
  EXPECT_FALSE(id.is_broadcast());
  EXPECT_TRUE(decode_identifier(3u << 10).value().is_broadcast());
}

TEST(FpsIdentifier, RoundTripsAcrossTheWholeRange) {
  for (std::uint32_t raw : {0u, 1u, 0x12345u, 0x0ABCDEF0u, 0x1FFFFFFFu, 0x10000000u}) {
    const auto id = decode_identifier(raw).value();
    EXPECT_EQ(encode_identifier(id).value(), raw);
  }
}

TEST(FpsIdentifier, RejectsFieldsThatDoNotFit) {
  EXPECT_EQ(encode_identifier({2048, 1, 1, ResponseCode::accepted}).error(), ProtocolErrc::positioner_out_of_range);
  EXPECT_EQ(encode_identifier({1, 1, 64, ResponseCode::accepted}).error(), ProtocolErrc::uid_out_of_range);
  EXPECT_EQ(encode_identifier({1, 1, 1, static_cast<ResponseCode>(16)}).error(), ProtocolErrc::response_out_of_range);
  EXPECT_EQ(decode_identifier(0x20000000u).error(), ProtocolErrc::invalid_identifier);
  EXPECT_EQ(decode_identifier(0xFFFFFFFFu).error(), ProtocolErrc::invalid_identifier);
}

TEST(FpsMessage, FrameRoundTrip) {
  const std::array<std::uint8_t, 8> data{0, 0, 0, 0x10, 0, 0, 0, 0x08};
  const Identifier id{17, 30, 3, ResponseCode::accepted};
  const auto frame = to_frame(id, data).value();
  EXPECT_TRUE(frame.is_extended());
  EXPECT_EQ(frame.id(), 0x00447830u);
  EXPECT_EQ(frame.to_string(), "00447830#0000001000000008");
  const auto m = from_frame(frame).value();
  EXPECT_EQ(m.id, id);
  EXPECT_EQ(m.payload.to_hex(), "00 00 00 10 00 00 00 08");
  EXPECT_EQ(to_frame(m).value(), frame);
  EXPECT_EQ(to_string(m), "17 GO_TO_ABSOLUTE_POSITION uid=3 COMMAND_ACCEPTED [00 00 00 10 00 00 00 08]");
}

TEST(FpsMessage, RejectsFramesThatAreNotExtendedData) {
  const std::array<std::uint8_t, 1> one{1};
  EXPECT_EQ(from_frame(axon::can::Frame::standard(0x123, one).value()).error(), ProtocolErrc::not_extended_frame);
  EXPECT_EQ(from_frame(axon::can::Frame::remote(0x447830, axon::can::IdFormat::extended, 8).value()).error(),
            ProtocolErrc::not_extended_frame);
}

TEST(FpsMessage, UnknownCommandNumbersStillDecode) {
  const auto m = from_frame(axon::can::Frame::extended((5u << 18) | (250u << 10), {}).value()).value();
  EXPECT_EQ(m.id.command, 250);
  EXPECT_EQ(to_string(m), "5 UNKNOWN_COMMAND_250 uid=0 COMMAND_ACCEPTED []");
}

TEST(FpsMessage, MakeRequestChecksTheCommandTable) {
  // Broadcast GET_ID (positioner 0, uid 0): the discovery frame.
  EXPECT_EQ(make_request(0, CommandId::get_id, 0).value().to_string(), "00000400#");
  EXPECT_EQ(make_request(0, CommandId::go_to_datums, 0).error(), ProtocolErrc::broadcast_not_allowed);
  EXPECT_EQ(make_request(5, CommandId::collision_detected, 1).error(), ProtocolErrc::not_sendable);
  const std::array<std::uint8_t, 4> four{};
  EXPECT_EQ(make_request(5, CommandId::go_to_absolute_position, 1, four).error(), ProtocolErrc::wrong_length);
  EXPECT_EQ(make_request(5, CommandId::get_status, 64).error(), ProtocolErrc::uid_out_of_range);
  EXPECT_EQ(make_request(2048, CommandId::get_status, 1).error(), ProtocolErrc::positioner_out_of_range);
}

TEST(FpsMessage, MakeReplyCarriesTheResponderAndCode) {
  const auto f = make_reply(17, 18, 0, ResponseCode::alpha_collision).value();
  EXPECT_EQ(f.id(), (17u << 18) | (18u << 10) | 8u);
  EXPECT_TRUE(f.payload().empty());
  EXPECT_EQ(make_reply(0, 1, 0, ResponseCode::accepted).error(), ProtocolErrc::positioner_out_of_range);
}
