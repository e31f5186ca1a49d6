// candump log files: the text format of can-utils' `candump -l` (read by canplayer and log2asc)
// and of python-can's CanutilsLogReader/Writer. One frame per line:
//
//   (1436509052.249713) vcan0 12345678#01020304
//   (SECONDS.MICROS)    IFACE ID#DATA
//
// ID has 3 hex digits (11-bit) or 8 (29-bit). DATA is 0..8 bytes as hex pairs; `R` or `R<n>`
// instead of data is a remote frame with DLC n. An 8-digit id with bit 29 (0x20000000) set is a
// controller error report, not a frame. python-can adds a fourth field, ` R` or ` T` (received
// or transmitted); it is read and kept, never written.
//
// Not supported, and refused with CanErrc::not_supported rather than misread: CAN FD (`ID##...`)
// and raw DLC suffixes (`..._C`, classic frames with DLC 9..15). See docs/can-logs.md.
#pragma once

#include "axon/can/frame.hpp"
#include "axon/core/rotating_file.hpp"

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

namespace axon::can {

// Error-flag bit of the 8-digit id that marks an error report in a log line.
inline constexpr std::uint32_t kCandumpErrorFlag = 0x2000'0000U;

enum class LogDirection : std::uint8_t { unknown, rx, tx };

struct LogEntry {
  // The frame with its timestamp. For an error report: an extended frame whose id holds the
  // error classes (the id without the error flag) and whose data are the report's detail bytes.
  Frame frame;
  std::string iface;
  bool error_frame = false;
  LogDirection direction = LogDirection::unknown;  // only python-can logs say
};

// Parses one line (surrounding white space and a CR from CRLF files are ignored).
// Errors: parse_error for anything that is not the format above (the detail says what);
// not_supported for CAN FD frames and raw DLC suffixes.
Result<LogEntry> parse_candump_line(std::string_view line);

// The line (without newline) candump would write for the frame: seconds padded to 10 digits,
// microseconds to 6 (the timestamp is truncated to the microsecond; a negative or unknown one
// is written as 0). White space in iface becomes '_', an empty one "any".
std::string format_candump_line(const Frame& frame, std::string_view iface);
// As above; error reports are written with the error flag in the id.
std::string format_candump_line(const LogEntry& entry);

// Writes candump log lines to a stream or a file.
class CandumpWriter {
 public:
  enum class Flush : std::uint8_t { every_line, on_request };

  // Writes to a stream the caller keeps alive.
  explicit CandumpWriter(std::ostream& out, Flush flush = Flush::every_line);
  // Creates (or appends to) a file. Errors: io, naming the file.
  static Result<CandumpWriter> create(const std::filesystem::path& path, Flush flush = Flush::every_line,
                                      bool append = false);
  // The same with a size and/or age limit: the file rotates (NAME.1, NAME.2, ...; see
  // core/rotating_file.hpp) instead of growing without end. Errors: io, or invalid limits.
  static Result<CandumpWriter> create(const std::filesystem::path& path, core::RotationLimits limits,
                                      Flush flush = Flush::every_line, bool append = false);

  CandumpWriter(CandumpWriter&&) noexcept = default;
  CandumpWriter& operator=(CandumpWriter&&) noexcept = default;

  Result<void> write(const Frame& frame, std::string_view iface);
  Result<void> write(const LogEntry& entry);
  Result<void> flush();

  [[nodiscard]] std::uint64_t lines_written() const noexcept { return lines_; }
  // Rotations so far (0 for a stream or a file without limits).
  [[nodiscard]] std::uint64_t rotations() const noexcept { return file_ ? file_->rotations() : 0; }

 private:
  CandumpWriter(core::RotatingFile file, Flush flush);
  Result<void> put(std::string line);

  std::optional<core::RotatingFile> file_;
  std::ostream* out_ = nullptr;
  std::string name_;
  Flush flush_;
  std::uint64_t lines_ = 0;
};

struct CandumpReadOptions {
  // Count bad lines and go on instead of returning their error.
  bool skip_bad = false;
};

// Reads candump log lines one entry at a time; blank lines are ignored.
class CandumpReader {
 public:
  // Errors: io, naming the file.
  static Result<CandumpReader> open(const std::filesystem::path& path, CandumpReadOptions options = {});
  // Reads a stream the caller keeps alive; `name` is used in error messages.
  CandumpReader(std::istream& in, std::string name, CandumpReadOptions options = {});

  CandumpReader(CandumpReader&&) noexcept = default;
  CandumpReader& operator=(CandumpReader&&) noexcept = default;

  // The next entry, or nullopt at the end of the file. A bad line gives its error (code from
  // parse_candump_line, detail "FILE:LINE: ...") unless skip_bad is set; the next call goes on
  // with the following line. A read failure gives io.
  Result<std::optional<LogEntry>> next();

  [[nodiscard]] std::uint64_t lines_read() const noexcept { return lines_; }      // blank ones included
  [[nodiscard]] std::uint64_t entries_read() const noexcept { return entries_; }  // returned by next()
  [[nodiscard]] std::uint64_t lines_skipped() const noexcept { return skipped_; }  // bad, passed over
  // The first bad line passed over with skip_bad, for a summary.
  [[nodiscard]] const std::optional<Error>& first_skipped() const noexcept { return first_skipped_; }

 private:
  CandumpReader(std::unique_ptr<std::ifstream> file, std::string name, CandumpReadOptions options);

  std::unique_ptr<std::ifstream> file_;
  std::istream* in_;
  std::string name_;
  CandumpReadOptions options_;
  std::uint64_t lines_ = 0;
  std::uint64_t entries_ = 0;
  std::uint64_t skipped_ = 0;
  std::optional<Error> first_skipped_;
};

}  // namespace axon::can
