#include "axon/actor/actor_core.hpp"

#include "axon/actor/command_line.hpp"
#include "axon/core/log.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <system_error>
#include <optional>
#include <thread>

namespace axon::actor {

Message reply_message(MessageCode code, const Keywords& keywords, const std::string& commander_id,
                      const std::string& command_id, const std::string& sender) {
  Message m;
  m.routing_key = commander_id.empty() ? std::string(kBroadcastKey) : reply_key(commander_id);
  m.headers["message_code"] = std::string(1, to_char(code));
  m.headers["commander_id"] = commander_id.empty() ? HeaderValue{} : HeaderValue{commander_id};
  m.headers["command_id"] = command_id.empty() ? HeaderValue{} : HeaderValue{command_id};
  m.headers["sender"] = sender;
  m.headers["internal"] = false;
  m.correlation_id = command_id;
  m.body = (keywords.is_object() ? keywords : Keywords::object()).dump();
  return m;
}

// ---- Command --------------------------------------------------------------------------------------

Command::Command(CommandLine line, Id id, std::function<void(Message)> publish, std::string sender)
    : line_(std::move(line)), id_(std::move(id)), publish_(std::move(publish)), sender_(std::move(sender)) {}

void Command::write(MessageCode code, Keywords keywords) {
  std::lock_guard lock(mutex_);
  if (done_) return;  // nothing follows a final reply
  if (is_final(code)) done_ = true;
  publish_(reply_message(code, keywords, id_.commander_id, id_.command_id, sender_));
}

void Command::finish(Keywords keywords) { write(MessageCode::done, std::move(keywords)); }

void Command::fail(const std::string& reason, Keywords keywords) {
  if (!keywords.is_object()) keywords = Keywords::object();
  keywords["error"] = reason;
  write(MessageCode::failed, std::move(keywords));
}

// ---- ActorCore ------------------------------------------------------------------------------------

struct ActorCore::Running {
  std::thread thread;
  std::atomic<bool> finished{false};
};

ActorCore::ActorCore(std::string name, std::function<void(Message)> publish, ActorLimits limits)
    : name_(std::move(name)), publish_(std::move(publish)), limits_(limits) {
  add_builtins();
}

ActorCore::~ActorCore() { wait_idle(); }

void ActorCore::add(Verb verb) {
  std::lock_guard lock(mutex_);
  std::erase_if(verbs_, [&](const Verb& v) { return v.name == verb.name; });
  verbs_.push_back(std::move(verb));
}

void ActorCore::set_schema(std::string schema) {
  std::lock_guard lock(mutex_);
  schema_ = std::move(schema);
}

void ActorCore::add_builtins() {
  verbs_.push_back(Verb{"ping", "ping", false, [](Command& c) { c.finish({{"text", "Pong."}}); }});
  verbs_.push_back(Verb{"version", "version", false, [](Command& c) { c.finish({{"version", "axon 0.1.0"}}); }});
  verbs_.push_back(Verb{"help", "help", false, [this](Command& c) {
                          std::vector<std::string> lines;
                          {
                            std::lock_guard lock(mutex_);
                            for (const auto& v : verbs_) lines.push_back(v.usage);
                          }
                          std::sort(lines.begin(), lines.end());
                          c.finish({{"help", lines}});
                        }});
  verbs_.push_back(Verb{"get_schema", "get_schema (the keyword schema, as JSON text)", false, [this](Command& c) {
                          std::string schema;
                          {
                            std::lock_guard lock(mutex_);
                            schema = schema_;
                          }
                          if (schema.empty()) return c.fail("this actor has no keyword schema");
                          c.finish({{"schema", schema}});
                        }});
}

void ActorCore::refuse(const std::string& commander, const std::string& id, const std::string& reason,
                       std::uint64_t CoreCounters::*counter) {
  std::uint64_t refusals = 0;
  {
    std::lock_guard lock(mutex_);
    ++(counters_.*counter);
    ++counters_.failed;
    refusals = counters_.not_json + counters_.malformed + counters_.unknown + counters_.refused + counters_.oversized +
               counters_.busy;
  }
  if (core::first_or_every(refusals, 100))
    spdlog::warn("{}: command refused: {} ({} refused so far; logged on the first and every 100th)", name_, reason,
                 refusals);
  else
    spdlog::debug("{}: command refused: {}", name_, reason);
  publish_(reply_message(MessageCode::failed, Keywords{{"error", reason}}, commander, id, name_));
}

void ActorCore::handle(const Message& message) {
  reap();
  const std::string commander = header_text(message.headers, "commander_id");
  std::string id = header_text(message.headers, "command_id");
  if (id.empty()) id = message.correlation_id;
  {
    std::lock_guard lock(mutex_);
    ++counters_.received;
    if (id.empty()) id = fmt::format("{}-{}", name_, next_id_++);
  }
  if (message.body.size() > limits_.max_body_bytes)
    return refuse(commander, id,
                  fmt::format("the message body is {} bytes, more than the {} a command may have", message.body.size(),
                              limits_.max_body_bytes),
                  &CoreCounters::oversized);
  auto text = command_string_of(message.body);
  if (!text) return refuse(commander, id, text.error().detail, &CoreCounters::not_json);
  auto line = split_command(text.value());
  if (!line) return refuse(commander, id, fmt::format("{}: {:?}", line.error().detail, text.value()), &CoreCounters::malformed);
  std::optional<Verb> verb;
  bool closed = false;
  {
    std::lock_guard lock(mutex_);
    closed = closed_;
    for (const auto& v : verbs_)
      if (v.name == line.value().verb) verb = v;
  }
  if (closed) return refuse(commander, id, "the actor is shutting down", &CoreCounters::refused);
  if (!verb) return refuse(commander, id, fmt::format("unknown command {:?} (help lists the commands)", line.value().verb),
                           &CoreCounters::unknown);
  spdlog::info("{}: command {:?} from {} ({})", name_, text.value(), commander.empty() ? "?" : commander, id);
  start(Command::Id{commander, id}, std::move(line).value(), *verb);
}

void ActorCore::start(const Command::Id& who, CommandLine line, const Verb& verb) {
  std::string conflict;
  std::size_t in_flight = 0;
  {
    std::lock_guard lock(mutex_);
    in_flight = running_.size();
    if (in_flight >= limits_.max_running) {
    } else if (verb.exclusive && !exclusive_running_.empty()) {
      conflict = exclusive_running_;
    } else {
      if (verb.exclusive) exclusive_running_ = verb.name;
      ++counters_.accepted;
    }
  }
  if (in_flight >= limits_.max_running)
    return refuse(who.commander_id, who.command_id,
                  fmt::format("busy: {} commands are running, the most this actor runs at once (try again later)",
                              in_flight),
                  &CoreCounters::busy);
  if (!conflict.empty())
    return refuse(who.commander_id, who.command_id,
                  fmt::format("{:?} refused: {:?} is running (stop it or wait for its end)", verb.name, conflict),
                  &CoreCounters::refused);
  // The exclusive slot is free again before the final reply leaves: a commander that sends the
  // next move on reading ':' is not refused.
  auto publish = [this, exclusive = verb.exclusive](Message m) {
    const auto code = parse_message_code(header_text(m.headers, "message_code"));
    if (code && is_final(*code)) {
      std::lock_guard lock(mutex_);
      if (exclusive) exclusive_running_.clear();
      if (*code != MessageCode::done) ++counters_.failed;
    }
    publish_(std::move(m));
  };
  auto command = std::make_shared<Command>(std::move(line), who, std::move(publish), name_);
  auto running = std::make_unique<Running>();
  try {
    running->thread = std::thread([command, run = verb.run, done = &running->finished] {
      try {
        command->write(MessageCode::running, Keywords::object());
        run(*command);
        if (!command->done()) command->finish();
      } catch (const std::exception& e) {
        command->fail(e.what());
      } catch (...) {
        command->fail("unknown failure");
      }
      *done = true;
    });
  } catch (const std::system_error& e) {  // the process is out of threads: this command fails, the actor goes on
    command->fail(fmt::format("busy: no thread to run it ({})", e.what()));
    return;
  }
  std::lock_guard lock(mutex_);
  running_.push_back(std::move(running));
}

void ActorCore::broadcast(MessageCode code, const Keywords& keywords) {
  publish_(reply_message(code, keywords, "", "", name_));
}

CoreCounters ActorCore::counters() const {
  std::lock_guard lock(mutex_);
  return counters_;
}

std::string ActorCore::busy_with() const {
  std::lock_guard lock(mutex_);
  return exclusive_running_;
}

void ActorCore::reap() {
  std::list<std::unique_ptr<Running>> done;
  {
    std::lock_guard lock(mutex_);
    for (auto it = running_.begin(); it != running_.end();) {
      if ((*it)->finished) done.splice(done.end(), running_, it++);
      else ++it;
    }
  }
  for (auto& r : done) r->thread.join();
}

void ActorCore::close() {
  {
    std::lock_guard lock(mutex_);
    closed_ = true;
  }
  wait_idle();
}

void ActorCore::wait_idle() {
  for (;;) {
    std::list<std::unique_ptr<Running>> all;
    {
      std::lock_guard lock(mutex_);
      all.swap(running_);
    }
    if (all.empty()) return;
    for (auto& r : all) r->thread.join();
  }
}

}  // namespace axon::actor
