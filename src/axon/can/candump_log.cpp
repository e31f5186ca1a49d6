#include "axon/can/candump_log.hpp"

#include "axon/core/text.hpp"

#include <fmt/format.h>

#include <array>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <istream>
#include <ostream>

namespace axon::can {

namespace {

constexpr std::int64_t kNanosPerSecond = 1'000'000'000;
// Latest second a timestamp may name: keeps nanoseconds since the epoch inside 64 bits.
constexpr std::uint64_t kMaxSeconds = 9'000'000'000ULL;
// Longer lines are refused before parsing (the longest valid one is well under 100 characters
// plus the interface name).
constexpr std::size_t kMaxLine = 4096;

using core::is_space;
using core::trim;
using core::hex_value;

// Splits off the next white-space separated field.
std::string_view next_field(std::string_view& s) noexcept {
  s = trim(s);
  std::size_t end = 0;
  while (end < s.size() && !is_space(s[end])) ++end;
  const std::string_view field = s.substr(0, end);
  s.remove_prefix(end);
  return field;
}

bool all_digits(std::string_view s) noexcept {
  for (char c : s)
    if (c < '0' || c > '9') return false;
  return !s.empty();
}

// Quotes (part of) a line for an error message, without control characters or unbounded length.
std::string quoted(std::string_view s) {
  std::string out;
  const std::size_t n = std::min<std::size_t>(s.size(), 80);
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c < 0x20 || c == 0x7F) {
      out += fmt::format("\\x{:02X}", c);
    } else {
      out += static_cast<char>(c);
    }
  }
  if (s.size() > n) out += "...";
  return "'" + out + "'";
}

Result<core::WallTime> parse_timestamp(std::string_view field, std::string_view line) {
  auto bad = [&](std::string_view why) {
    return Error(CanErrc::parse_error,
                 fmt::format("{}: timestamp {} {} (expected (SECONDS.MICROSECONDS) like (1436509052.249713))",
                             quoted(line), quoted(field), why));
  };
  if (field.size() < 2 || field.front() != '(' || field.back() != ')') return bad("is not in parentheses");
  const std::string_view inner = field.substr(1, field.size() - 2);
  const auto dot = inner.find('.');
  if (dot == std::string_view::npos) return bad("has no decimal point");
  const std::string_view sec_text = inner.substr(0, dot), frac_text = inner.substr(dot + 1);
  if (!all_digits(sec_text) || !all_digits(frac_text)) return bad("is not a plain decimal number");
  if (frac_text.size() > 9) return bad("has more than 9 decimals");
  std::uint64_t sec = 0;
  // Leading zeros are allowed (candump pads to 10 digits); the value is what must fit.
  const auto [p, ec] = std::from_chars(sec_text.data(), sec_text.data() + sec_text.size(), sec);
  if (ec != std::errc() || p != sec_text.data() + sec_text.size() || sec > kMaxSeconds) return bad("is out of range");
  std::int64_t frac = 0;
  for (char c : frac_text) frac = frac * 10 + (c - '0');
  for (std::size_t i = frac_text.size(); i < 9; ++i) frac *= 10;
  return core::WallTime(static_cast<std::int64_t>(sec) * kNanosPerSecond + frac);
}

struct ParsedFrame {
  Frame frame;
  bool error_frame = false;
};

