// What an actor under test publishes, collected in order, with a wait for a condition (no broker).
#pragma once

#include "axon/actor/actor_core.hpp"

#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <vector>

namespace axon::actor::test {

struct Replies {
  std::mutex mutex;
  std::condition_variable changed;
  std::vector<Message> messages;

  std::function<void(Message)> sink() {
    return [this](Message m) {
      std::lock_guard lock(mutex);
      messages.push_back(std::move(m));
      changed.notify_all();
    };
  }
  // Waits (at most 20 s: a hung test fails instead of hanging) until some message satisfies `pred`.
  std::optional<Message> wait_for(const std::function<bool(const Message&)>& pred) {
    std::unique_lock lock(mutex);
    std::optional<Message> found;
    changed.wait_for(lock, std::chrono::seconds(20), [&] {
      for (const auto& m : messages)
        if (pred(m)) {
          found = m;
          return true;
        }
      return false;
    });
    return found;
  }
  // The final reply to command `id`.
  std::optional<Message> final_of(const std::string& id) {
    return wait_for([&](const Message& m) {
      const auto code = parse_message_code(header_text(m.headers, "message_code"));
      return header_text(m.headers, "command_id") == id && code && is_final(*code);
    });
  }
  std::vector<Message> of(const std::string& id) {
    std::lock_guard lock(mutex);
    std::vector<Message> out;
    for (const auto& m : messages)
      if (header_text(m.headers, "command_id") == id) out.push_back(m);
    return out;
  }
};

inline Message command(const std::string& text, const std::string& id, const std::string& commander = "tester") {
  Message m;
  m.routing_key = "command.test";
  m.headers = {{"commander_id", commander}, {"command_id", id}};
  m.correlation_id = id;
  m.body = command_body(text);
  return m;
}

inline char code_of(const Message& m) { return header_text(m.headers, "message_code").front(); }
inline nlohmann::json body_of(const Message& m) { return nlohmann::json::parse(m.body); }

}  // namespace axon::actor::test
