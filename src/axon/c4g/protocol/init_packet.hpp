// The initialization packet: sent once by the controller before the cyclic packets, it says how many
// axes are open, which logical axes they are, and the robot data the PC needs (calibration constants,
// current limits, transmission ratios, kinematic influence coefficients, following-error thresholds).
//
// Wire layout: 300 little-endian four-byte fields (int32 or float32) in the declaration order of the
// controller's struct, 1200 bytes, no padding. The manual's prose lists the fields in another order;
// the struct order is what goes on the wire (field notes). for_each_field() walks that order and is
// the single place that defines it: the codec, the names and the printer all use it.
//
// Per-arm arrays are indexed [arm - 1][logical axis - 1] (arms 1..4, logical axes 1..10).
#pragma once

#include "axon/c4g/protocol/packet.hpp"
#include "axon/core/error.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

namespace axon::c4g::protocol {

inline constexpr std::size_t kInitFieldCount = 300;
inline constexpr std::size_t kInitPacketSize = 4 * kInitFieldCount;  // 1200
inline constexpr std::int32_t kModeUnspecified = 0xFF;  // start-up mode "open, mode not given"
// The controller's period is 1 ms in the manual (2 ms on some); everything derived from it (time,
// per-cycle step limits of the applications) would scale with a wild value, so 1..10 ms is accepted.
inline constexpr std::int32_t kMaxPeriodMs = 10;

using ArmInts = std::array<std::array<std::int32_t, kAxesPerArm>, kMaxArms>;
using ArmFloats = std::array<std::array<float, kAxesPerArm>, kMaxArms>;

struct InitPacket {
  std::int32_t protocol_number = 0;    // nblip
  std::int32_t fields_per_packet = 3;  // nFieldPck, always 3
  std::int32_t fields_per_axis = 9;    // nFieldAx, always 9
  std::int32_t open_axes = 0;          // nAxOpen, 1..20
  ArmInts modes{};                     // armNOpenMask: start-up mode per logical axis
  std::array<std::int32_t, 3> packet_field_types{1, 2, 3};                // num, infPar, cmd
  std::array<std::int32_t, 9> axis_field_types{1, 2, 2, 2, 2, 2, 3, 3, 3};  // sMax, d1..d5, ext1..ext3
  std::int32_t period_ms = 0;          // period: controller sampling period [ms]
  ArmInts open_axis_list{};            // armNOpenAx: logical axis numbers (1-based) in open order
  ArmFloats calibration{};             // armNCalData: calibration constants [motor turns]
  ArmFloats current_limit{};           // armNAzLim: maximum reference current [A]
  std::int32_t version_major = 0;      // majorVersion
  std::int32_t version_minor = 0;      // minorVersion
  std::int32_t version_build = 0;      // buildNum
  ArmFloats influence{};               // armNAxInfo: kinematic influence coefficients
  ArmFloats transmission_ratio{};      // armNTxRate: signed transmission ratios
  ArmFloats following_error{};         // armNFollowError: following-error thresholds

  friend bool operator==(const InitPacket&, const InitPacket&) = default;
};

// Calls f(name, index, value&) for every one of the 300 fields in wire order; name is the field's name
// in the controller's struct, index is the array element (-1 for a scalar), value is std::int32_t& or
// float& (const when p is const).
template <class P, class F>
void for_each_field(P& p, F&& f) {
  auto scalar = [&](std::string_view name, auto& v) { f(name, -1, v); };
  auto array = [&](std::string_view name, auto& a) {
    for (std::size_t i = 0; i < a.size(); ++i) f(name, static_cast<int>(i), a[i]);
  };
  auto per_arm = [&](std::string_view a1, std::string_view a2, std::string_view a3, std::string_view a4, auto& a) {
    array(a1, a[0]);
    array(a2, a[1]);
    array(a3, a[2]);
    array(a4, a[3]);
  };
  scalar("nblip", p.protocol_number);
  scalar("nFieldPck", p.fields_per_packet);
  scalar("nFieldAx", p.fields_per_axis);
  scalar("nAxOpen", p.open_axes);
  per_arm("arm1OpenMask", "arm2OpenMask", "arm3OpenMask", "arm4OpenMask", p.modes);
  scalar("num", p.packet_field_types[0]);
  scalar("infPar", p.packet_field_types[1]);
  scalar("cmd", p.packet_field_types[2]);
  scalar("sMax", p.axis_field_types[0]);
  scalar("d1Ax", p.axis_field_types[1]);
  scalar("d2Ax", p.axis_field_types[2]);
  scalar("d3Ax", p.axis_field_types[3]);
  scalar("d4Ax", p.axis_field_types[4]);
  scalar("d5Ax", p.axis_field_types[5]);
  scalar("ext1Ax", p.axis_field_types[6]);
  scalar("ext2Ax", p.axis_field_types[7]);
  scalar("ext3Ax", p.axis_field_types[8]);
  scalar("period", p.period_ms);
  per_arm("arm1OpenAx", "arm2OpenAx", "arm3OpenAx", "arm4OpenAx", p.open_axis_list);
  per_arm("arm1CalData", "arm2CalData", "arm3CalData", "arm4CalData", p.calibration);
  per_arm("arm1AzLim", "arm2AzLim", "arm3AzLim", "arm4AzLim", p.current_limit);
  scalar("majorVersion", p.version_major);
  scalar("minorVersion", p.version_minor);
  scalar("buildNum", p.version_build);
  per_arm("arm1AxInfo", "arm2AxInfo", "arm3AxInfo", "arm4AxInfo", p.influence);
  per_arm("arm1TxRate", "arm2TxRate", "arm3TxRate", "arm4TxRate", p.transmission_ratio);
  per_arm("arm1FollowError", "arm2FollowError", "arm3FollowError", "arm4FollowError", p.following_error);
}

// Format checks shared by encode and decode: 3 packet and 9 axis fields, 1..20 open axes, a period
// of 1..kMaxPeriodMs ms, finite floats. (The consistency of the open-axis lists is AxisMap's job.)
Result<void> validate(const InitPacket& p);

Result<void> encode_init(const InitPacket& p, std::span<std::byte> out);  // out.size() >= 1200
Result<InitPacket> decode_init(std::span<const std::byte> in);            // exactly 1200 bytes

// The struct name of field i (0..299), e.g. "nblip", "arm1CalData[3]"; "?" outside. Its byte offset is 4 i.
std::string init_field_name(std::size_t index);
// A report of every field, grouped as in the controller's own printout (one line per arm array).
std::string to_string(const InitPacket& p);

}  // namespace axon::c4g::protocol
