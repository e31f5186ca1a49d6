#include "axon/actor/command_line.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace axon::actor {

Result<std::string> command_string_of(std::string_view body) {
  const auto j = nlohmann::json::parse(body, nullptr, false);
  if (j.is_discarded()) return Error(CoreErrc::invalid_argument, "the message body is not JSON");
  if (!j.is_object()) return Error(CoreErrc::invalid_argument, "the message body is not a JSON object");
  const auto it = j.find("command_string");
  if (it == j.end()) return Error(CoreErrc::invalid_argument, "the message body has no command_string");
  if (!it->is_string()) return Error(CoreErrc::invalid_argument, "command_string is not a string");
  return it->get<std::string>();
}

Result<CommandLine> split_command(std::string_view text) {
  std::vector<std::string> words;
  std::string word;
  bool in_word = false, quoted = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quoted && c == '\\' && i + 1 < text.size() && (text[i + 1] == '"' || text[i + 1] == '\\')) {
      word += text[++i];
    } else if (c == '"') {
      quoted = !quoted;
      in_word = true;
    } else if (!quoted && (c == ' ' || c == '\t' || c == '\n' || c == '\r')) {
      if (in_word) words.push_back(std::move(word));
      word.clear();
      in_word = false;
    } else {
      word += c;
      in_word = true;
    }
  }
  if (quoted) return Error(CoreErrc::invalid_argument, "unterminated quote in the command");
  if (in_word) words.push_back(std::move(word));
  if (words.empty()) return Error(CoreErrc::invalid_argument, "empty command");
  CommandLine line;
  line.verb = std::move(words.front());
  line.args.assign(std::make_move_iterator(words.begin() + 1), std::make_move_iterator(words.end()));
  return line;
}

std::string command_body(std::string_view text) { return nlohmann::json{{"command_string", text}}.dump(); }

}  // namespace axon::actor
