#include "axon/blmc/protocol/command_code.hpp"

#include <algorithm>
#include <array>
#include <cctype>

namespace axon::blmc::protocol {
namespace {
using C = CommandCode;
using K = ValueKind;
constexpr std::array<CommandInfo, 17> kTable = {{
    {C::enable_sys, "ENABLE_SYS", K::flag, 1, false},
    {C::enable_mtr1, "ENABLE_MTR1", K::flag, 0, false},
    {C::enable_mtr2, "ENABLE_MTR2", K::flag, 0, false},
    {C::enable_vspring1, "ENABLE_VSPRING1", K::flag, 0, false},
    {C::enable_vspring2, "ENABLE_VSPRING2", K::flag, 0, false},
    {C::send_current, "SEND_CURRENT", K::flag, 0, false},
    {C::send_position, "SEND_POSITION", K::flag, 0, false},
    {C::send_velocity, "SEND_VELOCITY", K::flag, 0, false},
    {C::send_adc6, "SEND_ADC6", K::flag, 0, false},
    {C::send_enc_index, "SEND_ENC_INDEX", K::flag, 0, false},
    {C::send_all, "SEND_ALL", K::flag, 0, false},
    {C::set_can_recv_timeout, "SET_CAN_RECV_TIMEOUT", K::milliseconds, 0, false},
    {C::enable_pos_rollover_error, "ENABLE_POS_ROLLOVER_ERROR", K::flag, 0, false},
    {C::p_controller_limit_iq_mtr1, "CAN_CMD_P_CONTROLLER_LIMIT_IQ_MTR1", K::amperes_q24, 0, true},
    {C::p_controller_limit_iq_mtr2, "CAN_CMD_P_CONTROLLER_LIMIT_IQ_MTR2", K::amperes_q24, 0, true},
    {C::d_controller_limit_iq_mtr1, "CAN_CMD_D_CONTROLLER_LIMIT_IQ_MTR1", K::amperes_q24, 0, true},
    {C::d_controller_limit_iq_mtr2, "CAN_CMD_D_CONTROLLER_LIMIT_IQ_MTR2", K::amperes_q24, 0, true},
}};

bool iequal(std::string_view a, std::string_view b) noexcept {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::toupper(static_cast<unsigned char>(x)) == std::toupper(static_cast<unsigned char>(y));
         });
}
}  // namespace

std::span<const CommandInfo> command_table() noexcept { return kTable; }

const CommandInfo* find_command(std::uint32_t raw_code) noexcept {
  for (const auto& c : kTable) {
    if (static_cast<std::uint32_t>(c.code) == raw_code) return &c;
  }
  return nullptr;
}

const CommandInfo* find_command(std::string_view name) noexcept {
  for (const auto& c : kTable) {
    if (iequal(c.name, name)) return &c;
  }
  return nullptr;
}

const CommandInfo& info(CommandCode code) noexcept {
  // Every enumerator is in the table; the fallback only guards against a forged enum value.
  const CommandInfo* c = find_command(static_cast<std::uint32_t>(code));
  return c ? *c : kTable[0];
}

std::string_view name(CommandCode code) noexcept {
  const CommandInfo* c = find_command(static_cast<std::uint32_t>(code));
  return c ? c->name : std::string_view("?");
}

}  // namespace axon::blmc::protocol
