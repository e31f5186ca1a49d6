// A recording file with a size and/or age limit: when the next record would pass a limit, the file
// is closed and renamed, and recording goes on in a fresh file of the same name.
//
// Naming follows logrotate and Python's RotatingFileHandler: NAME is always the file being written;
// the previous one is NAME.1, the one before NAME.2, and so on up to NAME.<keep>; a rotation shifts
// each NAME.k to NAME.k+1 and deletes what would pass `keep`. So the newest data is in NAME, then
// NAME.1, and tools that follow NAME keep working.
//
// A record is never split across files: a record larger than max_bytes goes alone into a fresh
// file. `header` (e.g. a pcap file header or a CSV title line) starts every file, and counts
// towards its size. The age limit is measured from when the file was opened, on the clock the
// caller passes to write() (so tests use plain numbers).
//
// Not for real-time loops: write() may rename and open files.
#pragma once

#include "axon/core/clock.hpp"
#include "axon/core/error.hpp"

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

namespace axon::core {

struct RotationLimits {
  std::uint64_t max_bytes = 0;            // 0: no size limit
  Duration max_age = Duration::zero();    // zero: no age limit
  unsigned keep = 10;                     // rotated files kept (NAME.1 .. NAME.keep); at least 1

  [[nodiscard]] bool any() const noexcept { return max_bytes > 0 || max_age > Duration::zero(); }
  // CoreErrc::invalid_argument for keep 0 or a negative age.
  [[nodiscard]] Result<void> validate() const;
};

class RotatingFile {
 public:
  // Creates (truncates) `path`, or appends to it with `append` (its present size counts towards
  // the limit), and writes `header` into a new or empty file. `now` starts the age of the file.
  // Errors: CoreErrc::io naming the file, or the limits' validate() error.
  static Result<RotatingFile> open(const std::filesystem::path& path, RotationLimits limits, TimePoint now,
                                   std::string header = {}, bool append = false);
  RotatingFile(RotatingFile&&) noexcept;
  RotatingFile& operator=(RotatingFile&&) noexcept;
  ~RotatingFile();

  // Appends one record, rotating first when it would pass a limit. CoreErrc::io on failure.
  Result<void> write(std::string_view record, TimePoint now);
  Result<void> flush();

  [[nodiscard]] const std::filesystem::path& path() const noexcept { return path_; }
  [[nodiscard]] std::uint64_t size() const noexcept { return size_; }            // of the current file
  [[nodiscard]] std::uint64_t rotations() const noexcept { return rotations_; }
  // The header of every file from now on (a CSV title line known only once the first row is); it
  // is written at once when the current file holds nothing yet.
  Result<void> set_header(std::string header);

  // NAME.k, the k-th older file (k >= 1).
  [[nodiscard]] static std::filesystem::path rotated_name(const std::filesystem::path& path, unsigned k);
  // Moves NAME to NAME.1, NAME.1 to NAME.2, ... and deletes NAME.<keep>: the renaming of a rotation,
  // for writers that keep their own file handle (a libpcap dumper). CoreErrc::io naming the file.
  static Result<void> shift(const std::filesystem::path& path, unsigned keep);

 private:
  RotatingFile(std::filesystem::path path, RotationLimits limits, std::string header);
  Result<void> open_file(bool append, TimePoint now);
  Result<void> rotate(TimePoint now);
  Result<void> put(std::string_view bytes);

  struct Closer {
    void operator()(std::FILE* f) const noexcept;
  };
  std::filesystem::path path_;
  RotationLimits limits_;
  std::string header_;
  std::unique_ptr<std::FILE, Closer> file_;
  std::uint64_t size_ = 0;
  TimePoint opened_{};
  std::uint64_t rotations_ = 0;
};

}  // namespace axon::core
