// Layout files: what loads, and every error points at the offending line.
#include "axon/fps/layout/layout_file.hpp"
#include "axon/fps/layout/layout_generator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
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

// The geometry keys (arms, guide cameras, per-robot orientation, arm lengths, measured fibres):
// optional with the old values as defaults, validated, and written back as they were read.
const std::string kGeometry = std::string(kHeader) +
                              "arms: {alpha_length_mm: 7.41, beta_tip_mm: 16.25, beta_collision_mm: 14.7276}\n"
                              "robots:\n"
                              "  - {id: 1, x: 0, y: 0, sextant: 1, gateway: 1, bus: 1, fibres: [boss, metrology]}\n"
                              "  - {id: 2, x: 22.4, y: 0, sextant: 1, gateway: 1, bus: 1, fibres: [boss],\n"
                              "     orientation_deg: -90.125, alpha_length_mm: 7.3912345, beta_length_mm: 16.19,\n"
                              "     fibre_offsets: {boss: [14.9655, -0.3811], metrology: [14.3201, 0]}}\n"
                              "fiducials:\n"
                              "  - {id: 3, x: 11.2, y: 19.399}\n"
                              "guide_cameras:\n"
                              "  - {id: 2, x1: -56.54, y1: 276.26, x2: 56.54, y2: 276.26, buffer_mm: 3.5}\n"
                              "  - {id: 5, x1: 0, y1: -300, x2: 10, y2: -300}\n";

TEST(LayoutFileGeometry, LoadsArmsRobotGeometryAndGuideCameras) {
  auto r = load(kGeometry);
  ASSERT_TRUE(r.has_value()) << r.error().message();
  const auto& plane = r.value();
  EXPECT_EQ(plane.arms(), (ArmLengths{7.41, 16.25, 14.7276}));
  const auto* plain = plane.find(1);
  EXPECT_EQ(plain->orientation_deg, 0);
  EXPECT_FALSE(plain->alpha_length_mm.has_value());
  EXPECT_FALSE(plain->beta_length_mm.has_value());
  EXPECT_TRUE(plain->fibre_offsets.empty());
  const auto* measured = plane.find(2);
  EXPECT_EQ(measured->orientation_deg, -90.125);
  EXPECT_EQ(measured->alpha_length_mm, 7.3912345);
  EXPECT_EQ(measured->beta_length_mm, 16.19);
  ASSERT_EQ(measured->fibre_offsets.size(), 2u);
  EXPECT_EQ(measured->fibre_offsets[0], (FibreOffset{Fibre::boss, 14.9655, -0.3811}));
  EXPECT_EQ(measured->fibre_offsets[1], (FibreOffset{Fibre::metrology, 14.3201, 0}));
  ASSERT_EQ(plane.guide_cameras().size(), 2u);
  EXPECT_EQ(plane.guide_cameras()[0], (GuideCamera{2, -56.54, 276.26, 56.54, 276.26, 3.5}));
  EXPECT_EQ(plane.guide_cameras()[1].buffer_mm, 3.0);  // the default
}

