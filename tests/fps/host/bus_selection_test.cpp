// The buses a host opens: given options win over the bus file, the file over the defaults.
#include "axon/fps/host/bus_selection.hpp"

#include "temp_file.hpp"

#include <gtest/gtest.h>


#include <string>

namespace axon::fps::host {
namespace {

using BusFile = testing::TempFileTest;

std::vector<std::string> texts(const BusSelection& s) {
  const auto specs = s.specs().value();
  std::vector<std::string> out;
  for (const auto& spec : specs) out.push_back(spec.to_string());
  return out;
}

TEST_F(BusFile, FillsWhatIsNotGivenAndKeepsWhatIs) {
  BusSelection s;
  s.channels = {3};
  ASSERT_TRUE(s.apply_file(write("gateway: 127.0.0.1:4000\nchannels: [1, 2]\ntimeout_ms: 250\n")).has_value());
  s.apply_defaults();
  EXPECT_EQ(s.gateway, "127.0.0.1:4000");
  EXPECT_EQ(s.channels, std::vector<int>{3});
  EXPECT_DOUBLE_EQ(s.timeout_s, 0.25);
  EXPECT_EQ(texts(s), std::vector<std::string>{"cannet://127.0.0.1:4000/3"});
}

TEST_F(BusFile, AChannelTwiceIsLocated) {
  BusSelection s;
  const auto r = s.apply_file(write("gateway: h:1\nchannels:\n  - 1\n  - 2\n  - 1\n"));
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message().find("channel 1 listed twice (first at line 3)"), std::string::npos) << r.error().message();
}

TEST_F(BusFile, UnknownKeysAreErrors) {
  BusSelection s;
  EXPECT_FALSE(s.apply_file(write("gateway: h:1\nchanels: [1]\n")).has_value());
}

TEST(BusSelection, DefaultsAreChannelOneAndCan0) {
  BusSelection s;
  s.gateway = "127.0.0.1:19228";
  s.socketcand = "127.0.0.1:29536";
  s.apply_defaults();
  EXPECT_EQ(texts(s), (std::vector<std::string>{"cannet://127.0.0.1:19228/1", "socketcand://127.0.0.1:29536/can0"}));
}

TEST(BusSelection, NothingSelectedOrOneBusTwiceIsAnError) {
  BusSelection none;
  EXPECT_EQ(none.specs().error().code, CoreErrc::invalid_argument);
  BusSelection twice;
  twice.buses = {"cannet://127.0.0.1:19228/1", "cannet://127.0.0.1:19228/1"};
  EXPECT_EQ(twice.specs().error().code, CoreErrc::invalid_argument);
}

}  // namespace
}  // namespace axon::fps::host
