// The message convention of the SDSS actor system (clu over AMQP 0-9-1), as axon speaks it
// (docs/actor.md): one topic exchange, commands routed by `command.<actor>`, replies by
// `reply.<commander_id>` or `reply.broadcast`, the reply's message code in a header. Plain values
// only: nothing here knows the broker client (amqp_link.hpp) or JSON.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <variant>

namespace axon::actor {

// The exchange clu's actors and clients declare by default (topic, auto-delete).
inline constexpr std::string_view kDefaultExchange = "sdss_exchange";
// Routing key of replies nobody asked for (status every N seconds, alerts).
inline constexpr std::string_view kBroadcastKey = "reply.broadcast";

// `command.<actor>.#`: what an actor's command queue is bound to.
std::string command_binding(std::string_view actor);
// `command.<actor>`: where a commander sends a command.
std::string command_key(std::string_view actor);
// `reply.<commander_id>`: where the replies to one commander go.
std::string reply_key(std::string_view commander_id);

// The reply's stage, one character in the `message_code` header.
enum class MessageCode : char {
  running = '>',  // accepted, working
  done = ':',     // finished well (final)
  failed = 'f',   // finished badly (final)
  error = 'e',    // something went wrong; the command goes on, or a final 'f' follows
  fatal = '!',    // the actor cannot go on (final)
  info = 'i',
  warning = 'w',
  debug = 'd',
};

// The code of a header value ("f"), or nothing for anything else.
std::optional<MessageCode> parse_message_code(std::string_view text) noexcept;
[[nodiscard]] inline char to_char(MessageCode c) noexcept { return static_cast<char>(c); }
// ':', 'f' and '!' end a command: no reply to it follows.
[[nodiscard]] bool is_final(MessageCode c) noexcept;

// An AMQP header value, as clu uses them: text, a number, a flag or nothing (null).
using HeaderValue = std::variant<std::monostate, std::string, std::int64_t, bool>;
using Headers = std::map<std::string, HeaderValue>;

// A header as text: strings as they are, numbers in decimal, flags as true/false; empty for null
// or absent (clu sends ids as strings; other clients send numbers).
std::string header_text(const Headers& headers, const std::string& key);

// A message as the broker hands it over or takes it.
struct Message {
  std::string routing_key;
  Headers headers;
  std::string correlation_id;
  std::string reply_to;
  std::string content_type = "text/json";  // what clu sends
  std::string body;
};

}  // namespace axon::actor