Result<ParsedFrame> parse_frame_field(std::string_view field, std::string_view line) {
  auto bad = [&](std::string_view why) {
    return Error(CanErrc::parse_error,
                 fmt::format("{}: frame {} {} (expected ID#DATA like 123#DEADBEEF or 12345678#R)", quoted(line),
                             quoted(field), why));
  };
  const auto hash = field.find('#');
  if (hash == std::string_view::npos) return bad("has no '#'");
  const std::string_view id_text = field.substr(0, hash);
  std::string_view rest = field.substr(hash + 1);
  if (id_text.size() != 3 && id_text.size() != 8) return bad("needs a 3-digit (11-bit) or 8-digit (29-bit) hex id");
  std::uint32_t raw_id = 0;
  for (char c : id_text) {
    const int v = hex_value(c);
    if (v < 0) return bad("has an id that is not hexadecimal");
    raw_id = raw_id << 4 | static_cast<std::uint32_t>(v);
  }
  if (!rest.empty() && rest.front() == '#')
    return Error(CanErrc::not_supported,
                 fmt::format("{}: CAN FD frame {}: only classic CAN frames are supported", quoted(line), quoted(field)));

  ParsedFrame out;
  IdFormat format = IdFormat::standard;
  if (id_text.size() == 8) {
    format = IdFormat::extended;
    if (raw_id & 0xC000'0000U) return bad("has extended/remote flag bits in the id (only the error flag may be set)");
    if (raw_id & kCandumpErrorFlag) {
      out.error_frame = true;
      raw_id &= ~kCandumpErrorFlag;
    }
  } else if (raw_id > Frame::kMaxStandardId) {
    return bad("has a 3-digit id over 7FF");
  }

  if (!rest.empty() && (rest.front() == 'R' || rest.front() == 'r')) {
    if (out.error_frame) return bad("is an error report marked remote");
    rest.remove_prefix(1);
    std::uint8_t dlc = 0;
    if (!rest.empty() && rest.front() != '_') {
      const int v = hex_value(rest.front());
      if (v < 0 || v > 8) return bad("has a remote DLC that is not 0..8");
      dlc = static_cast<std::uint8_t>(v);
      rest.remove_prefix(1);
    }
    if (!rest.empty() && rest.front() == '_')
      return Error(CanErrc::not_supported, fmt::format("{}: raw DLC suffix in {}: DLC 9..15 cannot be represented",
                                                       quoted(line), quoted(field)));
    if (!rest.empty()) return bad("has characters after the remote DLC");
    auto f = Frame::remote(raw_id, format, dlc);
    if (!f) return bad(f.error().message());
    out.frame = f.value();
    return out;
  }

  std::array<std::uint8_t, Frame::kMaxData> data{};
  std::size_t n = 0;
  while (!rest.empty()) {
    if (rest.front() == '.') {  // cansend's optional byte separator
      rest.remove_prefix(1);
      continue;
    }
    if (rest.front() == '_') {
      if (n == Frame::kMaxData)
        return Error(CanErrc::not_supported, fmt::format("{}: raw DLC suffix in {}: DLC 9..15 cannot be represented",
                                                         quoted(line), quoted(field)));
      return bad("has a raw DLC suffix on a frame with fewer than 8 bytes");
    }
    if (rest.size() < 2) return bad("has an odd number of hex digits in the data");
    const int hi = hex_value(rest[0]), lo = hex_value(rest[1]);
    if (hi < 0 || lo < 0) return bad("has data that is not hexadecimal");
    if (n == Frame::kMaxData) return bad("has more than 8 data bytes");
    data[n++] = static_cast<std::uint8_t>(hi << 4 | lo);
    rest.remove_prefix(2);
  }
  auto f = Frame::data(raw_id, format, std::span<const std::uint8_t>(data.data(), n));
  if (!f) return bad(f.error().message());
  out.frame = f.value();
  return out;
}

std::string printable_iface(std::string_view iface) {
  if (iface.empty()) return "any";
  std::string out(iface);
  for (char& c : out) {
    const auto u = static_cast<unsigned char>(c);
    if (u <= 0x20 || u == 0x7F) c = '_';
  }
  return out;
}

}  // namespace

Result<LogEntry> parse_candump_line(std::string_view line) {
  std::string_view rest = trim(line);
  if (rest.empty()) return Error(CanErrc::parse_error, "blank line");
  if (rest.size() > kMaxLine)
    return Error(CanErrc::parse_error, fmt::format("{}: line of {} characters is too long", quoted(rest), rest.size()));
  const std::string_view ts_field = next_field(rest);
  const std::string_view iface = next_field(rest);
  const std::string_view frame_field = next_field(rest);
  const std::string_view dir_field = next_field(rest);
  if (frame_field.empty())
    return Error(CanErrc::parse_error,
                 fmt::format("{}: expected (TIMESTAMP) IFACE ID#DATA, e.g. (1436509052.249713) vcan0 123#00", quoted(line)));
  if (!trim(rest).empty())
    return Error(CanErrc::parse_error, fmt::format("{}: unexpected text after the frame", quoted(line)));

  LogEntry entry;
  AXON_TRY(ts, parse_timestamp(ts_field, line));
  for (char c : iface)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7F)
      return Error(CanErrc::parse_error, fmt::format("{}: control character in the interface name", quoted(line)));
  entry.iface = std::string(iface);
  AXON_TRY(parsed, parse_frame_field(frame_field, line));
  entry.frame = parsed.frame;
  entry.frame.set_timestamp(ts);
  entry.error_frame = parsed.error_frame;
  if (dir_field == "R" || dir_field == "r") {
    entry.direction = LogDirection::rx;
  } else if (dir_field == "T" || dir_field == "t") {
    entry.direction = LogDirection::tx;
  } else if (!dir_field.empty()) {
    return Error(CanErrc::parse_error,
                 fmt::format("{}: unexpected {} after the frame (only R or T may follow)", quoted(line), quoted(dir_field)));
  }
  return entry;
}

