#include "axon/blmc/host/error.hpp"

#include <gtest/gtest.h>

// Exit code 2 in the CLI is for bad input only (std::errc::invalid_argument), not a board that failed.
TEST(BlmcErrorCondition, BadInputIsInvalidArgumentAndBoardTroubleIsNot) {
  using axon::blmc::host::HostErrc;
  EXPECT_TRUE(make_error_code(HostErrc::invalid_argument) == std::errc::invalid_argument);
  EXPECT_FALSE(make_error_code(HostErrc::timeout) == std::errc::invalid_argument);
  EXPECT_FALSE(make_error_code(HostErrc::not_ready) == std::errc::invalid_argument);
}
