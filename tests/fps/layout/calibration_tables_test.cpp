// Calibration tables (positionerTable, wokCoords, fiducialCoords, gfaCoords) into a focal plane:
// the sample under tests/fps/data/calibration, and every bad cell named by file, line and column.
#include "axon/fps/layout/calibration_tables.hpp"
#include "axon/fps/layout/layout_file.hpp"
#include "axon/fps/layout/layout_name.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

namespace axon::fps {
namespace {

const std::string kDir = std::string(AXON_TESTS_DIR) + "/fps/data/calibration";

std::string slurp(const std::string& name) {
  std::ifstream in(kDir + "/" + name);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The sample's four tables as text, to be spoiled one cell at a time.
struct SampleTables {
  std::string positioners = slurp("positionerTable.csv");
  std::string wok = slurp("wokCoords.csv");
  std::string fiducials = slurp("fiducialCoords.csv");
  std::string cameras = slurp("gfaCoords.csv");

  Result<FocalPlane> parse() const {
    CalibrationText t;
    t.positioners = positioners;
    t.wok = wok;
    t.fiducials = fiducials;
    t.guide_cameras = cameras;
    return parse_calibration_tables(t);
  }
  std::string error() const {
    auto r = parse();
    EXPECT_FALSE(r.has_value());
    return r ? std::string() : r.error().detail;
  }
};

void spoil(std::string& text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  ASSERT_NE(at, std::string::npos) << from;
  text.replace(at, from.size(), to);
}

TEST(CalibrationTables, ReadsTheSampleDirectory) {
  auto r = load_calibration_dir(kDir);
  ASSERT_TRUE(r.has_value()) << r.error().message();
  const auto& plane = r.value();
  EXPECT_EQ(plane.name(), "calibration");
  EXPECT_EQ(plane.arms(), (ArmLengths{7.4, 16.2, 14.7276}));
  ASSERT_EQ(plane.robots().size(), 6u);
  EXPECT_EQ(plane.robots()[0].id, 101);  // table order

  // Robot 102 in hole R+13C7 (-11.2, 252.1866), axes i = (0, -1), j = (1, 0), dx 0.08, dy -0.11.
  const auto* r102 = plane.find(102);
  ASSERT_NE(r102, nullptr);
  EXPECT_NEAR(r102->x_mm, -11.2 - 0.11, 1e-12);
  EXPECT_NEAR(r102->y_mm, 252.1866 - 0.08, 1e-12);
  EXPECT_NEAR(r102->orientation_deg, -90, 1e-12);
  EXPECT_EQ(r102->alpha_length_mm, 7.4215);
  EXPECT_FALSE(r102->beta_length_mm.has_value());
  ASSERT_TRUE(r102->offsets.has_value());
  EXPECT_EQ(*r102->offsets, (ArmOffsets{-0.31, 0.22}));
  // A Boss hole: metrology and boss fibres, no apogee.
  EXPECT_TRUE(r102->carries(Fibre::metrology));
  EXPECT_TRUE(r102->carries(Fibre::boss));
  EXPECT_FALSE(r102->carries(Fibre::apogee));
  ASSERT_EQ(r102->fibre_offsets.size(), 2u);
  EXPECT_EQ(r102->fibre_offsets[0], (FibreOffset{Fibre::metrology, 14.3388, 0.0}));
  EXPECT_EQ(r102->fibre_offsets[1], (FibreOffset{Fibre::boss, 14.9871, -0.3702}));
  EXPECT_TRUE(plane.find(103)->carries(Fibre::apogee));
  // Robot 104's hole is turned: axes i = (1, 0), j = (0, 1).
  EXPECT_NEAR(plane.find(104)->orientation_deg, 0, 1e-12);
  // No wiring in the tables: the sextant of the azimuth (all near 90 deg: sextant 2), bus 1.
  EXPECT_EQ(r102->sextant, 2);
  EXPECT_EQ(r102->bus, (BusRef{2, 1}));

  ASSERT_EQ(plane.fiducials().size(), 2u);
  EXPECT_EQ(plane.fiducials()[0].id, 17);
  EXPECT_EQ(plane.fiducials()[1].id, 23);
  EXPECT_EQ(plane.fiducials()[1].x_mm, 0.0387);

  ASSERT_EQ(plane.guide_cameras().size(), 2u);
  const auto& top = plane.guide_cameras()[0];
  EXPECT_EQ(top.id, 2);
  EXPECT_NEAR(top.x1_mm, -56.54, 1e-9);
  EXPECT_NEAR(top.x2_mm, 56.54, 1e-9);
  EXPECT_NEAR(top.y1_mm, 327.6 - 51.34, 1e-9);
  EXPECT_NEAR(top.y2_mm, 327.6 - 51.34, 1e-9);
  EXPECT_EQ(top.buffer_mm, 3.0);
  // The turned camera: its edge lies 276.26 mm from the centre too, 113.08 mm long.
  const auto& turned = plane.guide_cameras()[1];
  const double mx = (turned.x1_mm + turned.x2_mm) / 2, my = (turned.y1_mm + turned.y2_mm) / 2;
  EXPECT_NEAR(std::hypot(mx, my), std::hypot(283.7, -163.8) - 51.34, 1e-3);
  EXPECT_NEAR(std::hypot(turned.x2_mm - turned.x1_mm, turned.y2_mm - turned.y1_mm), 113.08, 1e-9);
}

TEST(CalibrationTables, ADirectoryIsALayoutNameAndWritesAsYaml) {
  auto r = resolve_layout(kDir);
  ASSERT_TRUE(r.has_value()) << r.error().message();
  const std::string yaml = to_yaml(r.value());
  auto root = core::ConfigNode::load_string(yaml, "from-tables.yaml");
  ASSERT_TRUE(root.has_value());
  auto again = load_layout(root.value());
  ASSERT_TRUE(again.has_value()) << again.error().message() << "\n" << yaml;
  EXPECT_EQ(to_yaml(again.value()), yaml);
  EXPECT_EQ(again.value().guide_cameras().size(), 2u);
  EXPECT_EQ(again.value().find(105)->alpha_length_mm, r.value().find(105)->alpha_length_mm);
}

TEST(CalibrationTables, ABadCellNamesFileLineAndColumn) {
  SampleTables s;
  spoil(s.positioners, "7.4215", "7.4x15");
  auto e = s.error();
  EXPECT_NE(e.find("positionerTable.csv:3: column 'alphaArmLen'"), std::string::npos) << e;
  EXPECT_NE(e.find("'7.4x15'"), std::string::npos) << e;

  s = SampleTables{};
  spoil(s.positioners, "7.4215", "-7.4215");
  EXPECT_NE(s.error().find("column 'alphaArmLen': an arm length must be above 0"), std::string::npos) << s.error();

  s = SampleTables{};
  spoil(s.positioners, ",103,", ",3000,");
  EXPECT_NE(s.error().find("positionerTable.csv:4: column 'positionerID': expected an id 1..2047"), std::string::npos)
      << s.error();

  s = SampleTables{};
  spoil(s.positioners, ",103,", ",102,");
  EXPECT_NE(s.error().find("robot 102 already listed at line 3"), std::string::npos) << s.error();

  s = SampleTables{};
  spoil(s.positioners, "R+12C9", "R+99C9");
  EXPECT_NE(s.error().find("positionerTable.csv:7: column 'holeID': hole 'R+99C9' is not in the wok table"),
            std::string::npos)
      << s.error();

  s = SampleTables{};
  spoil(s.wok, ",11.2,252.1866,0,0,-1,0,1,0", ",11.2,252.1866,0,0,-1,0,-1,0");  // a left-handed frame
  EXPECT_NE(s.error().find("wokCoords.csv:4: column 'ix': axes"), std::string::npos) << s.error();

  s = SampleTables{};
  spoil(s.wok, "-22.4,232.7876,0", "-22.4,nan,0");
  EXPECT_NE(s.error().find("wokCoords.csv:7: column 'yWok': expected a finite number, got 'nan'"), std::string::npos)
      << s.error();

  s = SampleTables{};
  spoil(s.fiducials, "F23", "Fx");
  EXPECT_NE(s.error().find("fiducialCoords.csv:3: column 'id'"), std::string::npos) << s.error();

  s = SampleTables{};
  spoil(s.cameras, "283.7,-163.8,0", "283.7,-163.8");
  EXPECT_NE(s.error().find("gfaCoords.csv:3: 14 cells, but the header names 15 columns"), std::string::npos)
      << s.error();

  s = SampleTables{};
  spoil(s.positioners, "betaOffset", "betaOffs");
  EXPECT_NE(s.error().find("positionerTable.csv:1: no column 'betaOffset'"), std::string::npos) << s.error();

  s = SampleTables{};
  s.fiducials.clear();
  EXPECT_NE(s.error().find("fiducialCoords.csv:1: empty table"), std::string::npos) << s.error();
}

TEST(CalibrationTables, AMissingTableIsAnIoError) {
  auto r = load_calibration_dir(std::string(AXON_TESTS_DIR) + "/fps/data");
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error().code, CoreErrc::io);
  EXPECT_NE(r.error().detail.find("positionerTable.csv"), std::string::npos) << r.error().detail;
  EXPECT_FALSE(is_calibration_dir(std::string(AXON_TESTS_DIR) + "/fps/data"));
  EXPECT_TRUE(is_calibration_dir(kDir));
}

}  // namespace
}  // namespace axon::fps
