#include "axon/blmc/protocol/frames.hpp"

#include "axon/blmc/protocol/error.hpp"
#include "axon/blmc/protocol/q24.hpp"

#include <fmt/format.h>

#include <array>

namespace axon::blmc::protocol {
namespace {

Result<can::Frame> make(MessageId id, std::span<const std::uint8_t> bytes) {
  return can::Frame::standard(static_cast<std::uint32_t>(id), bytes);
}

// Checks everything but the content: standard data frame, the expected id, the expected length.
Result<void> check_frame(MessageId id, const can::Frame& f) {
  if (f.is_extended() || f.is_remote()) {
    return Error(ProtocolErrc::not_standard_frame, fmt::format("frame {}", f.to_string()));
  }
  if (f.id() != static_cast<std::uint32_t>(id)) {
    return Error(ProtocolErrc::wrong_id,
                 fmt::format("expected {} (0x{:03X}), got frame {}", name(id), static_cast<unsigned>(id), f.to_string()));
  }
  if (f.payload().size() != payload_size(id)) {
    return Error(ProtocolErrc::wrong_length, fmt::format("{} needs {} bytes, got frame {}", name(id),
                                                         payload_size(id), f.to_string()));
  }
  return ok();
}

std::int32_t half(std::span<const std::uint8_t> p, std::size_t at) {
  return static_cast<std::int32_t>(get_be32(std::span<const std::uint8_t, 4>(p.data() + at, 4)));
}

}  // namespace

bool is_pair_message(MessageId id) noexcept {
  switch (id) {
    case MessageId::iq_ref:
    case MessageId::kp:
    case MessageId::kd:
    case MessageId::pos_ref:
    case MessageId::vel_ref:
    case MessageId::current:
    case MessageId::position:
    case MessageId::velocity:
    case MessageId::adc6:
      return true;
    default:
      return false;
  }
}

void put_be32(std::span<std::uint8_t, 4> out, std::uint32_t v) noexcept {
  out[0] = static_cast<std::uint8_t>(v >> 24);
  out[1] = static_cast<std::uint8_t>(v >> 16);
  out[2] = static_cast<std::uint8_t>(v >> 8);
  out[3] = static_cast<std::uint8_t>(v);
}

std::uint32_t get_be32(std::span<const std::uint8_t, 4> in) noexcept {
  return (std::uint32_t{in[0]} << 24) | (std::uint32_t{in[1]} << 16) | (std::uint32_t{in[2]} << 8) |
         std::uint32_t{in[3]};
}

Result<can::Frame> encode(const Command& cmd) {
  std::array<std::uint8_t, 8> b{};
  put_be32(std::span<std::uint8_t, 4>(b.data(), 4), cmd.raw_value());
  put_be32(std::span<std::uint8_t, 4>(b.data() + 4, 4), static_cast<std::uint32_t>(cmd.code()));
  return make(MessageId::command, b);
}

Result<can::Frame> encode(const PairMessage& msg) {
  if (!is_pair_message(msg.id)) {
    return Error(ProtocolErrc::wrong_id, fmt::format("{} is not a two-motor message", name(msg.id)));
  }
  if (msg.id == MessageId::adc6) {
    for (double v : {msg.values.motor1, msg.values.motor2}) {
      if (!(v >= 0.0 && v <= 1.0)) {
        return Error(ProtocolErrc::value_out_of_range, fmt::format("ADC reading {} outside 0..1", v));
      }
    }
  }
  AXON_TRY(q1, to_q24(msg.values.motor1));
  AXON_TRY(q2, to_q24(msg.values.motor2));
  std::array<std::uint8_t, 8> b{};
  put_be32(std::span<std::uint8_t, 4>(b.data(), 4), static_cast<std::uint32_t>(q1));
  put_be32(std::span<std::uint8_t, 4>(b.data() + 4, 4), static_cast<std::uint32_t>(q2));
  return make(msg.id, b);
}

Result<can::Frame> encode_iq_ref(MotorPair amperes) { return encode(PairMessage{MessageId::iq_ref, amperes}); }

Result<can::Frame> encode(const Status& status) {
  const std::array<std::uint8_t, 1> b{status.to_byte()};
  return make(MessageId::status, b);
}

Result<can::Frame> encode(const EncoderIndex& index) {
  if (index.motor > 1) {
    return Error(ProtocolErrc::value_out_of_range,
                 fmt::format("encoder index motor number {} (0 = motor 1, 1 = motor 2)", index.motor));
  }
  AXON_TRY(q, to_q24(index.position_rev));
  std::array<std::uint8_t, 5> b{};
  put_be32(std::span<std::uint8_t, 4>(b.data(), 4), static_cast<std::uint32_t>(q));
  b[4] = index.motor;
  return make(MessageId::encoder_index, b);
}

Result<Command> decode_command(const can::Frame& f) {
  AXON_TRY(check_frame(MessageId::command, f));
  const auto p = f.payload();
  const auto code = static_cast<std::uint32_t>(half(p, 4));
  const CommandInfo* ci = find_command(code);
  if (ci == nullptr) {
    return Error(ProtocolErrc::unknown_command, fmt::format("command code 0x{:X} in {}", code, f.to_string()));
  }
  return Command::from_raw(ci->code, static_cast<std::uint32_t>(half(p, 0)));
}

Result<Status> decode_status(const can::Frame& f) {
  AXON_TRY(check_frame(MessageId::status, f));
  return Status::from_byte(f.payload()[0]);
}

Result<EncoderIndex> decode_encoder_index(const can::Frame& f) {
  AXON_TRY(check_frame(MessageId::encoder_index, f));
  const auto p = f.payload();
  if (p[4] > 1) {
    return Error(ProtocolErrc::value_out_of_range,
                 fmt::format("encoder index motor number {} in {}", p[4], f.to_string()));
  }
  return EncoderIndex{from_q24(half(p, 0)), p[4]};
}

Result<MotorPair> decode_pair(MessageId id, const can::Frame& f) {
  if (!is_pair_message(id)) {
    return Error(ProtocolErrc::wrong_id, fmt::format("{} is not a two-motor message", name(id)));
  }
  AXON_TRY(check_frame(id, f));
  const auto p = f.payload();
  const MotorPair v{from_q24(half(p, 0)), from_q24(half(p, 4))};
  if (id == MessageId::adc6 && !(v.motor1 >= 0.0 && v.motor1 <= 1.0 && v.motor2 >= 0.0 && v.motor2 <= 1.0)) {
    return Error(ProtocolErrc::value_out_of_range, fmt::format("ADC reading outside 0..1 in {}", f.to_string()));
  }
  return v;
}

Result<FromBoard> decode_from_board(const can::Frame& f) {
  const auto id = message_id_from_raw(f.id());
  if (f.is_extended() || f.is_remote()) {
    return Error(ProtocolErrc::not_standard_frame, fmt::format("frame {}", f.to_string()));
  }
  if (!id || direction(*id) != Direction::from_board) {
    return Error(ProtocolErrc::unknown_id, fmt::format("0x{:03X} is not sent by a blmc board", f.id()));
  }
  switch (*id) {
    case MessageId::status: {
      AXON_TRY(s, decode_status(f));
      return FromBoard{s};
    }
    case MessageId::encoder_index: {
      AXON_TRY(e, decode_encoder_index(f));
      return FromBoard{e};
    }
    default: {
      AXON_TRY(v, decode_pair(*id, f));
      return FromBoard{PairMessage{*id, v}};
    }
  }
}

Result<ToBoard> decode_to_board(const can::Frame& f) {
  const auto id = message_id_from_raw(f.id());
  if (f.is_extended() || f.is_remote()) {
    return Error(ProtocolErrc::not_standard_frame, fmt::format("frame {}", f.to_string()));
  }
  if (!id || direction(*id) != Direction::to_board) {
    return Error(ProtocolErrc::unknown_id, fmt::format("0x{:03X} is not sent to a blmc board", f.id()));
  }
  if (*id == MessageId::command) {
    AXON_TRY(c, decode_command(f));
    return ToBoard{c};
  }
  AXON_TRY(v, decode_pair(*id, f));
  return ToBoard{PairMessage{*id, v}};
}

Result<can::Frame> encode(const FromBoard& msg) {
  if (const auto* p = std::get_if<PairMessage>(&msg); p && direction(p->id) != Direction::from_board) {
    return Error(ProtocolErrc::wrong_id, fmt::format("{} is not sent by a board", name(p->id)));
  }
  return std::visit([](const auto& m) { return encode(m); }, msg);
}

Result<can::Frame> encode(const ToBoard& msg) {
  if (const auto* p = std::get_if<PairMessage>(&msg); p && direction(p->id) != Direction::to_board) {
    return Error(ProtocolErrc::wrong_id, fmt::format("{} is not sent to a board", name(p->id)));
  }
  return std::visit([](const auto& m) { return encode(m); }, msg);
}

namespace {
std::string pair_string(const PairMessage& p) {
  return fmt::format("{} m1={} m2={}", name(p.id), p.values.motor1, p.values.motor2);
}
}  // namespace

std::string to_string(const FromBoard& msg) {
  if (const auto* s = std::get_if<Status>(&msg)) return "STATUS " + s->to_string();
  if (const auto* e = std::get_if<EncoderIndex>(&msg)) {
    return fmt::format("ENCODER_INDEX motor{} pos={}", e->motor + 1, e->position_rev);
  }
  return pair_string(std::get<PairMessage>(msg));
}

std::string to_string(const ToBoard& msg) {
  if (const auto* c = std::get_if<Command>(&msg)) return "COMMAND " + c->to_string();
  return pair_string(std::get<PairMessage>(msg));
}

}  // namespace axon::blmc::protocol
