// The identifiers of blmc messages (11-bit standard frames) in both directions, their payload
// sizes and their send rates. A lower identifier wins arbitration, so host commands (0x000..0x009)
// beat board data (0x010..0x060).
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

namespace axon::blmc::protocol {

enum class MessageId : std::uint16_t {
  // host -> board
  command = 0x000,  // MDL value, MDH command code
  iq_ref = 0x005,   // current reference per motor [A]
  kp = 0x006,       // P gain per motor [A / motor rev]               (optional)
  kd = 0x007,       // D gain per motor [A / krpm]                    (optional)
  pos_ref = 0x008,  // position reference per motor [motor rev]       (optional)
  vel_ref = 0x009,  // velocity reference per motor [krpm]            (optional)
  // board -> host
  status = 0x010,         // 1 byte, see status.hpp
  current = 0x020,        // Iq per motor [A]
  position = 0x030,       // encoder position per motor [motor rev]
  velocity = 0x040,       // velocity per motor [krpm]
  adc6 = 0x050,           // ADC inputs A6 (motor 1 half) and B6 (motor 2 half), 0..1
  encoder_index = 0x060,  // 5 bytes: position at the index tick, motor number (0 or 1)
};

enum class Direction : std::uint8_t { to_board, from_board };

// The board also sees these identifiers used by force sensors on the same bus; not blmc messages.
inline constexpr std::uint32_t kOptoForceIds[] = {0x100, 0x101};

// Send rates of the board: status always (even while disabled); the four data messages every
// millisecond while enabled, in the order current, position, velocity, ADC. The encoder index
// frame has no rate: it goes out whenever the index mark passes.
inline constexpr std::chrono::milliseconds kStatusPeriod{1000};
inline constexpr std::chrono::milliseconds kDataPeriod{1};

// Every defined identifier, ascending.
std::span<const MessageId> all_message_ids() noexcept;
// The message with this raw identifier, or nothing.
std::optional<MessageId> message_id_from_raw(std::uint32_t raw) noexcept;

std::string_view name(MessageId id) noexcept;  // e.g. "IQ_REF", "STATUS"
Direction direction(MessageId id) noexcept;
std::size_t payload_size(MessageId id) noexcept;  // 1 status, 5 encoder index, 8 otherwise
// Documented but absent from the firmware in service (KP, KD, POS_REF, VEL_REF).
bool is_optional(MessageId id) noexcept;

}  // namespace axon::blmc::protocol
