#include "axon/can/frame.hpp"
#include "axon/core/text.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>

namespace axon::can {

Result<void> check_id(std::uint32_t id, IdFormat fmt) {
  const std::uint32_t max = fmt == IdFormat::extended ? Frame::kMaxExtendedId : Frame::kMaxStandardId;
  if (id > max)
    return Error(CanErrc::invalid_id, fmt::format("id 0x{:X} does not fit a {} frame", id,
                                                  fmt == IdFormat::extended ? "29-bit extended" : "11-bit standard"));
  return ok();
}

Result<Frame> Frame::data(std::uint32_t id, IdFormat fmt, std::span<const std::uint8_t> bytes) {
  AXON_TRY(check_id(id, fmt));
  if (bytes.size() > kMaxData)
    return Error(CanErrc::invalid_length, fmt::format("{} data bytes for id 0x{:X}", bytes.size(), id));
  Frame f;
  f.id_ = id;
  f.fmt_ = fmt;
  f.dlc_ = static_cast<std::uint8_t>(bytes.size());
  std::copy(bytes.begin(), bytes.end(), f.bytes_.begin());
  return f;
}

Result<Frame> Frame::remote(std::uint32_t id, IdFormat fmt, std::uint8_t dlc) {
  AXON_TRY(check_id(id, fmt));
  if (dlc > kMaxData) return Error(CanErrc::invalid_length, fmt::format("remote frame DLC {} for id 0x{:X}", dlc, id));
  Frame f;
  f.id_ = id;
  f.fmt_ = fmt;
  f.remote_ = true;
  f.dlc_ = dlc;
  return f;
}

using core::hex_value;

Result<Frame> Frame::parse(std::string_view text) {
  auto bad = [&](std::string_view why) {
    return Error(CanErrc::parse_error, fmt::format("'{}': {} (expected ID#DATA like 123#DEADBEEF)", text, why));
  };
  const auto hash = text.find('#');
  if (hash == std::string_view::npos) return bad("no '#'");
  const std::string_view id_text = text.substr(0, hash);
  std::string_view rest = text.substr(hash + 1);
  if (id_text.size() != 3 && id_text.size() != 8) return bad("id must have 3 (standard) or 8 (extended) hex digits");
  std::uint32_t id = 0;
  auto [p, ec] = std::from_chars(id_text.data(), id_text.data() + id_text.size(), id, 16);
  if (ec != std::errc() || p != id_text.data() + id_text.size()) return bad("id is not hexadecimal");
  const IdFormat fmt = id_text.size() == 8 ? IdFormat::extended : IdFormat::standard;
  if (!rest.empty() && rest[0] == '#') return bad("CAN FD frames are not supported");
  if (!rest.empty() && (rest[0] == 'R' || rest[0] == 'r')) {
    std::uint8_t dlc = 0;
    if (rest.size() == 2) {
      const int v = hex_value(rest[1]);
      if (v < 0 || v > 8) return bad("remote length must be 0..8");
      dlc = static_cast<std::uint8_t>(v);
    } else if (rest.size() > 2) {
      return bad("trailing characters after remote length");
    }
    return remote(id, fmt, dlc);
  }
  std::array<std::uint8_t, kMaxData + 1> buf{};
  std::size_t n = 0;
  std::size_t i = 0;
  while (i < rest.size()) {
    if (rest[i] == '.') {
      ++i;
      continue;
    }
    if (i + 1 >= rest.size()) return bad("odd number of hex digits in data");
    const int hi = hex_value(rest[i]), lo = hex_value(rest[i + 1]);
    if (hi < 0 || lo < 0) return bad("data is not hexadecimal");
    if (n == kMaxData) return bad("more than 8 data bytes");
    buf[n++] = static_cast<std::uint8_t>(hi << 4 | lo);
    i += 2;
  }
  return data(id, fmt, std::span<const std::uint8_t>(buf.data(), n));
}

std::string Frame::to_string() const {
  std::string s = is_extended() ? fmt::format("{:08X}#", id_) : fmt::format("{:03X}#", id_);
  if (remote_) {
    s += 'R';
    if (dlc_ > 0) s += static_cast<char>('0' + dlc_);
    return s;
  }
  for (std::size_t i = 0; i < dlc_; ++i) s += fmt::format("{:02X}", bytes_[i]);
  return s;
}

}  // namespace axon::can
