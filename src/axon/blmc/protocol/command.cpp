#include "axon/blmc/protocol/command.hpp"

#include "axon/core/text.hpp"

#include "axon/blmc/protocol/error.hpp"
#include "axon/blmc/protocol/q24.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cstdlib>
#include <string>

namespace axon::blmc::protocol {
namespace {

using core::trim;

// Parses all of `s` as a number (strtod: decimal or exponent form; inf/nan parse here and are
// rejected later by the Q24 range check).
Result<double> parse_double(std::string_view s) {
  if (s.empty() || s.size() > 64) return Error(ProtocolErrc::bad_command_text, "value is not a number");
  const std::string z(s);
  char* end = nullptr;
  const double v = std::strtod(z.c_str(), &end);
  if (end != z.c_str() + z.size()) {
    return Error(ProtocolErrc::bad_command_text, fmt::format("value '{}' is not a number", s));
  }
  return v;
}

Result<std::uint32_t> parse_u32(std::string_view s) {
  std::uint32_t v = 0;
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec == std::errc::result_out_of_range) {
    return Error(ProtocolErrc::value_out_of_range, fmt::format("value '{}' does not fit 32 bits", s));
  }
  if (ec != std::errc() || p != s.data() + s.size() || s.empty()) {
    return Error(ProtocolErrc::bad_command_text, fmt::format("value '{}' is not an unsigned integer", s));
  }
  return v;
}

}  // namespace

Result<Command> Command::from_raw(CommandCode code, std::uint32_t raw_value) {
  const CommandInfo& ci = info(code);
  if (ci.kind == ValueKind::flag && raw_value > 1) {
    return Error(ProtocolErrc::value_out_of_range,
                 fmt::format("{} takes 0 or 1, not {}", ci.name, raw_value));
  }
  return Command(code, raw_value);
}

Result<Command> Command::flag(CommandCode code, bool on) {
  if (info(code).kind != ValueKind::flag) {
    return Error(ProtocolErrc::value_out_of_range, fmt::format("{} does not take a 0/1 flag", name(code)));
  }
  return Command(code, on ? 1u : 0u);
}

Command Command::recv_timeout_ms(std::uint32_t ms) noexcept {
  return Command(CommandCode::set_can_recv_timeout, ms);
}

Result<Command> Command::current_limit(CommandCode code, double amperes) {
  if (info(code).kind != ValueKind::amperes_q24) {
    return Error(ProtocolErrc::value_out_of_range, fmt::format("{} does not take a current", name(code)));
  }
  AXON_TRY(q, to_q24(amperes));
  return Command(code, static_cast<std::uint32_t>(q));
}

double Command::value() const noexcept {
  if (info(code_).kind == ValueKind::amperes_q24) return from_q24(static_cast<std::int32_t>(raw_));
  return static_cast<double>(raw_);
}

std::string Command::to_string() const {
  const CommandInfo& ci = info(code_);
  if (ci.kind == ValueKind::amperes_q24) {
    return fmt::format("{}={}", ci.name, from_q24(static_cast<std::int32_t>(raw_)));
  }
  return fmt::format("{}={}", ci.name, raw_);
}

Result<Command> Command::parse(std::string_view text) {
  const auto eq = text.find('=');
  if (eq == std::string_view::npos) {
    return Error(ProtocolErrc::bad_command_text, fmt::format("'{}' has no '='", text.substr(0, 80)));
  }
  const std::string_view key = trim(text.substr(0, eq));
  const std::string_view val = trim(text.substr(eq + 1));
  const CommandInfo* ci = find_command(key);
  if (ci == nullptr) {
    return Error(ProtocolErrc::unknown_command, fmt::format("command name '{}'", key.substr(0, 80)));
  }
  if (ci->kind == ValueKind::amperes_q24) {
    AXON_TRY(a, parse_double(val));
    return current_limit(ci->code, a);
  }
  AXON_TRY(raw, parse_u32(val));
  return from_raw(ci->code, raw);
}

}  // namespace axon::blmc::protocol
