// The command codes of the command message (id 0x000): the code goes in MDH, the value in MDL.
// Each code says what kind of value it takes: a 0/1 flag, a plain unsigned number of milliseconds,
// or a current in amperes as Q24.
#pragma once

#include <cstdint>
#include <span>
#include <string_view>

namespace axon::blmc::protocol {

enum class CommandCode : std::uint8_t {
  enable_sys = 0x01,
  enable_mtr1 = 0x02,
  enable_mtr2 = 0x03,
  enable_vspring1 = 0x04,
  enable_vspring2 = 0x05,
  send_current = 0x0C,
  send_position = 0x0D,
  send_velocity = 0x0E,
  send_adc6 = 0x0F,
  send_enc_index = 0x10,  // encoder index frames (0x060); SEND_ALL switches them too
  send_all = 0x14,
  set_can_recv_timeout = 0x1E,  // milliseconds, 0 = no timeout
  enable_pos_rollover_error = 0x1F,
  p_controller_limit_iq_mtr1 = 0x28,  // optional (not in the firmware in service)
  p_controller_limit_iq_mtr2 = 0x29,  // optional
  d_controller_limit_iq_mtr1 = 0x2A,  // optional
  d_controller_limit_iq_mtr2 = 0x2B,  // optional
};

enum class ValueKind : std::uint8_t {
  flag,         // 0 or 1, anything else is rejected
  milliseconds, // the 32 MDL bits as an unsigned number
  amperes_q24,  // a current, Q24
};

struct CommandInfo {
  CommandCode code;
  std::string_view name;  // as the nomenclature NAME=value writes it, e.g. "ENABLE_SYS"
  ValueKind kind;
  std::uint32_t default_raw;  // the board's value after power-up (MDL bits)
  bool optional;              // documented, but absent from the firmware in service
};

std::span<const CommandInfo> command_table() noexcept;
// nullptr when the code (MDH, all 32 bits) or the name (case-insensitive) is not defined.
const CommandInfo* find_command(std::uint32_t raw_code) noexcept;
const CommandInfo* find_command(std::string_view name) noexcept;
const CommandInfo& info(CommandCode code) noexcept;
std::string_view name(CommandCode code) noexcept;

}  // namespace axon::blmc::protocol
