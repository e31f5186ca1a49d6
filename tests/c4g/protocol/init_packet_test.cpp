#include "axon/c4g/protocol/init_packet.hpp"

#include "axon/c4g/protocol/error.hpp"
#include "c4g/protocol/example_init.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

using namespace axon::c4g::protocol;
using axon::c4g::protocol::test::manual_example_init;

namespace {

std::vector<std::byte> encoded(const InitPacket& p) {
  std::vector<std::byte> buf(kInitPacketSize);
  encode_init(p, buf).value();
  return buf;
}
std::int32_t int_at(const std::vector<std::byte>& b, std::size_t off) {
  std::int32_t v = 0;
  std::memcpy(&v, b.data() + off, 4);  // the test host is little-endian like the wire
  return v;
}
float float_at(const std::vector<std::byte>& b, std::size_t off) {
  float v = 0;
  std::memcpy(&v, b.data() + off, 4);
  return v;
}

}  // namespace

TEST(C4gInitPacket, HasThreeHundredFieldsAndTwelveHundredBytes) {
  std::size_t n = 0;
  InitPacket p;
  for_each_field(p, [&](std::string_view, int, auto&) { ++n; });
  EXPECT_EQ(n, 300u);
  EXPECT_EQ(kInitPacketSize, 1200u);
  EXPECT_EQ(encoded(manual_example_init()).size(), 1200u);
}

TEST(C4gInitPacket, FieldsAreInTheControllersStructOrder) {
  EXPECT_EQ(init_field_name(0), "nblip");
  EXPECT_EQ(init_field_name(3), "nAxOpen");
  EXPECT_EQ(init_field_name(4), "arm1OpenMask[0]");
  EXPECT_EQ(init_field_name(43), "arm4OpenMask[9]");
  EXPECT_EQ(init_field_name(44), "num");
  EXPECT_EQ(init_field_name(47), "sMax");
  EXPECT_EQ(init_field_name(55), "ext3Ax");
  EXPECT_EQ(init_field_name(56), "period");
  EXPECT_EQ(init_field_name(57), "arm1OpenAx[0]");
  EXPECT_EQ(init_field_name(97), "arm1CalData[0]");
  EXPECT_EQ(init_field_name(137), "arm1AzLim[0]");
  EXPECT_EQ(init_field_name(177), "majorVersion");
  EXPECT_EQ(init_field_name(179), "buildNum");
  EXPECT_EQ(init_field_name(180), "arm1AxInfo[0]");
  EXPECT_EQ(init_field_name(220), "arm1TxRate[0]");
  EXPECT_EQ(init_field_name(260), "arm1FollowError[0]");
  EXPECT_EQ(init_field_name(299), "arm4FollowError[9]");
  EXPECT_EQ(init_field_name(300), "?");
}

TEST(C4gInitPacket, ManualExampleEncodesAtTheStructOffsets) {
  const auto b = encoded(manual_example_init());
  EXPECT_EQ(int_at(b, 0), 10);     // protocol number
  EXPECT_EQ(int_at(b, 4), 3);      // fields per packet
  EXPECT_EQ(int_at(b, 8), 9);      // fields per axis
  EXPECT_EQ(int_at(b, 12), 6);     // open axes
  EXPECT_EQ(int_at(b, 176), 1);    // NUM type
  EXPECT_EQ(int_at(b, 184), 3);    // CMD type
  EXPECT_EQ(int_at(b, 212), 3);    // EXT1 type
  EXPECT_EQ(int_at(b, 224), 2);    // period [ms]
  EXPECT_EQ(int_at(b, 228), 1);    // arm 1 open axis 1
  EXPECT_EQ(int_at(b, 248), 6);    // arm 1 open axis 6
  EXPECT_EQ(float_at(b, 388), 0.142965f);      // arm 1 calibration, axis 1
  EXPECT_EQ(float_at(b, 408), 0.355824f);      // arm 1 calibration, axis 6
  EXPECT_EQ(float_at(b, 548), 24.5f);          // arm 1 current limit, axis 1
  EXPECT_EQ(float_at(b, 560), 9.5f);           // arm 1 current limit, axis 4
  EXPECT_EQ(int_at(b, 708), 3);                // major version
  EXPECT_EQ(int_at(b, 712), 11);               // minor version
  EXPECT_EQ(int_at(b, 716), 115);              // build
  EXPECT_EQ(float_at(b, 732), -0.02f);         // arm 1 influence, axis 4
  EXPECT_EQ(float_at(b, 740), 0.02f);          // arm 1 influence, axis 6
  EXPECT_EQ(float_at(b, 880), -181.587296f);   // arm 1 transmission ratio, axis 1
  EXPECT_EQ(float_at(b, 900), -50.0f);         // arm 1 transmission ratio, axis 6
  EXPECT_EQ(float_at(b, 1040), 7.5f);          // arm 1 following error, axis 1
  EXPECT_EQ(float_at(b, 1060), 0.0f);          // arm 1 following error, axis 6
}

