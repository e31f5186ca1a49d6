#include "axon/actor/teller.hpp"

#include "axon/actor/command_line.hpp"
#include "axon/core/error.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <random>

namespace axon::actor {
namespace {

std::string unique_suffix() {
  std::random_device rd;
  return fmt::format("{}.{:08x}", ::getpid(), rd());
}

TellReply reply_of(const Message& m) {
  TellReply r;
  r.code = parse_message_code(header_text(m.headers, "message_code")).value_or(MessageCode::info);
  r.sender = header_text(m.headers, "sender");
  r.command_id = header_text(m.headers, "command_id");
  if (r.command_id.empty()) r.command_id = m.correlation_id;
  r.keywords = nlohmann::json::parse(m.body, nullptr, false);
  if (r.keywords.is_discarded() || !r.keywords.is_object()) r.keywords = nlohmann::json{{"text", m.body}};
  return r;
}

// What the link's thread hands to the caller's thread.
struct Inbox {
  std::mutex mutex;
  std::condition_variable changed;
  std::deque<TellReply> replies;
  bool connected = false;
  void push(TellReply r) {
    std::lock_guard lock(mutex);
    replies.push_back(std::move(r));
    changed.notify_all();
  }
};

}  // namespace

TellReply tell(const std::string& actor, const std::string& command_string, const TellOptions& options,
               const std::function<void(const TellReply&)>& on_reply) {
  const std::string suffix = unique_suffix();
  const std::string commander = fmt::format("{}.{}.{}", options.commander, suffix, actor);
  const std::string command_id = fmt::format("{}-{}", options.commander, suffix);
  LinkConfig config = options.link;
  config.queue = fmt::format("{}.{}_replies", options.commander, suffix);
  config.bindings = {reply_key(commander)};
  config.mandatory = true;
  config.backoff_max_s = 0.5;

  Inbox inbox;
  AmqpLink::Callbacks callbacks;
  callbacks.on_message = [&inbox, &command_id](Message m) {
    auto r = reply_of(m);
    if (r.command_id == command_id) inbox.push(std::move(r));
  };
  callbacks.on_returned = [&inbox, &actor, &command_id](Message) {
    TellReply r{MessageCode::failed, actor, command_id,
                nlohmann::json{{"error", fmt::format("no actor {:?} takes commands on this exchange", actor)}}};
    inbox.push(std::move(r));
  };
  callbacks.on_state = [&inbox](bool up, const std::string&) {
    std::lock_guard lock(inbox.mutex);
    inbox.connected = up;
    inbox.changed.notify_all();
  };
  AmqpLink link(config, std::move(callbacks));

  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(options.timeout_s);
  std::unique_lock lock(inbox.mutex);
  if (!inbox.changed.wait_until(lock, until, [&] { return inbox.connected; }))
    throw Exception(Error(CoreErrc::timeout, fmt::format("cannot reach the broker at {}:{} within {:g} s",
                                                         config.host, config.port, options.timeout_s)));
  Message m;
  m.routing_key = command_key(actor);
  m.headers = {{"commander_id", commander}, {"command_id", command_id}, {"internal", false}};
  m.correlation_id = command_id;
  m.reply_to = config.queue;
  m.body = command_body(command_string);
  link.publish(std::move(m));
  for (;;) {
    if (!inbox.changed.wait_until(lock, until, [&] { return !inbox.replies.empty(); }))
      throw Exception(Error(CoreErrc::timeout, fmt::format("no final reply from {} within {:g} s", actor, options.timeout_s)));
    TellReply r = std::move(inbox.replies.front());
    inbox.replies.pop_front();
    lock.unlock();
    if (on_reply) on_reply(r);
    if (is_final(r.code)) return r;
    lock.lock();
  }
}

}  // namespace axon::actor
