#include "axon/c4g/protocol/packet.hpp"

#include "axon/c4g/protocol/wire.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace axon::c4g::protocol {
namespace {

constexpr int kFieldsPerAxis = 9;

Fault fault(ProtocolErrc c, int axis = -1, int field = -1, std::int64_t got = 0, std::int64_t expected = 0) noexcept {
  Fault f;
  f.code = c;
  f.axis = axis;
  f.field = field;
  f.got = got;
  f.expected = expected;
  return f;
}

std::array<float, 8> floats_of(const Axis& a) noexcept { return {a.d1, a.d2, a.d3, a.d4, a.d5, a.ext1, a.ext2, a.ext3}; }

Fault check_header(std::int32_t num) noexcept {
  if (num < 0 || num > kMaxProtocolNumber) return fault(ProtocolErrc::value_out_of_range, -1, -1, num, kMaxProtocolNumber);
  return {};
}

}  // namespace

bool operator==(const Packet& a, const Packet& b) noexcept {
  if (a.num != b.num || a.infpar != b.infpar || a.cmd != b.cmd || a.count != b.count) return false;
  const auto x = a.open_axes();
  const auto y = b.open_axes();
  return std::equal(x.begin(), x.end(), y.begin(), y.end());
}

Fault encode_packet(const Packet& pkt, std::span<std::byte> out) noexcept {
  if (pkt.count < 1 || pkt.count > kMaxAxes)
    return fault(ProtocolErrc::too_many_axes, -1, -1, static_cast<std::int64_t>(pkt.count), kMaxAxes);
  const std::size_t size = packet_size(pkt.count);
  if (out.size() < size)
    return fault(ProtocolErrc::wrong_size, -1, -1, static_cast<std::int64_t>(out.size()), static_cast<std::int64_t>(size));
  if (auto f = check_header(pkt.num); !f.ok()) return f;
  // Check everything before writing anything: a refused packet leaves the buffer as it was.
  for (std::size_t i = 0; i < pkt.count; ++i) {
    const auto v = floats_of(pkt.axes[i]);
    for (std::size_t k = 0; k < v.size(); ++k)
      if (!wire::is_finite(v[k])) return fault(ProtocolErrc::not_finite, static_cast<int>(i), static_cast<int>(k + 1));
  }
  std::byte* p = out.data();
  wire::put_i32(p, pkt.num);
  wire::put_i32(p + 4, pkt.infpar);
  wire::put_i32(p + 8, pkt.cmd);
  p += kHeaderSize;
  for (std::size_t i = 0; i < pkt.count; ++i, p += kAxisSize) {
    const Axis& a = pkt.axes[i];
    wire::put_i32(p, a.mode);
    const auto v = floats_of(a);
    for (std::size_t k = 0; k < v.size(); ++k) wire::put_f32(p + 4 + 4 * k, v[k]);
  }
  return {};
}

Fault decode_packet(std::span<const std::byte> in, Packet& out) noexcept {
  const std::size_t n = in.size();
  if (n < packet_size(1) || (n - kHeaderSize) % kAxisSize != 0)
    return fault(ProtocolErrc::wrong_size, -1, -1, static_cast<std::int64_t>(n), static_cast<std::int64_t>(packet_size(1)));
  const std::size_t axes = (n - kHeaderSize) / kAxisSize;
  if (axes > kMaxAxes)
    return fault(ProtocolErrc::too_many_axes, -1, -1, static_cast<std::int64_t>(axes), kMaxAxes);
  const std::byte* p = in.data();
  const std::int32_t num = wire::get_i32(p);
  if (auto f = check_header(num); !f.ok()) return f;
  // Validate the floats before touching out, so a rejected datagram leaves the last good packet.
  for (std::size_t i = 0; i < axes; ++i) {
    const std::byte* a = p + kHeaderSize + i * kAxisSize;
    for (int k = 1; k < kFieldsPerAxis; ++k)
      if (wire::is_non_finite_bits(wire::get_u32(a + 4 * k))) return fault(ProtocolErrc::not_finite, static_cast<int>(i), k);
  }
  out.num = num;
  out.infpar = wire::get_i32(p + 4);
  out.cmd = wire::get_i32(p + 8);
  out.count = axes;
  for (std::size_t i = 0; i < axes; ++i) {
    const std::byte* a = p + kHeaderSize + i * kAxisSize;
    Axis& x = out.axes[i];
    x.mode = wire::get_i32(a);
    x.d1 = wire::get_f32(a + 4);
    x.d2 = wire::get_f32(a + 8);
    x.d3 = wire::get_f32(a + 12);
    x.d4 = wire::get_f32(a + 16);
    x.d5 = wire::get_f32(a + 20);
    x.ext1 = wire::get_f32(a + 24);
    x.ext2 = wire::get_f32(a + 28);
    x.ext3 = wire::get_f32(a + 32);
  }
  return {};
}

