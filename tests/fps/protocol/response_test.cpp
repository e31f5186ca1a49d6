#include "axon/fps/protocol/response.hpp"

#include "axon/fps/protocol/error.hpp"

#include <gtest/gtest.h>

using namespace axon::fps::protocol;

TEST(FpsResponse, NamesFollowTheCodeTable) {
  EXPECT_EQ(response_name(ResponseCode::accepted), "COMMAND_ACCEPTED");
  EXPECT_EQ(response_name(ResponseCode::incorrect_data_length), "INCORRECT_DATA_LENGTH");
  EXPECT_EQ(response_name(ResponseCode::beta_collision), "BETA_COLLISION");
  EXPECT_EQ(response_name(ResponseCode::hall_sensors_disabled), "HALL_SENSORS_DISABLED");
  EXPECT_EQ(response_name(static_cast<ResponseCode>(16)), "UNKNOWN_RESPONSE");
  EXPECT_EQ(static_cast<int>(ResponseCode::invalid_broadcast), 10);
  EXPECT_EQ(static_cast<int>(ResponseCode::datum_not_calibrated), 14);
}

TEST(FpsResponse, EveryFailureHasMeaningAndAdvice) {
  EXPECT_TRUE(response_advice(ResponseCode::accepted).empty());
  for (unsigned c = 1; c <= kMaxResponseCode; ++c) {
    const auto code = static_cast<ResponseCode>(c);
    EXPECT_FALSE(response_meaning(code).empty()) << c;
    EXPECT_FALSE(response_advice(code).empty()) << c;
  }
  // The beta collision advice names the beta open-loop command, not alpha's.
  EXPECT_NE(response_advice(ResponseCode::beta_collision).find("125"), std::string_view::npos);
  EXPECT_NE(response_advice(ResponseCode::hall_sensors_disabled).find("116"), std::string_view::npos);
}

TEST(FpsResponse, TravelsAsAnAxonError) {
  const axon::Error e(ResponseCode::datum_not_initialized, "positioner 17 GO_TO_ABSOLUTE_POSITION");
  EXPECT_EQ(e, ResponseCode::datum_not_initialized);
  EXPECT_STREQ(e.code.category().name(), "axon.fps.response");
  EXPECT_NE(e.message().find("DATUM_NOT_INITIALIZED"), std::string::npos);
  EXPECT_NE(e.message().find("GO_TO_DATUMS"), std::string::npos);
  // Accepted is success.
  EXPECT_FALSE(std::error_code(ResponseCode::accepted));
  EXPECT_TRUE(std::error_code(ResponseCode::value_out_of_range));
}

TEST(FpsResponse, ChecksTheFourBitRange) {
  EXPECT_EQ(response_code_from(15).value(), ResponseCode::hall_sensors_disabled);
  EXPECT_EQ(response_code_from(16).error(), ProtocolErrc::response_out_of_range);
}

TEST(FpsResponse, MapsCodecErrorsToWhatADeviceAnswers) {
  EXPECT_EQ(response_code_for(ProtocolErrc::wrong_length), ResponseCode::incorrect_data_length);
  EXPECT_EQ(response_code_for(ProtocolErrc::value_out_of_range), ResponseCode::value_out_of_range);
  EXPECT_EQ(response_code_for(ProtocolErrc::invalid_trajectory), ResponseCode::invalid_trajectory);
  EXPECT_EQ(response_code_for(ProtocolErrc::unknown_command), ResponseCode::unknown_command);
  EXPECT_EQ(response_code_for(ProtocolErrc::broadcast_not_allowed), ResponseCode::invalid_broadcast);
}
