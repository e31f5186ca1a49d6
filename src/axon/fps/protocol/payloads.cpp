#include "axon/fps/protocol/payloads.hpp"

#include "axon/fps/protocol/error.hpp"
#include "axon/fps/protocol/identifier.hpp"

#include <fmt/format.h>

namespace axon::fps::protocol {
namespace {

// The command table and CommandTypes must agree on every size.
template <class T>
constexpr bool same_size(const Layout& l) {
  return T::kMinSize == l.min_size && T::kMaxSize == l.max_size;
}
template <CommandId C>
constexpr bool types_match_table() {
  constexpr const CommandInfo& info = command_info(C);
  return same_size<RequestOf<C>>(info.request) && same_size<ReplyOf<C>>(info.reply) &&
         same_size<typename CommandTypes<C>::bootloader_reply>(info.bootloader_reply);
}
template <std::size_t... I>
constexpr bool all_types_match(std::index_sequence<I...>) {
  return (types_match_table<kCommands[I].id>() && ...);
}
static_assert(all_types_match(std::make_index_sequence<kCommands.size()>{}),
              "CommandTypes and the command table disagree on a payload size");

std::string deg(Angle a) { return fmt::format("{:.4f} deg", a.degrees()); }
std::string sec(Time t) { return fmt::format("{:.4f} s", t.seconds()); }

}  // namespace

Result<Empty> Empty::decode(std::span<const std::uint8_t> bytes) {
  AXON_TRY(expect_size(bytes, 0, "no data"));
  return Empty{};
}

Result<PositionerIdReply> PositionerIdReply::decode(std::span<const std::uint8_t> bytes) {
  AXON_TRY(expect_size(bytes, kMaxSize, "positioner id"));
  const auto v = read_u32(bytes, 0);
  if (v > kMaxPositionerId) {
    return Error(ProtocolErrc::positioner_out_of_range, fmt::format("GET_ID reply carries id {}", v));
  }
  return PositionerIdReply{static_cast<std::uint16_t>(v)};
}
std::string PositionerIdReply::to_string() const { return fmt::format("id={}", id); }

Result<TrajectorySize> TrajectorySize::decode(std::span<const std::uint8_t> bytes) {
  AXON_TRY(expect_size(bytes, kMaxSize, "trajectory size"));
  TrajectorySize s{read_u32(bytes, 0), read_u32(bytes, 4)};
  if (s.alpha_points > kMaxPoints || s.beta_points > kMaxPoints) {
    return Error(ProtocolErrc::value_out_of_range,
                 fmt::format("trajectory of {} alpha and {} beta points (at most {} each)", s.alpha_points,
                             s.beta_points, kMaxPoints));
  }
  return s;
}
std::string TrajectorySize::to_string() const {
  return fmt::format("alpha_points={} beta_points={}", alpha_points, beta_points);
}

Result<TrajectoryPoint> TrajectoryPoint::decode(std::span<const std::uint8_t> bytes) {
  AXON_TRY(expect_size(bytes, kMaxSize, "trajectory point"));
  return TrajectoryPoint{Angle::from_steps(read_i32(bytes, 0)), Time::from_ticks(read_u32(bytes, 4))};
}
std::string TrajectoryPoint::to_string() const {
  return fmt::format("position={} time={}", deg(position), sec(time));
}

Result<ArmPositions> ArmPositions::decode(std::span<const std::uint8_t> bytes) {
  AXON_TRY(expect_size(bytes, kMaxSize, "arm positions"));
  return ArmPositions{Angle::from_steps(read_i32(bytes, 0)), Angle::from_steps(read_i32(bytes, 4))};
}
std::string ArmPositions::to_string() const { return fmt::format("alpha={} beta={}", deg(alpha), deg(beta)); }

Result<ArmTimes> ArmTimes::decode(std::span<const std::uint8_t> bytes) {
  AXON_TRY(expect_size(bytes, kMaxSize, "arm move times"));
  return ArmTimes{Time::from_ticks(read_u32(bytes, 0)), Time::from_ticks(read_u32(bytes, 4))};
}
std::string ArmTimes::to_string() const { return fmt::format("alpha={} beta={}", sec(alpha), sec(beta)); }

Result<ArmSpeeds> ArmSpeeds::decode(std::span<const std::uint8_t> bytes) {
  AXON_TRY(expect_size(bytes, kMaxSize, "motor speeds"));
  return ArmSpeeds{MotorSpeed::from_wire(read_u32(bytes, 0)), MotorSpeed::from_wire(read_u32(bytes, 4))};
}
std::string ArmSpeeds::to_string() const {
  return fmt::format("alpha={} rpm beta={} rpm", alpha.rpm(), beta.rpm());
}

Result<ArmCurrents> ArmCurrents::decode(std::span<const std::uint8_t> bytes) {
  AXON_TRY(expect_size(bytes, kMaxSize, "currents"));
  AXON_TRY(a, CurrentPercent::from_percent(read_u32(bytes, 0)));
  AXON_TRY(b, CurrentPercent::from_percent(read_u32(bytes, 4)));
  return ArmCurrents{a, b};
}
std::string ArmCurrents::to_string() const {
  return fmt::format("alpha={} % beta={} %", alpha.percent(), beta.percent());
}

Result<ArmMargins> ArmMargins::decode(std::span<const std::uint8_t> bytes) {
  AXON_TRY(expect_size(bytes, kMaxSize, "collision margins"));
  AXON_TRY(a, CollisionMargin::from_value(read_i32(bytes, 0)));
  AXON_TRY(b, CollisionMargin::from_value(read_i32(bytes, 4)));
  return ArmMargins{a, b};
}
std::string ArmMargins::to_string() const { return fmt::format("alpha={} beta={}", alpha.value(), beta.value()); }

Result<ArmIndices> ArmIndices::decode(std::span<const std::uint8_t> bytes) {
  AXON_TRY(expect_size(bytes, kMaxSize, "cogging indices"));
  return ArmIndices{read_u32(bytes, 0), read_u32(bytes, 4)};
}
std::string ArmIndices::to_string() const { return fmt::format("alpha_index={} beta_index={}", alpha, beta); }

Result<ArmValues> ArmValues::decode(std::span<const std::uint8_t> bytes) {
  AXON_TRY(expect_size(bytes, kMaxSize, "arm values"));
  return ArmValues{read_i32(bytes, 0), read_i32(bytes, 4)};
}
std::string ArmValues::to_string() const { return fmt::format("alpha={} beta={}", alpha, beta); }

Result<PositionAndValue> PositionAndValue::decode(std::span<const std::uint8_t> bytes) {
  AXON_TRY(expect_size(bytes, kMaxSize, "position and reading"));
  return PositionAndValue{Angle::from_steps(read_i32(bytes, 0)), read_i32(bytes, 4)};
}
std::string PositionAndValue::to_string() const {
  return fmt::format("position={} value={} %", deg(position), value);
}

Result<U32Value> U32Value::decode(std::span<const std::uint8_t> bytes) {
  AXON_TRY(expect_size(bytes, kMaxSize, "value"));
  return U32Value{read_u32(bytes, 0)};
}
std::string U32Value::to_string() const { return fmt::format("value={}", value); }

Result<FirmwareVersionReply> FirmwareVersionReply::decode(std::span<const std::uint8_t> bytes) {
  AXON_TRY(v, FirmwareVersion::decode(bytes));
  return FirmwareVersionReply{v};
}

Result<StatusReply> StatusReply::decode(std::span<const std::uint8_t> bytes) {
  AXON_TRY(s, PositionerStatus::decode(bytes));
  return StatusReply{s};
}

Result<BootloaderStatusReply> BootloaderStatusReply::decode(std::span<const std::uint8_t> bytes) {
  AXON_TRY(s, BootloaderStatus::decode(bytes));
  return BootloaderStatusReply{s};
}

Result<FirmwareUpgradeHeader> FirmwareUpgradeHeader::decode(std::span<const std::uint8_t> bytes) {
  AXON_TRY(expect_size(bytes, kMaxSize, "firmware upgrade header"));
  return FirmwareUpgradeHeader{read_u32(bytes, 0), read_u32(bytes, 4)};
}
std::string FirmwareUpgradeHeader::to_string() const { return fmt::format("size={} crc32=0x{:08X}", size, crc32); }

Result<FirmwareChunk> FirmwareChunk::decode(std::span<const std::uint8_t> bytes) {
  if (bytes.size() < kMinSize || bytes.size() > kMaxSize) {
    return Error(ProtocolErrc::wrong_length, fmt::format("firmware data: {} bytes, expected 1..8", bytes.size()));
  }
  AXON_TRY(p, Payload::from(bytes));
  return FirmwareChunk{p};
}

Result<void> check_payload(CommandId id, Direction dir, Mode mode, std::span<const std::uint8_t> bytes) {
  Result<void> out = ok();
  visit_command(id, [&]<CommandId C>() {
    auto check = [&]<class T>() -> Result<void> {
      auto r = T::decode(bytes);
      if (!r) return Error(r.error().code, fmt::format("{}: {}", command_name(C), r.error().detail));
      return ok();
    };
    if (dir == Direction::request) {
      out = check.template operator()<RequestOf<C>>();
    } else if (mode == Mode::bootloader) {
      out = check.template operator()<typename CommandTypes<C>::bootloader_reply>();
    } else {
      out = check.template operator()<ReplyOf<C>>();
    }
  });
  return out;
}

Result<std::string> describe_payload(CommandId id, Direction dir, Mode mode, std::span<const std::uint8_t> bytes) {
  Result<std::string> out = std::string();
  visit_command(id, [&]<CommandId C>() {
    auto show = [&]<class T>() -> Result<std::string> {
      AXON_TRY(v, T::decode(bytes));
      return v.to_string();
    };
    if (dir == Direction::request) {
      out = show.template operator()<RequestOf<C>>();
    } else if (mode == Mode::bootloader) {
      out = show.template operator()<typename CommandTypes<C>::bootloader_reply>();
    } else {
      out = show.template operator()<ReplyOf<C>>();
    }
  });
  return out;
}

}  // namespace axon::fps::protocol
