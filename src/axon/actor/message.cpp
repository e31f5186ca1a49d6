#include "axon/actor/message.hpp"

#include <fmt/format.h>

namespace axon::actor {

std::string command_binding(std::string_view actor) { return fmt::format("command.{}.#", actor); }
std::string command_key(std::string_view actor) { return fmt::format("command.{}", actor); }
std::string reply_key(std::string_view commander_id) { return fmt::format("reply.{}", commander_id); }

std::optional<MessageCode> parse_message_code(std::string_view text) noexcept {
  if (text.size() != 1) return std::nullopt;
  for (MessageCode c : {MessageCode::running, MessageCode::done, MessageCode::failed, MessageCode::error,
                        MessageCode::fatal, MessageCode::info, MessageCode::warning, MessageCode::debug})
    if (to_char(c) == text[0]) return c;
  return std::nullopt;
}

bool is_final(MessageCode c) noexcept {
  return c == MessageCode::done || c == MessageCode::failed || c == MessageCode::fatal;
}

std::string header_text(const Headers& headers, const std::string& key) {
  const auto it = headers.find(key);
  if (it == headers.end()) return {};
  const auto& v = it->second;
  if (const auto* s = std::get_if<std::string>(&v)) return *s;
  if (const auto* i = std::get_if<std::int64_t>(&v)) return std::to_string(*i);
  if (const auto* b = std::get_if<bool>(&v)) return *b ? "true" : "false";
  return {};
}

}  // namespace axon::actor