Fault decode_packet(std::span<const std::byte> in, Packet& out, std::size_t expected_axes) noexcept {
  if (expected_axes < 1 || expected_axes > kMaxAxes)
    return fault(ProtocolErrc::too_many_axes, -1, -1, static_cast<std::int64_t>(expected_axes), kMaxAxes);
  const std::size_t want = packet_size(expected_axes);
  if (in.size() != want) {
    // A well-formed packet of another width is a configuration disagreement, not line noise.
    const bool other_width = in.size() >= packet_size(1) && in.size() <= kMaxPacketSize &&
                             (in.size() - kHeaderSize) % kAxisSize == 0;
    if (other_width)
      return fault(ProtocolErrc::axis_count_mismatch, -1, -1,
                   static_cast<std::int64_t>((in.size() - kHeaderSize) / kAxisSize), static_cast<std::int64_t>(expected_axes));
    return fault(ProtocolErrc::wrong_size, -1, -1, static_cast<std::int64_t>(in.size()), static_cast<std::int64_t>(want));
  }
  return decode_packet(in, out);
}

Error to_error(const Fault& f, std::string_view what) {
  std::string where;
  switch (f.code) {
    case ProtocolErrc::wrong_size:
      where = fmt::format("{}: {} bytes, expected {}", what, f.got, f.expected);
      break;
    case ProtocolErrc::axis_count_mismatch:
      where = fmt::format("{}: {} axes, the initialization packet announced {}", what, f.got, f.expected);
      break;
    case ProtocolErrc::too_many_axes:
      where = fmt::format("{}: axis count {} (allowed 1..{})", what, f.got, f.expected);
      break;
    case ProtocolErrc::value_out_of_range:
      where = f.field >= 0 ? fmt::format("{}: field {} value {} (maximum {})", what, f.field, f.got, f.expected)
                           : fmt::format("{}: value {} (maximum {})", what, f.got, f.expected);
      break;
    default:
      if (f.axis >= 0 && f.field >= 0)
        where = fmt::format("{}: open axis {} field {}", what, f.axis, field_name(f.field));
      else if (f.field >= 0)
        where = fmt::format("{}: field {}", what, f.field);
      else
        where = std::string(what);
      break;
  }
  return Error(make_error_code(f.code), std::move(where));
}

Result<void> to_result(const Fault& f, std::string_view what) {
  if (f.ok()) return ok();
  return to_error(f, what);
}

std::string_view field_name(int field) noexcept {
  static constexpr std::array<std::string_view, kFieldsPerAxis> names{"SM", "D1", "D2", "D3", "D4",
                                                                      "D5", "EXT1", "EXT2", "EXT3"};
  if (field < 0 || field >= kFieldsPerAxis) return "?";
  return names[static_cast<std::size_t>(field)];
}

std::string_view field_meaning(Direction dir, int field) noexcept {
  static constexpr std::array<std::string_view, kFieldsPerAxis> to_pc{
      "axis mode",           "target position [motor turns]", "target velocity [delta motor turns]",
      "actual position [motor turns]", "actual velocity [delta motor turns]", "reference current [A]",
      "extra 1 (dynamic-model current [A])", "extra 2 (diagonal inertia [kg m^2])", "extra 3"};
  static constexpr std::array<std::string_view, kFieldsPerAxis> to_controller{
      "axis mode",       "target position [motor turns]", "target velocity [delta motor turns]",
      "measure [sensor unit]", "velocity contribution [delta motor turns]", "current contribution [A]",
      "extra 1",         "extra 2",                       "extra 3"};
  if (field < 0 || field >= kFieldsPerAxis) return "?";
  return (dir == Direction::to_pc ? to_pc : to_controller)[static_cast<std::size_t>(field)];
}

std::string to_string(const Packet& pkt) {
  std::string s = fmt::format("NUM={} INFPAR=0x{:08X} CMD=0x{:08X} axes={}", pkt.num,
                              static_cast<std::uint32_t>(pkt.infpar), static_cast<std::uint32_t>(pkt.cmd), pkt.count);
  std::size_t i = 0;
  for (const Axis& a : pkt.open_axes()) {
    s += fmt::format("\n  [{}] SM={} D1={} D2={} D3={} D4={} D5={} EXT1={} EXT2={} EXT3={}", i++, a.mode, a.d1, a.d2,
                     a.d3, a.d4, a.d5, a.ext1, a.ext2, a.ext3);
  }
  return s;
}

DatagramKind classify(std::size_t size) noexcept {
  if (size == 1200) return DatagramKind::init;  // init_packet.hpp kInitPacketSize
  if (size >= packet_size(1) && size <= kMaxPacketSize && (size - kHeaderSize) % kAxisSize == 0)
    return DatagramKind::cyclic;
  return DatagramKind::unknown;
}

}  // namespace axon::c4g::protocol
