#include "axon/fps/protocol/firmware_gates.hpp"

#include <fmt/format.h>

namespace axon::fps::protocol {
namespace {

// From this version on, hosts in service send the precise-move switches (FIELD-NOTES).
constexpr FirmwareVersion kPreciseMoveSwitches{4, 1, 17};

bool precise_move_switch(CommandId c) noexcept {
  return c == CommandId::switch_on_precise_move_alpha || c == CommandId::switch_off_precise_move_alpha ||
         c == CommandId::switch_on_precise_move_beta || c == CommandId::switch_off_precise_move_beta;
}

}  // namespace

bool firmware_takes(CommandId c, FirmwareVersion version, FirmwareHistory history) noexcept {
  if (precise_move_switch(c)) return history == FirmwareHistory::document || version.has_precise_move_switches();
  return true;
}

std::string firmware_lacks(CommandId c, FirmwareVersion version, FirmwareHistory history) {
  if (firmware_takes(c, version, history)) return {};
  return fmt::format("firmware {} lacks {} ({}): it has it from {} on", version.to_string(), command_name(c), number(c),
                     kPreciseMoveSwitches.to_string());
}

std::string status_layout_unknown(FirmwareVersion version) {
  if (version.has_64bit_status()) return {};
  return fmt::format("firmware {} predates {}: its status word is not the 64-bit layout of the document and is "
                     "described nowhere",
                     version.to_string(), kOldestModelledFirmware.to_string());
}

}  // namespace axon::fps::protocol
