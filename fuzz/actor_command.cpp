// Fuzzes what an actor does with a command message from the bus: arbitrary bytes as the body (and a
// slice of them as the commander and command ids, as text or number headers) handed to an ActorCore
// with the built-in verbs and a verb that echoes its arguments. Nothing may crash or hang; every
// message ends in exactly one final reply to the right commander, the counters add up, a reply
// body is always a JSON object, and a command that splits is run with exactly the words split.
#include "axon/actor/actor_core.hpp"
#include "axon/actor/command_line.hpp"

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <cstddef>
#include <cstdint>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

namespace {

namespace actor = axon::actor;

void require(bool ok) {
  if (!ok) __builtin_trap();
}

struct Harness {
  std::mutex mutex;
  std::vector<actor::Message> replies;
  actor::ActorCore core{"fuzz", [this](actor::Message m) {
                          std::lock_guard lock(mutex);
                          replies.push_back(std::move(m));
                        }};
  Harness() {
    spdlog::set_level(spdlog::level::off);
    core.add(actor::Verb{"echo", "echo [WORD ...]", false, [](actor::Command& c) {
                           c.finish(actor::Keywords{{"words", c.args()}});
                         }});
  }
};

Harness& harness() {
  static auto* h = new Harness();
  return *h;
}

// The input: one flags byte, one length byte, that many bytes of commander id, the body.
actor::Message message_from(std::string_view bytes) {
  actor::Message m;
  m.routing_key = "command.fuzz";
  if (bytes.size() < 2) {
    m.body = std::string(bytes);
    return m;
  }
  const auto flags = static_cast<std::uint8_t>(bytes[0]);
  const std::size_t n = std::min<std::size_t>(static_cast<std::uint8_t>(bytes[1]) % 24, bytes.size() - 2);
  const std::string id(bytes.substr(2, n));
  if (flags & 1) m.headers["commander_id"] = id;
  if (flags & 2) m.headers["command_id"] = static_cast<std::int64_t>(flags);
  if (flags & 4) m.correlation_id = id;
  m.body = std::string(bytes.substr(2 + n));
  return m;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto& h = harness();
  const auto before = h.core.counters();
  const auto message = message_from(std::string_view(reinterpret_cast<const char*>(data), size));
  h.core.handle(message);
  h.core.wait_idle();
  std::vector<actor::Message> replies;
  {
    std::lock_guard lock(h.mutex);
    replies.swap(h.replies);
  }
  const auto after = h.core.counters();
  require(after.received == before.received + 1);
  const auto accepted = after.accepted - before.accepted;
  const auto refused = (after.not_json - before.not_json) + (after.malformed - before.malformed) +
                       (after.unknown - before.unknown) + (after.refused - before.refused) +
                       (after.oversized - before.oversized) + (after.busy - before.busy);
  require(accepted + refused == 1);

  const std::string commander = actor::header_text(message.headers, "commander_id");
  std::size_t finals = 0;
  for (const auto& r : replies) {
    require(r.routing_key == (commander.empty() ? std::string(actor::kBroadcastKey) : actor::reply_key(commander)));
    const auto code = actor::parse_message_code(actor::header_text(r.headers, "message_code"));
    require(code.has_value());
    if (actor::is_final(*code)) ++finals;
    const auto body = nlohmann::json::parse(r.body, nullptr, false);
    require(body.is_object());
    if (*code == actor::MessageCode::failed) require(body.contains("error"));
  }
  require(finals == 1);
  require(actor::is_final(*actor::parse_message_code(actor::header_text(replies.back().headers, "message_code"))));

  // The echo verb runs with the words split_command gives, nothing more, nothing less.
  const auto text = actor::command_string_of(message.body);
  if (!text) return 0;
  require(actor::command_string_of(actor::command_body(text.value())).value() == text.value());
  const auto line = actor::split_command(text.value());
  if (!line || line.value().verb != "echo") return 0;
  const auto body = nlohmann::json::parse(replies.back().body);
  require(body.at("words").get<std::vector<std::string>>() == line.value().args);
  return 0;
}