TEST(LayoutFileGeometry, WritesTheGeometryBackExactly) {
  const auto plane = load(kGeometry).value();
  const std::string yaml = to_yaml(plane);
  EXPECT_NE(yaml.find("beta_collision_mm: 14.7276"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("alpha_length_mm: 7.3912345"), std::string::npos) << yaml;  // not cut to 4 decimals
  EXPECT_NE(yaml.find("guide_cameras:"), std::string::npos) << yaml;
  const auto again = load(yaml);
  ASSERT_TRUE(again.has_value()) << again.error().message() << "\n" << yaml;
  EXPECT_EQ(to_yaml(again.value()), yaml);
  EXPECT_EQ(again.value().arms(), plane.arms());
  EXPECT_EQ(again.value().guide_cameras(), plane.guide_cameras());
  const auto* a = plane.find(2);
  const auto* b = again.value().find(2);
  EXPECT_EQ(b->orientation_deg, a->orientation_deg);
  EXPECT_EQ(b->alpha_length_mm, a->alpha_length_mm);
  EXPECT_EQ(b->beta_length_mm, a->beta_length_mm);
  EXPECT_EQ(b->fibre_offsets, a->fibre_offsets);
}

TEST(LayoutFileGeometry, PlainLayoutsKeepTodaysGeometryAndTheirText) {
  const std::string plain = std::string(kHeader) + "robots:\n  - {id: 1, x: 0, y: 0, sextant: 1, gateway: 1, bus: 1}\n";
  const auto plane = load(plain).value();
  EXPECT_EQ(plane.arms(), ArmLengths{});
  EXPECT_EQ(plane.arms().beta_collision_mm, 14.7);
  EXPECT_TRUE(plane.guide_cameras().empty());
  const std::string yaml = to_yaml(plane);
  for (const char* key : {"arms:", "guide_cameras", "orientation_deg", "alpha_length_mm", "fibre_offsets"})
    EXPECT_EQ(yaml.find(key), std::string::npos) << key << " in\n" << yaml;
}

TEST(LayoutFileGeometry, BadLengthsAndCamerasAreLocatedErrors) {
  const std::string robot = std::string(kHeader) + "robots:\n  - {id: 1, x: 0, y: 0, sextant: 1, gateway: 1, bus: 1";
  auto e = error_of(robot + ", alpha_length_mm: -7.4}\n");
  EXPECT_NE(e.find("bench.yaml:5:"), std::string::npos) << e;
  EXPECT_NE(e.find("alpha_length_mm"), std::string::npos) << e;
  EXPECT_NE(e.find("above 0"), std::string::npos) << e;
  e = error_of(robot + ", beta_length_mm: 0}\n");
  EXPECT_NE(e.find("beta_length_mm"), std::string::npos) << e;
  e = error_of(robot + ", fibre_offsets: {gaia: [1, 2]}}\n");
  EXPECT_NE(e.find("unknown fibre 'gaia'"), std::string::npos) << e;
  e = error_of(robot + ", fibre_offsets: {boss: [1]}}\n");
  EXPECT_NE(e.find("[X, Y]"), std::string::npos) << e;
  e = error_of(robot + "}\narms: {beta_collision_mm: -1}\n");
  EXPECT_NE(e.find("bench.yaml:6:"), std::string::npos) << e;
  EXPECT_NE(e.find("beta_collision_mm"), std::string::npos) << e;
  e = error_of(robot + "}\narms: {beta_colision_mm: 14}\n");
  EXPECT_NE(e.find("beta_colision_mm"), std::string::npos) << e;
  const std::string cameras = robot + "}\nguide_cameras:\n";
  e = error_of(cameras + "  - {id: 1, x1: 5, y1: 7, x2: 5, y2: 7}\n");
  EXPECT_NE(e.find("bench.yaml:7:"), std::string::npos) << e;
  EXPECT_NE(e.find("same point"), std::string::npos) << e;
  e = error_of(cameras + "  - {id: 1, x1: 5, y1: 7, x2: 6, y2: 7, buffer_mm: -1}\n");
  EXPECT_NE(e.find("buffer_mm must not be negative"), std::string::npos) << e;
  e = error_of(cameras + "  - {id: 1, x1: 5, y1: 7, x2: 6, y2: 7}\n  - {id: 1, x1: 0, y1: 0, x2: 1, y2: 0}\n");
  EXPECT_NE(e.find("bench.yaml:8:"), std::string::npos) << e;
  EXPECT_NE(e.find("already used at line 7"), std::string::npos) << e;
  e = error_of(cameras + "  - {id: 1, x1: 5, y1: 7, x2: 6}\n");
  EXPECT_NE(e.find("y2"), std::string::npos) << e;
}

// Layouts built in code meet the same rules in FocalPlane::build, with typed errors.
TEST(LayoutFileGeometry, BuildRefusesNonFiniteNegativeAndDegenerateGeometry) {
  FocalPlaneSpec good;
  good.name = "code";
  good.gateways.push_back(GatewaySite{1, "", 0, 4});
  RobotSite r;
  r.id = 1;
  r.sextant = 1;
  r.bus = BusRef{1, 1};
  good.robots.push_back(r);
  ASSERT_TRUE(FocalPlane::build(good).has_value());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto refused = [](FocalPlaneSpec spec, const char* words) {
    auto p = FocalPlane::build(std::move(spec));
    ASSERT_FALSE(p.has_value()) << words;
    EXPECT_EQ(p.error().code, CoreErrc::config_bad_value);
    EXPECT_NE(p.error().detail.find(words), std::string::npos) << p.error().detail;
  };
  auto s = good;
  s.arms.beta_collision_mm = -14.7;
  refused(s, "beta collision segment");
  s = good;
  s.arms.alpha_length_mm = nan;
  refused(s, "alpha length");
  s = good;
  s.robots[0].alpha_length_mm = std::numeric_limits<double>::infinity();
  refused(s, "robot 1: alpha length");
  s = good;
  s.robots[0].beta_length_mm = 0.0;
  refused(s, "robot 1: beta length");
  s = good;
  s.robots[0].orientation_deg = nan;
  refused(s, "robot 1: position and orientation");
  s = good;
  s.robots[0].x_mm = nan;
  refused(s, "robot 1: position and orientation");
  s = good;
  s.robots[0].fibre_offsets = {{Fibre::boss, 15, 0}, {Fibre::boss, 15, 0.1}};
  refused(s, "boss fibre position given twice");
  s = good;
  s.guide_cameras = {GuideCamera{4, 100, 100, 100, 100, 3}};
  refused(s, "zero-length");
  s = good;
  s.guide_cameras = {GuideCamera{4, 100, 100, 110, 100, nan}};
  refused(s, "guide camera 4: buffer");
  s = good;
  s.guide_cameras = {GuideCamera{4, 100, 100, 110, 100, 3}, GuideCamera{4, 0, 100, 10, 100, 3}};
  refused(s, "guide camera 4 listed twice");
}

}  // namespace
}  // namespace axon::fps
