#include "axon/can/bus_spec.hpp"

#include <gtest/gtest.h>

using namespace axon::can;

TEST(BusSpec, ParsesEveryKind) {
  auto v = parse_bus_spec("virtual:vcan0").value();
  EXPECT_EQ(v.kind, BusSpec::Kind::virtual_bus);
  EXPECT_EQ(v.channel, "vcan0");

  auto s = parse_bus_spec("socketcand://127.0.0.1:4000/can1").value();
  EXPECT_EQ(s.kind, BusSpec::Kind::socketcand);
  EXPECT_EQ(s.endpoint.host, "127.0.0.1");
  EXPECT_EQ(s.endpoint.port, 4000);
  EXPECT_EQ(s.channel, "can1");
  EXPECT_EQ(parse_bus_spec("socketcand://gw/can0").value().endpoint.port, kSocketcandPort);

  auto c = parse_bus_spec("cannet://10.0.0.5/3").value();
  EXPECT_EQ(c.kind, BusSpec::Kind::cannet);
  EXPECT_EQ(c.endpoint.port, kCanNetPort);
  EXPECT_EQ(c.cannet_channel, 3);
  EXPECT_EQ(c.short_name(), "cannet3");

  auto k = parse_bus_spec("socketcan:can0").value();
  EXPECT_EQ(k.kind, BusSpec::Kind::socketcan);
  EXPECT_EQ(k.channel, "can0");
}

TEST(BusSpec, RoundTripsToString) {
  for (const char* t : {"virtual:a", "socketcand://127.0.0.1:29536/vcan0", "cannet://[::1]:19228/4", "socketcan:can0"})
    EXPECT_EQ(parse_bus_spec(t).value().to_string(), t);
}

TEST(BusSpec, RejectsBadSpecsWithReason) {
  for (const char* t : {"", "can0", "virtual:", "virtual:a b", "cannet://gw/5", "cannet://gw/0", "cannet://gw",
                        "socketcand://gw", "socketcand://:1/x", "socketcand://gw:99999/x", "socketcan:waytoolonginterfacename",
                        "tcp://gw/1"}) {
    auto r = parse_bus_spec(t);
    ASSERT_FALSE(r) << t;
    EXPECT_EQ(r.error(), CanErrc::bad_spec) << t;
    EXPECT_NE(r.error().message().find(t), std::string::npos) << r.error().message();
  }
}

// A bus or frame the user typed wrong is a usage error (CLI exit code 2); a device's trouble is not.
TEST(BusSpec, BadSpecAndBadFrameTextCompareEqualToInvalidArgument) {
  EXPECT_TRUE(parse_bus_spec("no-such-transport:x").error().code == std::errc::invalid_argument);
  EXPECT_TRUE(make_error_code(CanErrc::parse_error) == std::errc::invalid_argument);
  EXPECT_FALSE(make_error_code(CanErrc::timeout) == std::errc::invalid_argument);
  EXPECT_FALSE(make_error_code(CanErrc::connect_failed) == std::errc::invalid_argument);
}
