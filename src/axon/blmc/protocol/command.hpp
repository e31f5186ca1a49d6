// One command (message 0x000): a code and the 32-bit value for it, plus the text form the board's
// documentation uses, NAME=value (e.g. "ENABLE_SYS=1", "SET_CAN_RECV_TIMEOUT=100",
// "CAN_CMD_P_CONTROLLER_LIMIT_IQ_MTR1=2.5").
//
// A Command always holds a value its code accepts: flags are 0 or 1, timeouts any uint32, current
// limits any Q24. Names parse case-insensitively and print as the table spells them.
#pragma once

#include "axon/blmc/protocol/command_code.hpp"
#include "axon/core/error.hpp"

#include <cstdint>
#include <string>
#include <string_view>

namespace axon::blmc::protocol {

class Command {
 public:
  // A flag command; value_out_of_range if the code does not take a flag.
  static Result<Command> flag(CommandCode code, bool on);
  // SET_CAN_RECV_TIMEOUT; 0 disables the timeout.
  static Command recv_timeout_ms(std::uint32_t ms) noexcept;
  // A current-limit command [A]; value_out_of_range if the code does not take a current or the
  // current does not fit Q24.
  static Result<Command> current_limit(CommandCode code, double amperes);
  // The raw MDL bits for any code, checked against the code's value kind.
  static Result<Command> from_raw(CommandCode code, std::uint32_t raw_value);

  static Result<Command> parse(std::string_view text);  // NAME=value
  [[nodiscard]] std::string to_string() const;          // NAME=value

  [[nodiscard]] CommandCode code() const noexcept { return code_; }
  [[nodiscard]] std::uint32_t raw_value() const noexcept { return raw_; }
  // The value as a number in its unit: 0/1, milliseconds or amperes.
  [[nodiscard]] double value() const noexcept;

  friend bool operator==(const Command&, const Command&) = default;

 private:
  Command(CommandCode c, std::uint32_t raw) noexcept : code_(c), raw_(raw) {}
  CommandCode code_;
  std::uint32_t raw_;
};

}  // namespace axon::blmc::protocol