std::string format_candump_line(const Frame& frame, std::string_view iface) {
  LogEntry e;
  e.frame = frame;
  e.iface = std::string(iface);
  return format_candump_line(e);
}

std::string format_candump_line(const LogEntry& entry) {
  const std::int64_t ns = std::max<std::int64_t>(entry.frame.timestamp().count(), 0);
  const std::int64_t sec = ns / kNanosPerSecond, usec = ns % kNanosPerSecond / 1000;
  std::string frame_text;
  if (entry.error_frame) {
    frame_text = fmt::format("{:08X}#", (entry.frame.id() & Frame::kMaxExtendedId) | kCandumpErrorFlag);
    for (std::uint8_t b : entry.frame.payload()) frame_text += fmt::format("{:02X}", b);
  } else {
    frame_text = entry.frame.to_string();
  }
  return fmt::format("({:010}.{:06}) {} {}", sec, usec, printable_iface(entry.iface), frame_text);
}

// ---- writer

CandumpWriter::CandumpWriter(std::ostream& out, Flush flush) : out_(&out), name_("<stream>"), flush_(flush) {}

CandumpWriter::CandumpWriter(core::RotatingFile file, Flush flush)
    : file_(std::move(file)), name_(file_->path().string()), flush_(flush) {}

Result<CandumpWriter> CandumpWriter::create(const std::filesystem::path& path, Flush flush, bool append) {
  return create(path, core::RotationLimits{}, flush, append);
}

Result<CandumpWriter> CandumpWriter::create(const std::filesystem::path& path, core::RotationLimits limits, Flush flush,
                                            bool append) {
  auto file = core::RotatingFile::open(path, limits, core::steady_now(), {}, append);
  if (!file) {
    if (file.error() == CoreErrc::io)
      return Error(CanErrc::io, fmt::format("candump log: {}", file.error().detail));
    return file.error();
  }
  return CandumpWriter(std::move(file).value(), flush);
}

Result<void> CandumpWriter::put(std::string line) {
  line.push_back('\n');
  if (file_) {
    auto written = file_->write(line, core::steady_now());
    if (written && flush_ == Flush::every_line) written = file_->flush();
    if (!written) return Error(CanErrc::io, fmt::format("writing candump log {} failed: {}", name_, written.error().message()));
  } else {
    *out_ << line;
    if (flush_ == Flush::every_line) out_->flush();
    if (!*out_) return Error(CanErrc::io, fmt::format("writing candump log {} failed (disk full?)", name_));
  }
  ++lines_;
  return ok();
}

Result<void> CandumpWriter::write(const Frame& frame, std::string_view iface) {
  return put(format_candump_line(frame, iface));
}

Result<void> CandumpWriter::write(const LogEntry& entry) { return put(format_candump_line(entry)); }

Result<void> CandumpWriter::flush() {
  if (file_) {
    auto r = file_->flush();
    if (!r) return Error(CanErrc::io, fmt::format("flushing candump log {} failed: {}", name_, r.error().message()));
    return ok();
  }
  out_->flush();
  if (!*out_) return Error(CanErrc::io, fmt::format("flushing candump log {} failed (disk full?)", name_));
  return ok();
}

// ---- reader

CandumpReader::CandumpReader(std::istream& in, std::string name, CandumpReadOptions options)
    : in_(&in), name_(std::move(name)), options_(options) {}

CandumpReader::CandumpReader(std::unique_ptr<std::ifstream> file, std::string name, CandumpReadOptions options)
    : file_(std::move(file)), in_(file_.get()), name_(std::move(name)), options_(options) {}

Result<CandumpReader> CandumpReader::open(const std::filesystem::path& path, CandumpReadOptions options) {
  auto file = std::make_unique<std::ifstream>(path);
  if (!*file) return Error(CanErrc::io, fmt::format("cannot read candump log {}: {}", path.string(), std::strerror(errno)));
  return CandumpReader(std::move(file), path.string(), options);
}

Result<std::optional<LogEntry>> CandumpReader::next() {
  std::string line;
  while (std::getline(*in_, line)) {
    ++lines_;
    if (trim(line).empty()) continue;
    auto entry = parse_candump_line(line);
    if (entry) {
      ++entries_;
      return std::optional<LogEntry>(std::move(entry).value());
    }
    Error err(entry.error().code, fmt::format("{}:{}: {}", name_, lines_, entry.error().detail));
    if (!options_.skip_bad) return err;
    ++skipped_;
    if (!first_skipped_) first_skipped_ = std::move(err);
  }
  if (in_->bad()) return Error(CanErrc::io, fmt::format("reading candump log {} failed after line {}", name_, lines_));
  return std::optional<LogEntry>();
}

}  // namespace axon::can
