#include "axon/blmc/protocol/message_id.hpp"

#include <algorithm>
#include <array>

namespace axon::blmc::protocol {
namespace {
constexpr std::array kIds = {MessageId::command,  MessageId::iq_ref,   MessageId::kp,
                             MessageId::kd,       MessageId::pos_ref,  MessageId::vel_ref,
                             MessageId::status,   MessageId::current,  MessageId::position,
                             MessageId::velocity, MessageId::adc6,     MessageId::encoder_index};
}  // namespace

std::span<const MessageId> all_message_ids() noexcept { return kIds; }

std::optional<MessageId> message_id_from_raw(std::uint32_t raw) noexcept {
  const auto it = std::find_if(kIds.begin(), kIds.end(),
                               [raw](MessageId m) { return static_cast<std::uint32_t>(m) == raw; });
  if (it == kIds.end()) return std::nullopt;
  return *it;
}

std::string_view name(MessageId id) noexcept {
  switch (id) {
    case MessageId::command: return "COMMAND";
    case MessageId::iq_ref: return "IQ_REF";
    case MessageId::kp: return "KP";
    case MessageId::kd: return "KD";
    case MessageId::pos_ref: return "POS_REF";
    case MessageId::vel_ref: return "VEL_REF";
    case MessageId::status: return "STATUS";
    case MessageId::current: return "CURRENT";
    case MessageId::position: return "POSITION";
    case MessageId::velocity: return "VELOCITY";
    case MessageId::adc6: return "ADC6";
    case MessageId::encoder_index: return "ENCODER_INDEX";
  }
  return "?";
}

Direction direction(MessageId id) noexcept {
  return static_cast<std::uint16_t>(id) < 0x010 ? Direction::to_board : Direction::from_board;
}

std::size_t payload_size(MessageId id) noexcept {
  switch (id) {
    case MessageId::status: return 1;
    case MessageId::encoder_index: return 5;
    default: return 8;
  }
}

bool is_optional(MessageId id) noexcept {
  return id == MessageId::kp || id == MessageId::kd || id == MessageId::pos_ref || id == MessageId::vel_ref;
}

}  // namespace axon::blmc::protocol
