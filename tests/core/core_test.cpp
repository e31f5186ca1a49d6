#include "axon/core/clock.hpp"
#include "axon/core/error.hpp"
#include "axon/core/log.hpp"
#include "axon/core/realtime.hpp"

#include <gtest/gtest.h>

using namespace std::chrono_literals;

TEST(ManualClock, MovesOnlyWhenTold) {
  axon::core::ManualClock clock;
  const auto t0 = clock.now();
  const auto w0 = clock.wall();
  EXPECT_EQ(clock.now(), t0);
  clock.advance(1500us);
  EXPECT_EQ(clock.now() - t0, 1500us);
  EXPECT_EQ(clock.wall() - w0, 1500us);
}

TEST(SteadyClock, IsMonotonic) {
  auto& c = axon::core::SteadyClock::instance();
  const auto a = c.now();
  const auto b = c.now();
  EXPECT_LE(a, b);
  EXPECT_GT(c.wall().count(), 1'600'000'000'000'000'000LL);  // after 2020
}

namespace {
axon::Result<int> half(int v) {
  if (v % 2) return axon::Error(axon::CoreErrc::invalid_argument, "odd value " + std::to_string(v));
  return v / 2;
}
axon::Result<int> quarter(int v) {
  AXON_TRY(h, half(v));
  return half(h);
}
}  // namespace

TEST(Result, PropagatesTypedErrors) {
  EXPECT_EQ(quarter(8).value(), 2);
  auto r = quarter(6);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error(), axon::CoreErrc::invalid_argument);
  EXPECT_EQ(r.error().message(), "odd value 3: invalid argument; check the value against the command's help");
}

TEST(Result, ValueOfFailureThrowsTypedException) {
  try {
    (void)quarter(6).value();
    FAIL() << "no exception";
  } catch (const axon::Exception& e) {
    EXPECT_EQ(e.code(), axon::CoreErrc::invalid_argument);
    EXPECT_NE(std::string(e.what()).find("odd value 3"), std::string::npos);
  }
}

TEST(Logging, VerbosityMapsToLevels) {
  using axon::core::level_for_verbosity;
  EXPECT_EQ(level_for_verbosity(-1), spdlog::level::warn);
  EXPECT_EQ(level_for_verbosity(0), spdlog::level::info);
  EXPECT_EQ(level_for_verbosity(1), spdlog::level::debug);
  EXPECT_EQ(level_for_verbosity(3), spdlog::level::trace);
}

TEST(Realtime, ReportsEveryRequestedStep) {
  axon::core::RealtimeRequest req;
  req.fifo_priority = 150;  // out of range on Linux (1..99): refused with a reason, never fatal
  req.cpus = {0};
  auto report = axon::core::apply_realtime(req);
  ASSERT_EQ(report.steps.size(), 2u);
  EXPECT_FALSE(report.steps[0].granted);
  EXPECT_NE(report.steps[0].reason.find("1..99"), std::string::npos);
  EXPECT_TRUE(report.steps[1].granted) << report.steps[1].reason;  // CPU 0 exists everywhere
  EXPECT_FALSE(report.all_granted());
  EXPECT_NE(report.summary().find("affinity 0: granted"), std::string::npos);
}

TEST(Realtime, RefusesCpuThatDoesNotExist) {
  axon::core::RealtimeRequest req;
  req.cpus = {4096};
  auto report = axon::core::apply_realtime(req);
  ASSERT_EQ(report.steps.size(), 1u);
  EXPECT_FALSE(report.steps[0].granted);
}

// The CLI's exit code 2 ("usage error: nothing was done") rests on this: bad values and bad
// configuration files compare equal to std::errc::invalid_argument, device and I/O trouble does not.
TEST(Error, BadInputComparesEqualToInvalidArgument) {
  using axon::CoreErrc;
  for (auto e : {CoreErrc::invalid_argument, CoreErrc::config_syntax, CoreErrc::config_missing_key,
                 CoreErrc::config_bad_value, CoreErrc::config_unknown_key})
    EXPECT_TRUE(make_error_code(e) == std::errc::invalid_argument) << make_error_code(e).message();
  for (auto e : {CoreErrc::io, CoreErrc::timeout, CoreErrc::closed, CoreErrc::permission})
    EXPECT_FALSE(make_error_code(e) == std::errc::invalid_argument) << make_error_code(e).message();
  EXPECT_TRUE(make_error_code(CoreErrc::timeout) == CoreErrc::timeout);  // same-category compares unchanged
}
