// A time-stamped joint trajectory on the link side, read from CSV, sampled by linear interpolation.
//
// CSV format (docs/c4g-cli.md):
//   # any line starting with '#' is a comment; blank lines are ignored
//   # units: deg            <- optional directive (rad or deg; default rad, or the caller's choice)
//   t,j1,j2,j3,j4,j5,j6     <- header: time [s] first, then one column per logical axis 1..n
//   0.0,0,0,0,0,0,0
//   0.5,10,0,0,0,0,0
// Fields are separated by commas (spaces around them are ignored). Times must be finite, start at
// 0 or later and increase strictly from row to row; values must be finite. Every row has as many
// fields as the header. Errors name the source and the line: "traj.csv:7: ...".
//
// Positions are kept in radians whatever the file's unit. Sampling before the first time gives the
// first row, after the last time the last row (velocity 0 there).
#pragma once

#include "axon/core/error.hpp"

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace axon::c4g::apps {

enum class AngleUnit { rad, deg };
std::optional<AngleUnit> parse_angle_unit(std::string_view text) noexcept;

class Trajectory {
 public:
  // `unit`: the caller's choice (a command-line option) or nullopt; a file directive that disagrees
  // with an explicit choice is an error. Without either, radians.
  static Result<Trajectory> parse(std::string_view text, std::string_view source = "trajectory",
                                  std::optional<AngleUnit> unit = std::nullopt);
  static Result<Trajectory> load(const std::string& path, std::optional<AngleUnit> unit = std::nullopt);
  // From values already in radians (tests, generated corrections). times strictly increasing.
  static Result<Trajectory> from_rows(std::vector<double> times, std::vector<std::vector<double>> rows_rad);
  // From a row-major table of rows x `axes` values (a numpy array's buffer, one row per sample),
  // the rows `row_step` apart on the trajectory's clock from 0 (seconds, or cycles: see
  // StreamOptions::per_cycle), angles in `unit`. At least one row and one axis, every value finite,
  // row_step finite and > 0; CoreErrc::invalid_argument saying which otherwise.
  static Result<Trajectory> from_table(std::span<const double> values, std::size_t axes, double row_step,
                                       AngleUnit unit = AngleUnit::rad);

  [[nodiscard]] std::size_t axes() const noexcept { return axes_; }
  [[nodiscard]] std::size_t rows() const noexcept { return times_.size(); }
  [[nodiscard]] double start_time() const noexcept { return times_.front(); }
  [[nodiscard]] double end_time() const noexcept { return times_.back(); }
  [[nodiscard]] double duration() const noexcept { return times_.back() - times_.front(); }
  [[nodiscard]] AngleUnit file_unit() const noexcept { return unit_; }
  [[nodiscard]] double time(std::size_t row) const noexcept { return times_[row]; }
  [[nodiscard]] double value(std::size_t row, std::size_t axis) const noexcept { return values_[row * axes_ + axis]; }

  // Position [rad] and velocity [rad/s] of every axis at time t (relative to the file's clock);
  // out spans must hold axes() values. No allocation.
  void sample(double t, std::span<double> position, std::span<double> velocity) const noexcept;

 private:
  std::size_t axes_ = 0;
  AngleUnit unit_ = AngleUnit::rad;
  std::vector<double> times_;
  std::vector<double> values_;  // row-major, radians
};

}  // namespace axon::c4g::apps
