// Layout files: what loads, and every error points at the offending line.
#include "axon/fps/layout/layout_file.hpp"
#include "axon/fps/layout/layout_generator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace axon::fps {
namespace {

const char* kHeader =
    "name: bench\n"
    "gateways:\n"
    "  - {id: 1, address: \"127.0.0.1:19228\", channels: 2}\n";

Result<FocalPlane> load(const std::string& text) {
  auto root = core::ConfigNode::load_string(text, "bench.yaml");
  if (!root) return root.error();
  return load_layout(root.value());
}

// The error's detail, which must name the file and line.
std::string error_of(const std::string& text) {
  auto r = load(text);
  EXPECT_FALSE(r.has_value());
  return r ? std::string() : r.error().detail;
}

TEST(LayoutFile, LoadsRobotsFlagsFibresOffsetsAndFiducials) {
  auto r = load(std::string(kHeader) +
                "robots:\n"
                "  - {id: 7, x: 0, y: 0, sextant: 1, gateway: 1, bus: 1, fibres: [boss, apogee]}\n"
                "  - {id: 9, x: 22.4, y: 0, sextant: 2, gateway: 1, bus: 2, disabled: true, offline: true,\n"
                "     offsets: {alpha: 0.5, beta: -0.25}}\n"
                "fiducials:\n"
                "  - {id: 3, x: 11.2, y: 19.399}\n");
  ASSERT_TRUE(r.has_value()) << r.error().message();
  const auto& plane = r.value();
  EXPECT_EQ(plane.name(), "bench");
  ASSERT_EQ(plane.robots().size(), 2u);
  const auto* a = plane.find(7);
  ASSERT_NE(a, nullptr);
  EXPECT_TRUE(a->carries(Fibre::boss));
  EXPECT_TRUE(a->carries(Fibre::apogee));
  EXPECT_FALSE(a->carries(Fibre::metrology));
  EXPECT_FALSE(a->disabled);
  EXPECT_FALSE(a->offsets.has_value());
  const auto* b = plane.find(9);
  ASSERT_NE(b, nullptr);
  EXPECT_EQ(b->bus, (BusRef{1, 2}));
  EXPECT_EQ(b->sextant, 2);
  EXPECT_TRUE(b->disabled);
  EXPECT_TRUE(b->offline);
  ASSERT_TRUE(b->offsets.has_value());
  EXPECT_EQ(*b->offsets, (ArmOffsets{0.5, -0.25}));
  ASSERT_EQ(plane.fiducials().size(), 1u);
  EXPECT_EQ(plane.fiducials()[0].id, 3);
  // Both robots are one pitch apart, and the fiducial is within reach of both.
  EXPECT_EQ(plane.neighbours(7).adjacent, (std::vector<std::uint16_t>{9}));
  EXPECT_EQ(plane.neighbours(9).fiducials, (std::vector<int>{3}));
  EXPECT_EQ(plane.find(8), nullptr);
  EXPECT_TRUE(plane.neighbours(8).robots.empty());
}

// Found by fuzz_fps_layout: a gateway whose key was a map ended the program (an exception out of
// the loader) instead of being refused.
TEST(LayoutFile, AKeyThatIsAMapIsRefusedNotThrown) {
  const auto why = error_of("name: bench\ngateways:\n  - {id: 1, {address: x}: 2, channels: 2}\n");
  EXPECT_NE(why.find("bench.yaml:3"), std::string::npos) << why;
  EXPECT_NE(why.find("unknown"), std::string::npos) << why;
}

TEST(LayoutFile, DuplicateIdNamesBothLines) {
  const auto e = error_of(std::string(kHeader) +
                          "robots:\n"
                          "  - {id: 7, x: 0, y: 0, sextant: 1, gateway: 1, bus: 1}\n"
                          "  - {id: 7, x: 22.4, y: 0, sextant: 1, gateway: 1, bus: 1}\n");
  EXPECT_NE(e.find("bench.yaml:6:"), std::string::npos) << e;
  EXPECT_NE(e.find("already used at line 5"), std::string::npos) << e;
}

TEST(LayoutFile, DuplicatePositionIsRejected) {
  const auto e = error_of(std::string(kHeader) +
                          "robots:\n"
                          "  - {id: 1, x: 0, y: 0, sextant: 1, gateway: 1, bus: 1}\n"
                          "  - {id: 2, x: 0.001, y: 0, sextant: 1, gateway: 1, bus: 1}\n");
  EXPECT_NE(e.find("bench.yaml:6:"), std::string::npos) << e;
  EXPECT_NE(e.find("overlaps robot 1"), std::string::npos) << e;
}

TEST(LayoutFile, FiducialOnARobotIsRejected) {
  const auto e = error_of(std::string(kHeader) +
                          "robots:\n"
                          "  - {id: 1, x: 0, y: 0, sextant: 1, gateway: 1, bus: 1}\n"
                          "fiducials:\n"
                          "  - {id: 1, x: 1, y: 1}\n");
  EXPECT_NE(e.find("bench.yaml:7:"), std::string::npos) << e;
  EXPECT_NE(e.find("fiducial 1"), std::string::npos) << e;
}

TEST(LayoutFile, BusOutsideTheGatewaysChannels) {
  const auto e = error_of(std::string(kHeader) +
                          "robots:\n"
                          "  - {id: 1, x: 0, y: 0, sextant: 1, gateway: 1, bus: 3}\n");
  EXPECT_NE(e.find("bench.yaml:5:"), std::string::npos) << e;
  EXPECT_NE(e.find("robots[0].bus"), std::string::npos) << e;
  EXPECT_NE(e.find("1..2"), std::string::npos) << e;
}

TEST(LayoutFile, UndeclaredGateway) {
  const auto e = error_of(std::string(kHeader) +
                          "robots:\n"
                          "  - {id: 1, x: 0, y: 0, sextant: 1, gateway: 4, bus: 1}\n");
  EXPECT_NE(e.find("robots[0].gateway"), std::string::npos) << e;
  EXPECT_NE(e.find("not declared"), std::string::npos) << e;
}

TEST(LayoutFile, GatewayChannelsOutOfRange) {
  const auto e = error_of("gateways:\n  - {id: 1, channels: 5}\nrobots: []\n");
  EXPECT_NE(e.find("bench.yaml:2:"), std::string::npos) << e;
  EXPECT_NE(e.find("gateways[0].channels"), std::string::npos) << e;
}

TEST(LayoutFile, SextantOutOfRange) {
  const auto e = error_of(std::string(kHeader) + "robots:\n  - {id: 1, x: 0, y: 0, sextant: 7, gateway: 1, bus: 1}\n");
  EXPECT_NE(e.find("robots[0].sextant"), std::string::npos) << e;
}

TEST(LayoutFile, UnknownKeysAreErrorsAtEveryLevel) {
  auto e = error_of(std::string(kHeader) + "robots: []\nrobot: []\n");
  EXPECT_NE(e.find("bench.yaml:5:1"), std::string::npos) << e;
  EXPECT_NE(e.find("'robot'"), std::string::npos) << e;
  e = error_of(std::string(kHeader) + "robots:\n  - {id: 1, x: 0, y: 0, sextant: 1, gateway: 1, bus: 1, fibers: [boss]}\n");
  EXPECT_NE(e.find("robots[0].fibers"), std::string::npos) << e;
  e = error_of(std::string(kHeader) +
               "robots:\n  - {id: 1, x: 0, y: 0, sextant: 1, gateway: 1, bus: 1, offsets: {alpha: 1, gamma: 2}}\n");
  EXPECT_NE(e.find("offsets.gamma"), std::string::npos) << e;
  e = error_of(std::string(kHeader) + "robots:\n  - {id: 1, x: 0, y: 0, sextant: 1, gateway: 1, bus: 1, fibres: [gaia]}\n");
  EXPECT_NE(e.find("unknown fibre 'gaia'"), std::string::npos) << e;
}

TEST(LayoutFile, MissingKeyIsNamed) {
  const auto e = error_of(std::string(kHeader) + "robots:\n  - {id: 1, x: 0, sextant: 1, gateway: 1, bus: 1}\n");
  EXPECT_NE(e.find("robots[0].y"), std::string::npos) << e;
}

// Found by fuzz_fps_layout: an address holding a double quote was written between quotes
// unescaped, so the written file did not load again. Names and addresses are YAML-quoted now.
TEST(LayoutFile, NamesAndAddressesWithQuotesAndColonsRoundTrip) {
  const std::string text = "name: 'bench #2: \"west\" \\ side'\npitch_mm: 22.4\ngateways:\n"
                           "  - {id: 1, address: 0127.0.0.1:1\", sextant: 1, channels: 4}\n"
                           "robots:\n  - {id: 1, x: 0, y: 0, sextant: 1, gateway: 1, bus: 1}\n";
  auto a = load(text);
  ASSERT_TRUE(a.has_value()) << a.error().message();
  EXPECT_EQ(a.value().spec().name, "bench #2: \"west\" \\ side");
  EXPECT_EQ(a.value().spec().gateways.at(0).address, "0127.0.0.1:1\"");
  const std::string written = to_yaml(a.value());
  auto b = load(written);
  ASSERT_TRUE(b.has_value()) << b.error().message() << "\n" << written;
  EXPECT_EQ(b.value().spec().name, a.value().spec().name);
  EXPECT_EQ(b.value().spec().gateways.at(0).address, a.value().spec().gateways.at(0).address);
  EXPECT_EQ(to_yaml(b.value()), written);
}

TEST(LayoutFile, GeneratedLayoutRoundTripsThroughYaml) {
  auto g = generate_layout();
  ASSERT_TRUE(g.has_value()) << g.error().message();
  const std::string text = to_yaml(g.value());
  auto r = load(text);
  ASSERT_TRUE(r.has_value()) << r.error().message();
  const auto& a = g.value();
  const auto& b = r.value();
  ASSERT_EQ(a.robots().size(), b.robots().size());
  ASSERT_EQ(a.fiducials().size(), b.fiducials().size());
  for (std::size_t i = 0; i < a.robots().size(); ++i) {
    const auto& x = a.robots()[i];
    const auto& y = b.robots()[i];
    EXPECT_EQ(x.id, y.id);
    EXPECT_NEAR(x.x_mm, y.x_mm, 1e-3);
    EXPECT_NEAR(x.y_mm, y.y_mm, 1e-3);
    EXPECT_EQ(x.bus, y.bus);
    EXPECT_EQ(x.sextant, y.sextant);
    EXPECT_EQ(x.fibres, y.fibres);
    EXPECT_EQ(a.neighbours(x.id).robots, b.neighbours(y.id).robots);
  }
  EXPECT_EQ(to_yaml(b), text);
}

TEST(LayoutFile, ShippedLayoutsLoad) {
  auto def = load_layout_file(std::string(AXON_TESTS_DIR) + "/../data/layouts/default.yaml");
  ASSERT_TRUE(def.has_value()) << def.error().message();
  EXPECT_EQ(def.value().robots().size(), 500u);
  auto bench = load_layout_file(std::string(AXON_TESTS_DIR) + "/../data/layouts/benchtop.yaml");
  ASSERT_TRUE(bench.has_value()) << bench.error().message();
  EXPECT_EQ(bench.value().gateways().size(), 1u);
  EXPECT_EQ(bench.value().buses().size(), 1u);
}

}  // namespace
}  // namespace axon::fps
