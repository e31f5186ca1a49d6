// Encoding and decoding of every blmc message to and from can::Frame. Pure: no I/O.
//
// Payload layout: the 8 data bytes are two 4-byte halves, MDL = bytes 0..3 (motor 1, or the
// command value) and MDH = bytes 4..7 (motor 2, or the command code). Each half is a big-endian
// (most significant byte first) two's-complement int32. Motor quantities are Q24 (see q24.hpp).
// Exceptions: status is one byte; the encoder index frame is 5 bytes, a Q24 position in bytes 0..3
// and the motor number (0 = motor 1, 1 = motor 2) in byte 4.
//
// Decoders reject, with a typed ProtocolErrc, anything that is not exactly the message: extended or
// remote frames, another identifier, another payload length, an undefined command code or status
// error code, a flag other than 0/1, an ADC reading outside 0..1, a motor number other than 0/1.
#pragma once

#include "axon/blmc/protocol/command.hpp"
#include "axon/blmc/protocol/message_id.hpp"
#include "axon/blmc/protocol/status.hpp"
#include "axon/can/frame.hpp"
#include "axon/core/error.hpp"

#include <cstdint>
#include <span>
#include <string>
#include <variant>

namespace axon::blmc::protocol {

// The firmware's position counter rolls over: readings lie in [-100, 100) motor revolutions, and a
// shaft turning past +100 reads -100 next (error 5, POS_ROLLOVER, only when enabled).
inline constexpr double kPositionRolloverRev = 100.0;

// One value per motor, in the message's unit (A, motor rev, krpm, ADC fraction, or gains).
struct MotorPair {
  double motor1 = 0.0;
  double motor2 = 0.0;
  friend bool operator==(const MotorPair&, const MotorPair&) = default;
};

// A two-motor message: any of 0x005..0x009 (to the board) or 0x020..0x050 (from the board).
struct PairMessage {
  MessageId id = MessageId::iq_ref;
  MotorPair values;
  friend bool operator==(const PairMessage&, const PairMessage&) = default;
};

struct EncoderIndex {
  double position_rev = 0.0;  // motor position at the index mark
  std::uint8_t motor = 0;     // 0 = motor 1, 1 = motor 2
  friend bool operator==(const EncoderIndex&, const EncoderIndex&) = default;
};

// True for the identifiers PairMessage may carry.
bool is_pair_message(MessageId id) noexcept;

// Big-endian int32 halves: the helpers every 8-byte message uses.
void put_be32(std::span<std::uint8_t, 4> out, std::uint32_t v) noexcept;
std::uint32_t get_be32(std::span<const std::uint8_t, 4> in) noexcept;

// Host -> board.
Result<can::Frame> encode(const Command& cmd);
Result<can::Frame> encode(const PairMessage& msg);  // value_out_of_range if a value misses Q24
Result<can::Frame> encode_iq_ref(MotorPair amperes);
// Board -> host (for simulators and tests).
Result<can::Frame> encode(const Status& status);
Result<can::Frame> encode(const EncoderIndex& index);

Result<Command> decode_command(const can::Frame& f);
Result<Status> decode_status(const can::Frame& f);
Result<EncoderIndex> decode_encoder_index(const can::Frame& f);
// Decodes f as the two-motor message `id`; wrong_id if f carries another identifier.
Result<MotorPair> decode_pair(MessageId id, const can::Frame& f);

// Everything a board sends / everything a host sends, dispatched on the identifier. An identifier
// of the other direction or none at all is unknown_id.
using FromBoard = std::variant<Status, PairMessage, EncoderIndex>;
using ToBoard = std::variant<Command, PairMessage>;
Result<FromBoard> decode_from_board(const can::Frame& f);
Result<ToBoard> decode_to_board(const can::Frame& f);
Result<can::Frame> encode(const FromBoard& msg);
Result<can::Frame> encode(const ToBoard& msg);

// One line for logs, e.g. "IQ_REF m1=0.5 m2=-1", "COMMAND ENABLE_SYS=1", "STATUS SYS MTR1(-) ...".
std::string to_string(const FromBoard& msg);
std::string to_string(const ToBoard& msg);

}  // namespace axon::blmc::protocol
