// Response codes: the 4-bit result a positioner puts into the low bits of every reply identifier.
//
// They form a std::error_category ("axon.fps.response") so a rejected command travels as an
// axon::Error like any other failure; code 0 (accepted) is success. Each code has a printable
// name, a short meaning and advice on what to do about it (taken from the troubleshooting part of
// the interface document, in our own words).
#pragma once

#include "axon/core/error.hpp"

#include <cstdint>
#include <string_view>

namespace axon::fps::protocol {

enum class ResponseCode : std::uint8_t {
  accepted = 0,
  value_out_of_range = 1,
  invalid_trajectory = 2,
  already_in_motion = 3,
  datum_not_initialized = 4,
  incorrect_data_length = 5,
  calibration_mode_active = 6,
  motor_not_calibrated = 7,
  alpha_collision = 8,
  beta_collision = 9,
  invalid_broadcast = 10,
  invalid_bootloader_command = 11,
  invalid_command = 12,
  unknown_command = 13,
  datum_not_calibrated = 14,
  hall_sensors_disabled = 15,
};

inline constexpr std::uint8_t kMaxResponseCode = 15;

// "COMMAND_ACCEPTED", "VALUE_OUT_OF_RANGE", ... ("UNKNOWN_RESPONSE" above 15).
std::string_view response_name(ResponseCode c) noexcept;
// One line: what the positioner is saying.
std::string_view response_meaning(ResponseCode c) noexcept;
// What to do about it (empty for accepted).
std::string_view response_advice(ResponseCode c) noexcept;

// Checked conversion from the 4-bit wire field.
Result<ResponseCode> response_code_from(unsigned value);

const std::error_category& response_category() noexcept;
inline std::error_code make_error_code(ResponseCode c) noexcept {
  return {static_cast<int>(c), response_category()};
}

// The response code a positioner answers with when a request fails to decode with the given
// codec error: wrong_length -> incorrect_data_length, value_out_of_range -> value_out_of_range,
// invalid_trajectory -> invalid_trajectory, unknown_command -> unknown_command,
// broadcast_not_allowed -> invalid_broadcast. Other errors (and non-protocol errors) map to
// value_out_of_range, the device's catch-all for a request it cannot use.
ResponseCode response_code_for(std::error_code codec_error) noexcept;

}  // namespace axon::fps::protocol

template <>
struct std::is_error_code_enum<axon::fps::protocol::ResponseCode> : std::true_type {};
