// The focal plane from the calibration tables an installation publishes (the CSV files the SDSS
// focal planes keep per wok: positionerTable.csv, wokCoords.csv, fiducialCoords.csv,
// gfaCoords.csv; format in docs/fps-layout.md).
//
// What each table gives:
// - wokCoords: per hole its id (holeID), type (holeType: ApogeeBoss, Boss, Fiducial...), centre
//   (xWok, yWok) and axes (ix, iy: the robot's x axis; jx, jy: its y axis) in the wok frame.
// - positionerTable: per robot its id (positionerID), hole, alpha arm length (alphaArmLen),
//   metrology/apogee/boss fibre positions on the beta arm (metX, metY, apX, apY, bossX, bossY),
//   zero offsets (alphaOffset, betaOffset) and the alpha axis' offset from the hole centre along
//   the hole's axes (dx, dy).
// - fiducialCoords: per fiducial its id ("F" and a number) and centre (xWok, yWok).
// - gfaCoords: per guide camera its id, centre (xWok, yWok) and axes (ix, iy, jx, jy); the edge
//   the robots can touch is a segment in the camera's own frame (CalibrationOptions).
//
// The focal-plane frame is the wok's x, y (a flat wok: z and the k axis are not used). A robot
// sits at hole centre + dx * i + dy * j and faces atan2(iy, ix). Columns other than these are
// ignored, in any order; a leading unnamed index column (as pandas writes it) is fine. Cells are
// plain (no quoting). The tables carry no wiring: every robot gets the sextant of its azimuth (the
// 60-degree wedges counter-clockwise from +x), that sextant's gateway (ids 1..6, no address) and
// bus 1, which is what planning needs and nothing more.
//
// Errors are CoreErrc::config_bad_value (CoreErrc::io for a table that cannot be read) naming
// the file, the line and the column: a missing column, a cell that is not a finite number, a
// robot id outside 1..2047, a hole that wokCoords lacks, a duplicate id, axes that are not a
// right-handed orthonormal pair, a row with the wrong number of cells.
#pragma once

#include "axon/core/error.hpp"
#include "axon/fps/layout/focal_plane.hpp"

#include <string>
#include <string_view>

namespace axon::fps {

struct CalibrationOptions {
  std::string name;  // the plane's name (empty: the directory's name, or "calibration")
  double pitch_mm = kDefaultPitchMm;
  // The arms every robot shares: alpha arm and beta tip as designed, the collision segment as the
  // installation's planner models it (beta axis to 14.7276 mm).
  ArmLengths arms{.beta_collision_mm = 14.7276};
  // A guide camera's edge in the camera's frame: from -half_length to +half_length along its i
  // axis, `inset` towards the plane's centre along -j (the in-service planner's six edges lie
  // 51.34 mm inside the camera centres and are 113.08 mm long).
  double camera_half_length_mm = 56.54;
  double camera_inset_mm = 51.34;
  double camera_buffer_mm = 3.0;
};

// The four tables' text; the names are what errors cite (e.g. "cal/positionerTable.csv").
struct CalibrationText {
  std::string_view positioners, wok, fiducials, guide_cameras;
  std::string positioners_name = "positionerTable.csv";
  std::string wok_name = "wokCoords.csv";
  std::string fiducials_name = "fiducialCoords.csv";
  std::string guide_cameras_name = "gfaCoords.csv";
};

[[nodiscard]] Result<FocalPlane> parse_calibration_tables(const CalibrationText& text, const CalibrationOptions& options = {});
// Reads DIR/positionerTable.csv, DIR/wokCoords.csv, DIR/fiducialCoords.csv and DIR/gfaCoords.csv
// (all four required).
[[nodiscard]] Result<FocalPlane> load_calibration_dir(const std::string& dir, const CalibrationOptions& options = {});
// True when `dir` is a directory holding positionerTable.csv.
[[nodiscard]] bool is_calibration_dir(const std::string& dir);

}  // namespace axon::fps
