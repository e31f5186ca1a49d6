// The manual's monitoring views ("monis", types 19-24) rebuilt on the PC side, as CSV.
//
// The controller's monis sample, per interpolator tick and per axis, six values taken from the two
// packets of the cycle. The manual names them from the controller's side: its "RX packet" is the
// PC's reply, its "TX packet" the controller's own packet. Here columns say who sent the value:
// `pc_` (the reply) or `c4g_` (the controller's packet). Every value of every view is in the cyclic
// data the PC sees, so all six views are exported exactly, with these differences from the
// controller's own moni: the reply is the one the PC built (a reply lost on the wire still appears),
// time comes from the PC's clock (packet arrival), and the sixth value, the axis mode, is the one
// the controller announced in its packet.
//
//   19: pc d1 d2 d3 d4 d5, mode            (the whole reply)
//   20: c4g d1 d2 d3 d4 d5, mode           (the whole controller packet)
//   21: pc d1, pc d2, c4g d1, c4g d3, c4g d5, mode      (mode 5)
//   22: pc d4, pc d5, c4g d1, c4g d3, c4g d5, mode      (mode 2)
//   23: c4g d1, c4g d5, c4g ext1, c4g ext2, pc d5, mode (mode 9)
//   24: c4g d1, c4g d5, c4g ext1, c4g ext2, pc d4, mode (mode 8)
// Type 0 ("all") is not the manual's: every field of both packets plus NUM/INFPAR/CMD.
//
// A row: cycle, time [s] since the first row, then the view's columns for each open axis
// (a1_..., a2_..., in open order).
#pragma once

#include "axon/c4g/protocol/packet.hpp"
#include "axon/core/error.hpp"
#include "axon/core/rotating_file.hpp"

#include <array>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>

namespace axon::c4g::apps {

struct MoniColumn {
  std::string_view name;  // e.g. "pc_d1"
  bool from_pc;           // the reply (true) or the controller's packet (false)
  int field;              // 0 = SM (mode), 1..5 = D1..D5, 6..8 = EXT1..EXT3
};

// 19..24, or 0 for every field; false otherwise.
bool is_moni_type(int type) noexcept;
// The columns of one axis in a view.
std::span<const MoniColumn> moni_columns(int type) noexcept;
std::string moni_header(int type, std::size_t axes);
// One CSV row (with its newline) appended to out.
void append_moni_row(std::string& out, int type, std::uint64_t cycle, double time_s,
                     const protocol::Packet& from_controller, const protocol::Packet& from_pc);

// Writes rows to a file; the header goes out with the first row (when the axis count is known).
class MoniCsvWriter {
 public:
  // `rotation`: a size or age limit (none by default): the full file becomes PATH.1, and every
  // file starts with the title line (core::RotatingFile).
  static Result<std::unique_ptr<MoniCsvWriter>> open(const std::string& path, int type, core::RotationLimits rotation = {});
  ~MoniCsvWriter();
  MoniCsvWriter(const MoniCsvWriter&) = delete;
  MoniCsvWriter& operator=(const MoniCsvWriter&) = delete;

  // Not for the cycle thread (it formats and may rotate the file). A failed write is counted and
  // logged once.
  void write(std::uint64_t cycle, std::int64_t wall_ns, const protocol::Packet& from_controller,
             const protocol::Packet& from_pc);
  void flush();
  [[nodiscard]] std::uint64_t rows() const noexcept { return rows_; }
  [[nodiscard]] std::uint64_t write_errors() const noexcept { return write_errors_; }
  [[nodiscard]] std::uint64_t rotations() const noexcept { return file_ ? file_->rotations() : 0; }
  [[nodiscard]] const std::string& path() const noexcept { return path_; }

 private:
  MoniCsvWriter() = default;
  std::string path_;
  int type_ = 0;
  std::optional<core::RotatingFile> file_;
  std::size_t axes_ = 0;
  std::int64_t t0_ = 0;
  std::uint64_t rows_ = 0;
  std::uint64_t write_errors_ = 0;
  std::string line_;
};

}  // namespace axon::c4g::apps
