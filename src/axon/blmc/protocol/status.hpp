// The status byte (message 0x010): five flags in bits 0..4 and an error code in bits 5..7.
//
//   bit 0 system enabled, bit 1 motor 1 enabled, bit 2 motor 1 ready,
//   bit 3 motor 2 enabled, bit 4 motor 2 ready, bits 5..7 error code.
//
// "Ready" means the motor finished its alignment (which runs on the first enable after power-up).
// Error code 6 is not defined; decoding a byte that carries it is ProtocolErrc::unknown_error_code.
#pragma once

#include "axon/core/error.hpp"

#include <cstdint>
#include <string>
#include <string_view>

namespace axon::blmc::protocol {

enum class ErrorCode : std::uint8_t {
  none = 0,
  encoder = 1,
  can_recv_timeout = 2,
  crit_temp = 3,           // reserved: the boards have no temperature sensing
  pos_converter = 4,       // position converter module failure
  pos_rollover = 5,        // only when ENABLE_POS_ROLLOVER_ERROR=1
  other = 7,               // catch-all; the firmware reports a transmit failure with it
};

std::string_view name(ErrorCode e) noexcept;  // e.g. "ENCODER", "CAN_RECV_TIMEOUT"

// The 3-bit error field of a status byte (bits 5..7) as it arrived, defined or not.
constexpr std::uint8_t error_bits(std::uint8_t status_byte) noexcept {
  return static_cast<std::uint8_t>(status_byte >> 5);
}
// The one value of the field the spec leaves undefined. A board that sends it reports an error the
// host cannot name (a newer firmware's code, a corrupted byte): hosts treat it as an error.
inline constexpr std::uint8_t kUndocumentedErrorCode = 6;
// The code for the 3-bit field value, or unknown_error_code for 6 and value_out_of_range above 7.
Result<ErrorCode> error_code_from_raw(std::uint8_t raw);

struct Status {
  bool system_enabled = false;
  bool motor1_enabled = false;
  bool motor1_ready = false;
  bool motor2_enabled = false;
  bool motor2_ready = false;
  ErrorCode error = ErrorCode::none;

  [[nodiscard]] std::uint8_t to_byte() const noexcept;
  static Result<Status> from_byte(std::uint8_t byte);
  // e.g. "SYS MTR1(enabled,ready) MTR2(-) error=NONE"
  [[nodiscard]] std::string to_string() const;

  friend bool operator==(const Status&, const Status&) = default;
};

// Which single code the board reports when several faults hold at once: encoder, then transmit
// failure (reported as OTHER), then receive timeout, then position converter, then rollover.
struct FaultSet {
  bool encoder = false;
  bool transmit = false;
  bool recv_timeout = false;
  bool pos_converter = false;
  bool pos_rollover = false;
};
ErrorCode reported_error(const FaultSet& faults) noexcept;

}  // namespace axon::blmc::protocol
