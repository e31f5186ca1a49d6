// Fuzzes the fps protocol decoders with arbitrary identifiers and payloads.
//
// Input: byte 0 selects the mode (bit 0: bootloader), the direction (bit 1: reply) and the version
// byte order (bit 2: document order); bytes 1..4 are a raw identifier (little-endian, all 32 bits,
// so out-of-range identifiers are tried too); the rest is the payload (more than 8 bytes is tried as
// well). Nothing may crash, every decoder must reject or accept cleanly, and whatever decodes must
// encode back to the same bytes.
#include "axon/can/frame.hpp"
#include "axon/fps/protocol/commands.hpp"
#include "axon/fps/protocol/error.hpp"
#include "axon/fps/protocol/message.hpp"
#include "axon/fps/protocol/payloads.hpp"
#include "axon/fps/protocol/trajectory.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>

using namespace axon::fps::protocol;

namespace {

void require(bool ok) {
  if (!ok) __builtin_trap();
}

template <class T>
void round_trip(std::span<const std::uint8_t> b) {
  auto r = T::decode(b);
  if (!r) {
    require(r.error().code.category() == protocol_category());
    return;
  }
  const Payload p = r.value().encode();
  require(p.size() == b.size() && std::equal(b.begin(), b.end(), p.data()));
  (void)r.value().to_string();
}

void all_codecs(std::span<const std::uint8_t> b) {
  round_trip<Empty>(b);
  round_trip<PositionerIdReply>(b);
  round_trip<TrajectorySize>(b);
  round_trip<TrajectoryPoint>(b);
  round_trip<ArmPositions>(b);
  round_trip<ArmTimes>(b);
  round_trip<ArmSpeeds>(b);
  round_trip<ArmCurrents>(b);
  round_trip<ArmMargins>(b);
  round_trip<ArmIndices>(b);
  round_trip<ArmValues>(b);
  round_trip<PositionAndValue>(b);
  round_trip<U32Value>(b);
  round_trip<FirmwareVersionReply>(b);
  round_trip<StatusReply>(b);
  round_trip<BootloaderStatusReply>(b);
  round_trip<FirmwareUpgradeHeader>(b);
  round_trip<FirmwareChunk>(b);
  if (auto v = FirmwareVersion::decode(b, VersionByteOrder::document)) {
    const Payload p = v.value().encode(VersionByteOrder::document);
    require(std::equal(b.begin(), b.end(), p.data()));
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 5) return 0;
  const Mode mode = (data[0] & 1) ? Mode::bootloader : Mode::application;
  const Direction dir = (data[0] & 2) ? Direction::reply : Direction::request;
  const std::uint32_t raw = static_cast<std::uint32_t>(data[1]) | (static_cast<std::uint32_t>(data[2]) << 8) |
                            (static_cast<std::uint32_t>(data[3]) << 16) | (static_cast<std::uint32_t>(data[4]) << 24);
  const std::span<const std::uint8_t> payload(data + 5, size - 5);

  // Identifiers wider than 29 bits are rejected; all others round-trip.
  const auto id_full = decode_identifier(raw);
  require(id_full.has_value() == (raw <= kMaxIdentifier));
  const std::uint32_t id29 = raw & kMaxIdentifier;

  all_codecs(payload);

  auto frame = axon::can::Frame::extended(id29, payload);
  if (!frame) {
    require(payload.size() > 8);
    require(!Payload::from(payload));
    return 0;
  }
  const auto m = from_frame(frame.value());
  require(m.has_value());
  require(encode_identifier(m.value().id).value() == id29);
  require(to_frame(m.value()).value() == frame.value());
  (void)to_string(m.value());

  const auto& id = m.value().id;
  const auto verdict = check_device_request(id.command, mode, id.is_broadcast(), payload.size());
  const CommandInfo* info = find_command(id.command);
  require((info == nullptr) == (verdict.code == ResponseCode::unknown_command));
  if (info == nullptr) return 0;

  if (verdict.code == ResponseCode::accepted) {
    // The size is right, so a full decode can only fail on a value.
    const auto r = check_payload(verdict.command->id, Direction::request, mode, payload);
    require(r || r.error() == ProtocolErrc::value_out_of_range || r.error() == ProtocolErrc::positioner_out_of_range);
  }
  (void)check_payload(info->id, dir, mode, payload);
  (void)describe_payload(info->id, dir, mode, payload);
  (void)check_reply(*info, mode, id.response, payload.size());
  (void)check_request(*info, id.is_broadcast(), payload.size());
  if (id.positioner != kBroadcastId) {
    (void)make_request(id.positioner, info->id, id.uid, payload);
  }

  // A one-point trajectory from the payload's numbers.
  if (auto p = TrajectoryPoint::decode(payload)) {
    const auto t = Trajectory::make({p.value()}, {});
    require(t.has_value() == (p.value().time.ticks() > 0));
    if (t && id.positioner != kBroadcastId) require(upload_frames(id.positioner, t.value()).value().size() == 3);
  }
  return 0;
}
