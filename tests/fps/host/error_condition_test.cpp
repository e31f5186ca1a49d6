#include "axon/fps/host/error.hpp"
#include "axon/fps/plc/error.hpp"

#include <gtest/gtest.h>

// The CLI exits 2 ("bad input, nothing was sent") only for errors equal to
// std::errc::invalid_argument; a robot that failed is not bad input.
TEST(FpsErrorCondition, BadInputIsInvalidArgumentAndDeviceTroubleIsNot) {
  using axon::fps::host::HostErrc;
  using axon::fps::plc::PlcErrc;
  EXPECT_TRUE(make_error_code(HostErrc::invalid_argument) == std::errc::invalid_argument);
  EXPECT_TRUE(make_error_code(PlcErrc::invalid_argument) == std::errc::invalid_argument);
  for (auto e : {HostErrc::timeout, HostErrc::collision, HostErrc::locked, HostErrc::sequence_failed})
    EXPECT_FALSE(make_error_code(e) == std::errc::invalid_argument) << make_error_code(e).message();
  EXPECT_FALSE(make_error_code(PlcErrc::timeout) == std::errc::invalid_argument);
  EXPECT_TRUE(make_error_code(HostErrc::locked) == HostErrc::locked);
}
