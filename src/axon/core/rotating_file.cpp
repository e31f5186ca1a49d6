#include "axon/core/rotating_file.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <cstring>
#include <system_error>
#include <utility>

namespace axon::core {

namespace fs = std::filesystem;

Result<void> RotationLimits::validate() const {
  if (keep == 0) return Error(CoreErrc::invalid_argument, "rotation: keep at least one old file");
  if (max_age < Duration::zero()) return Error(CoreErrc::invalid_argument, "rotation: the age limit must not be negative");
  return ok();
}

void RotatingFile::Closer::operator()(std::FILE* f) const noexcept {
  if (f != nullptr) std::fclose(f);
}

RotatingFile::RotatingFile(fs::path path, RotationLimits limits, std::string header)
    : path_(std::move(path)), limits_(limits), header_(std::move(header)) {}
RotatingFile::RotatingFile(RotatingFile&&) noexcept = default;
RotatingFile& RotatingFile::operator=(RotatingFile&&) noexcept = default;
RotatingFile::~RotatingFile() = default;

fs::path RotatingFile::rotated_name(const fs::path& path, unsigned k) {
  fs::path p = path;
  p += fmt::format(".{}", k);
  return p;
}

Result<RotatingFile> RotatingFile::open(const fs::path& path, RotationLimits limits, TimePoint now, std::string header,
                                        bool append) {
  AXON_TRY(limits.validate());
  RotatingFile f(path, limits, std::move(header));
  AXON_TRY(f.open_file(append, now));
  return f;
}

Result<void> RotatingFile::open_file(bool append, TimePoint now) {
  file_.reset(std::fopen(path_.c_str(), append ? "ab" : "wb"));
  if (!file_) return Error(CoreErrc::io, fmt::format("cannot write {}: {}", path_.string(), std::strerror(errno)));
  std::error_code ec;
  const auto existing = append ? fs::file_size(path_, ec) : 0;
  size_ = ec ? 0 : existing;
  opened_ = now;
  if (size_ == 0 && !header_.empty()) return put(header_);
  return ok();
}

Result<void> RotatingFile::shift(const fs::path& path, unsigned keep) {
  std::error_code ec;
  fs::remove(rotated_name(path, keep), ec);
  for (unsigned k = keep; k > 1; --k) {
    const auto from = rotated_name(path, k - 1);
    if (fs::exists(from, ec)) fs::rename(from, rotated_name(path, k), ec);
    if (ec) return Error(CoreErrc::io, fmt::format("rotating {}: {}", from.string(), ec.message()));
  }
  fs::rename(path, rotated_name(path, 1), ec);
  if (ec) return Error(CoreErrc::io, fmt::format("rotating {}: {}", path.string(), ec.message()));
  return ok();
}

Result<void> RotatingFile::rotate(TimePoint now) {
  file_.reset();
  AXON_TRY(shift(path_, limits_.keep));
  ++rotations_;
  return open_file(false, now);
}

Result<void> RotatingFile::set_header(std::string header) {
  header_ = std::move(header);
  if (size_ != 0 || !file_) return ok();
  return put(header_);
}

Result<void> RotatingFile::put(std::string_view bytes) {
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_.get()) != bytes.size())
    return Error(CoreErrc::io, fmt::format("writing {} failed: {}", path_.string(), std::strerror(errno)));
  size_ += bytes.size();
  return ok();
}

Result<void> RotatingFile::write(std::string_view record, TimePoint now) {
  if (!file_) return Error(CoreErrc::io, fmt::format("{} is not open", path_.string()));
  const bool has_records = size_ > header_.size();
  const bool too_big = limits_.max_bytes > 0 && size_ + record.size() > limits_.max_bytes;
  const bool too_old = limits_.max_age > Duration::zero() && now - opened_ >= limits_.max_age;
  if (has_records && (too_big || too_old)) {
    AXON_TRY(rotate(now));
  }
  return put(record);
}

Result<void> RotatingFile::flush() {
  if (file_ && std::fflush(file_.get()) != 0)
    return Error(CoreErrc::io, fmt::format("flushing {} failed: {}", path_.string(), std::strerror(errno)));
  return ok();
}

}  // namespace axon::core