TEST(C4gInitPacket, ManualExampleRoundTrips) {
  const InitPacket p = manual_example_init();
  const auto back = decode_init(encoded(p)).value();
  EXPECT_EQ(back, p);
  EXPECT_EQ(back.transmission_ratio[0][4], 78.75f);
  EXPECT_EQ(back.influence[0][4], 0.0204f);
  EXPECT_EQ(back.calibration[0][4], 0.039380f);
}

TEST(C4gInitPacket, PrintsEveryGroupWithNames) {
  const auto s = to_string(manual_example_init());
  EXPECT_NE(s.find("protocol number: 10"), std::string::npos);
  EXPECT_NE(s.find("open axes: 6"), std::string::npos);
  EXPECT_NE(s.find("open axes (logical, 1-based) ARM1: 1 2 3 4 5 6 X X X X"), std::string::npos);
  EXPECT_NE(s.find("calibration constants [turns] ARM1: 0.142965 0.170353 0.222660 0.405883 0.039380 0.355824"),
            std::string::npos);
  EXPECT_NE(s.find("transmission ratios ARM1: -181.587296 159.260864"), std::string::npos);
  EXPECT_NE(s.find("influence coefficients ARM1: 0.000000 0.000000 0.000000 -0.020000 0.020400 0.020000"),
            std::string::npos);
  EXPECT_NE(s.find("period: 2 ms"), std::string::npos);
  EXPECT_NE(s.find("software version: 3.11.115"), std::string::npos);
}

TEST(C4gInitPacket, RejectsWrongSizes) {
  for (std::size_t n : {0u, 4u, 1196u, 1199u, 1201u, 1204u, 228u}) {
    std::vector<std::byte> b(n);
    const auto r = decode_init(b);
    ASSERT_FALSE(r.has_value()) << n;
    EXPECT_EQ(r.error(), ProtocolErrc::wrong_size);
  }
  std::vector<std::byte> small(1199);
  EXPECT_EQ(encode_init(manual_example_init(), small).error(), ProtocolErrc::wrong_size);
}

TEST(C4gInitPacket, RejectsBadHeaderValues) {
  auto b = encoded(manual_example_init());
  auto with_int = [&](std::size_t off, std::int32_t v) {
    auto c = b;
    std::memcpy(c.data() + off, &v, 4);
    return decode_init(c);
  };
  EXPECT_EQ(with_int(4, 4).error(), ProtocolErrc::bad_field_count);
  EXPECT_EQ(with_int(8, 8).error(), ProtocolErrc::bad_field_count);
  EXPECT_EQ(with_int(12, 0).error(), ProtocolErrc::too_many_axes);
  EXPECT_EQ(with_int(12, 21).error(), ProtocolErrc::too_many_axes);
  EXPECT_EQ(with_int(12, -3).error(), ProtocolErrc::too_many_axes);
  EXPECT_EQ(with_int(224, 0).error(), ProtocolErrc::value_out_of_range);
  EXPECT_TRUE(with_int(12, 20).has_value());  // the count alone is in range; AxisMap checks the lists
}

TEST(C4gInitPacket, RejectsNonFiniteFloatsNamingTheField) {
  const auto b = encoded(manual_example_init());
  for (std::size_t off : {388u, 548u, 720u, 900u, 1196u}) {
    auto c = b;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    std::memcpy(c.data() + off, &nan, 4);
    const auto r = decode_init(c);
    ASSERT_FALSE(r.has_value()) << off;
    EXPECT_EQ(r.error(), ProtocolErrc::not_finite);
    EXPECT_NE(r.error().detail.find(init_field_name(off / 4)), std::string::npos) << r.error().detail;
  }
  InitPacket p = manual_example_init();
  p.following_error[3][9] = std::numeric_limits<float>::infinity();
  std::vector<std::byte> out(1200);
  EXPECT_EQ(encode_init(p, out).error(), ProtocolErrc::not_finite);
}
