#include "axon/c4g/protocol/init_packet.hpp"

#include "axon/c4g/protocol/error.hpp"
#include "axon/c4g/protocol/wire.hpp"

#include <fmt/format.h>

#include <type_traits>

namespace axon::c4g::protocol {
namespace {

std::string name_of(std::string_view name, int index) {
  return index < 0 ? std::string(name) : fmt::format("{}[{}]", name, index);
}

}  // namespace

Result<void> validate(const InitPacket& p) {
  if (p.fields_per_packet != 3 || p.fields_per_axis != 9)
    return Error(ProtocolErrc::bad_field_count, fmt::format("c4g initialization packet: {} packet fields, {} axis fields",
                                                            p.fields_per_packet, p.fields_per_axis));
  if (p.open_axes < 1 || p.open_axes > static_cast<std::int32_t>(kMaxAxes))
    return Error(ProtocolErrc::too_many_axes, fmt::format("c4g initialization packet: nAxOpen = {}", p.open_axes));
  if (p.period_ms < 1 || p.period_ms > kMaxPeriodMs)
    return Error(ProtocolErrc::value_out_of_range,
                 fmt::format("c4g initialization packet: period = {} ms (1..{})", p.period_ms, kMaxPeriodMs));
  std::size_t i = 0;
  std::size_t bad = kInitFieldCount;
  for_each_field(p, [&](std::string_view, int, const auto& v) {
    if constexpr (std::is_same_v<std::decay_t<decltype(v)>, float>)
      if (bad == kInitFieldCount && !wire::is_finite(v)) bad = i;
    ++i;
  });
  if (bad != kInitFieldCount)
    return Error(ProtocolErrc::not_finite,
                 fmt::format("c4g initialization packet: field {} ({}) at byte {}", bad, init_field_name(bad), 4 * bad));
  return ok();
}

Result<void> encode_init(const InitPacket& p, std::span<std::byte> out) {
  if (out.size() < kInitPacketSize)
    return Error(ProtocolErrc::wrong_size, fmt::format("c4g initialization packet: buffer of {} bytes", out.size()));
  AXON_TRY(validate(p));
  std::byte* w = out.data();
  for_each_field(p, [&](std::string_view, int, const auto& v) {
    if constexpr (std::is_same_v<std::decay_t<decltype(v)>, float>)
      wire::put_f32(w, v);
    else
      wire::put_i32(w, v);
    w += 4;
  });
  return ok();
}

Result<InitPacket> decode_init(std::span<const std::byte> in) {
  if (in.size() != kInitPacketSize)
    return Error(ProtocolErrc::wrong_size, fmt::format("c4g initialization packet: {} bytes, expected {}", in.size(),
                                                       kInitPacketSize));
  InitPacket p;
  const std::byte* r = in.data();
  for_each_field(p, [&](std::string_view, int, auto& v) {
    if constexpr (std::is_same_v<std::decay_t<decltype(v)>, float>)
      v = wire::get_f32(r);
    else
      v = wire::get_i32(r);
    r += 4;
  });
  AXON_TRY(validate(p));
  return p;
}

std::string init_field_name(std::size_t index) {
  std::string out = "?";
  std::size_t i = 0;
  const InitPacket p;
  for_each_field(p, [&](std::string_view name, int element, const auto&) {
    if (i++ == index) out = name_of(name, element);
  });
  return out;
}

std::string to_string(const InitPacket& p) {
  std::string s;
  auto line = [&](std::string_view label, const auto& values, bool open_list) {
    s += fmt::format("{}:", label);
    for (const auto& v : values) {
      if constexpr (std::is_same_v<std::decay_t<decltype(v)>, float>)
        s += fmt::format(" {:.6f}", v);
      else if (open_list && (v <= 0 || v > static_cast<std::int32_t>(kAxesPerArm)))
        s += " X";
      else
        s += fmt::format(" {}", v);
    }
    s += '\n';
  };
  auto per_arm = [&](std::string_view label, const auto& a, bool open_list = false) {
    for (std::size_t arm = 0; arm < kMaxArms; ++arm) line(fmt::format("{} ARM{}", label, arm + 1), a[arm], open_list);
  };
  s += fmt::format("protocol number: {}\n", p.protocol_number);
  s += fmt::format("fields per packet: {}\n", p.fields_per_packet);
  s += fmt::format("fields per axis: {}\n", p.fields_per_axis);
  s += fmt::format("open axes: {}\n", p.open_axes);
  per_arm("start-up modes", p.modes);
  per_arm("open axes (logical, 1-based)", p.open_axis_list, true);
  per_arm("calibration constants [turns]", p.calibration);
  per_arm("current limits [A]", p.current_limit);
  per_arm("transmission ratios", p.transmission_ratio);
  per_arm("influence coefficients", p.influence);
  per_arm("following error thresholds", p.following_error);
  s += fmt::format("packet field types: NUM {} INFPAR {} CMD {}\n", p.packet_field_types[0], p.packet_field_types[1],
                   p.packet_field_types[2]);
  line("axis field types (SM D1..D5 EXT1..EXT3)", p.axis_field_types, false);
  s += fmt::format("period: {} ms\n", p.period_ms);
  s += fmt::format("software version: {}.{}.{}\n", p.version_major, p.version_minor, p.version_build);
  return s;
}

}  // namespace axon::c4g::protocol
