// A command as an actor receives it: the message body, a JSON object whose `command_string` holds
// the command line (clu's convention), and that line split into a verb and its arguments. Pure
// functions: no broker, no device.
#pragma once

#include "axon/core/error.hpp"

#include <string>
#include <string_view>
#include <vector>

namespace axon::actor {

struct CommandLine {
  std::string verb;
  std::vector<std::string> args;
};

// The `command_string` of a command body. Errors (CoreErrc::invalid_argument, with the reason):
// not JSON, not an object, no `command_string` or not a string.
Result<std::string> command_string_of(std::string_view body);

// Splits on blanks; "double quotes" keep blanks inside one argument (\" and \\ escape). Errors
// (CoreErrc::invalid_argument): empty, an unterminated quote.
Result<CommandLine> split_command(std::string_view text);

// The body a commander sends: {"command_string": text}.
std::string command_body(std::string_view text);

}  // namespace axon::actor
