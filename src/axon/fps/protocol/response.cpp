#include "axon/fps/protocol/response.hpp"

#include "axon/fps/protocol/error.hpp"

#include <fmt/format.h>

#include <array>
#include <string>

namespace axon::fps::protocol {
namespace {

struct ResponseText {
  std::string_view name;
  std::string_view meaning;
  std::string_view advice;
};

// Indexed by the code. The advice condenses the troubleshooting chapter of the interface document.
constexpr std::array<ResponseText, 16> kTexts{{
    {"COMMAND_ACCEPTED", "the command was carried out without error", ""},
    {"VALUE_OUT_OF_RANGE", "a value in the request is outside the positioner's limits",
     "check positions, speeds and currents against the limits set at the factory; for a trajectory, "
     "the first point must be reachable from the current position without exceeding the speed limit"},
    {"INVALID_TRAJECTORY", "the trajectory as a whole was rejected when it was closed",
     "make sure the number of points sent matches SEND_NEW_TRAJECTORY and every point was accepted, "
     "then send the whole trajectory again"},
    {"ALREADY_IN_MOTION", "a move or calibration is still running",
     "wait until GET_STATUS shows DISPLACEMENT_COMPLETED, or end the running move with STOP_TRAJECTORY (15)"},
    {"DATUM_NOT_INITIALIZED", "the positioner has lost its zero reference at the hard stops",
     "run GO_TO_DATUMS (20) once nothing can be hit on the way to the hard stops; if the way is not clear, "
     "first bring the arms near the stops with relative moves (31), or set an approximate position (33) and "
     "re-datum afterwards"},
    {"INCORRECT_DATA_LENGTH", "the request carried the wrong number of data bytes for its command",
     "check the payload size against the command table (a host bug or a corrupted frame)"},
    {"CALIBRATION_MODE_ACTIVE", "a motor, datum or cogging calibration is running",
     "wait for DISPLACEMENT_COMPLETED and the matching calibrated flag in GET_STATUS, or abort the "
     "calibration with STOP_TRAJECTORY (15)"},
    {"MOTOR_NOT_CALIBRATED", "the motors are not calibrated, so the hall sensors cannot be used",
     "run CALIBRATE_MOTORS (26) before datum or cogging calibration, then SAVE_CALIBRATION (53)"},
    {"ALPHA_COLLISION", "the alpha arm detected a collision and its flag is still set",
     "stop every robot; inspect; clear the flag with STOP_TRAJECTORY (15) (TRAJECTORY_ABORT keeps it) and "
     "back the arm off by at least 2 degrees; for false alarms from friction or cold raise the collision "
     "margin (111); if it persists test the axis in open loop without collision detection (121) and compare "
     "hall readings (44) with the motion"},
    {"BETA_COLLISION", "the beta arm detected a collision and its flag is still set",
     "stop every robot; inspect; clear the flag with STOP_TRAJECTORY (15) (TRAJECTORY_ABORT keeps it) and "
     "back the arm off by at least 2 degrees; for false alarms from friction or cold raise the collision "
     "margin (111); if it persists test the axis in open loop without collision detection (125) and compare "
     "hall readings (44) with the motion"},
    {"INVALID_BROADCAST_COMMAND", "this command cannot be sent to positioner 0 (broadcast)",
     "address each positioner by its id"},
    {"INVALID_BOOTLOADER_COMMAND", "the positioner runs its bootloader, which does not know this command",
     "only GET_ID, GET_FIRMWARE_VERSION, GET_STATUS and the firmware upgrade commands work there; wait for the "
     "10 s bootloader timeout or power-cycle with the sync line released to start the main application"},
    {"INVALID_COMMAND", "the main application does not take this command",
     "firmware upgrade commands need the bootloader: power on with the sync line held low"},
    {"UNKNOWN_COMMAND", "the firmware does not know this command number",
     "check the command number and the positioner's firmware version"},
    {"DATUM_NOT_CALIBRATED", "the datums have not been calibrated",
     "run CALIBRATE_DATUM (23) after the motor calibration, then SAVE_CALIBRATION (53)"},
    {"HALL_SENSORS_DISABLED", "the hall sensors are off or not in use",
     "after SWITCH_OFF_HALL (117) send SWITCH_ON_HALL (116) and allow about 5 s before moving; calibrations "
     "also need the sensors, so switch an axis out of open loop without collision detection (121/125) with "
     "118/122 first"},
}};

const ResponseText* text_of(ResponseCode c) noexcept {
  const auto i = static_cast<std::size_t>(c);
  return i < kTexts.size() ? &kTexts[i] : nullptr;
}

class ResponseCategory final : public std::error_category {
 public:
  const char* name() const noexcept override { return "axon.fps.response"; }
  std::string message(int c) const override {
    if (c < 0 || c > kMaxResponseCode) return fmt::format("unknown fps response code {}", c);
    const auto& t = kTexts[static_cast<std::size_t>(c)];
    if (t.advice.empty()) return fmt::format("positioner: {} ({})", t.name, t.meaning);
    return fmt::format("positioner: {} ({}); {}", t.name, t.meaning, t.advice);
  }
};

}  // namespace

std::string_view response_name(ResponseCode c) noexcept {
  const auto* t = text_of(c);
  return t ? t->name : std::string_view("UNKNOWN_RESPONSE");
}

std::string_view response_meaning(ResponseCode c) noexcept {
  const auto* t = text_of(c);
  return t ? t->meaning : std::string_view("response code outside 0..15");
}

std::string_view response_advice(ResponseCode c) noexcept {
  const auto* t = text_of(c);
  return t ? t->advice : std::string_view();
}

Result<ResponseCode> response_code_from(unsigned value) {
  if (value > kMaxResponseCode) {
    return Error(ProtocolErrc::response_out_of_range, fmt::format("response code {}", value));
  }
  return static_cast<ResponseCode>(value);
}

const std::error_category& response_category() noexcept {
  static const ResponseCategory c;
  return c;
}

ResponseCode response_code_for(std::error_code e) noexcept {
  if (e.category() != protocol_category()) return ResponseCode::value_out_of_range;
  switch (static_cast<ProtocolErrc>(e.value())) {
    case ProtocolErrc::wrong_length: return ResponseCode::incorrect_data_length;
    case ProtocolErrc::invalid_trajectory: return ResponseCode::invalid_trajectory;
    case ProtocolErrc::unknown_command: return ResponseCode::unknown_command;
    case ProtocolErrc::broadcast_not_allowed: return ResponseCode::invalid_broadcast;
    default: return ResponseCode::value_out_of_range;
  }
}

}  // namespace axon::fps::protocol
