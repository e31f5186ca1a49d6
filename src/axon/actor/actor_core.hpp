// ActorCore: what every axon actor does with a command, whatever its devices and wherever the
// messages come from (a broker through AmqpLink, a test directly). It reads the command from the
// message (command_line.hpp), finds the verb, refuses what conflicts with a running command, runs
// the verb's handler on a thread of its own and turns what the handler writes into replies with
// the convention's headers (message.hpp). Nothing a commander sends can crash it: a body that is
// not JSON, a malformed or unknown command and a handler that throws each end in a failure reply
// ('f', keyword `error` with the reason) and are counted. A flood cannot exhaust it either: a body
// over `max_body_bytes` is refused unparsed, a command beyond `max_running` running at once is
// refused as busy, and refusals are logged on the first and every 100th (all are counted).
//
// As clu's actors do, an accepted command's first reply is `>` (running, no keywords), then what its
// handler writes, then exactly one final reply; `get_schema` answers with the actor's keyword schema
// as a JSON string (keyword `schema`). An unknown verb gets one `f` that points to `help` (clu adds a
// `w` with the whole help first; one reply keeps a flood of unknown verbs from being amplified).
//
// Replies leave through the `publish` function given to the constructor, from the thread that
// writes them (the caller of handle() for refusals, a command's thread otherwise): it must be
// thread-safe (AmqpLink::publish is). Handlers must not throw past their command: what they throw
// becomes the command's failure reply.
#pragma once

#include "axon/actor/command_line.hpp"
#include "axon/actor/message.hpp"

#include <nlohmann/json.hpp>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace axon::actor {

// A reply's keywords: one JSON object, each member a keyword (docs/schema/<actor>.json).
using Keywords = nlohmann::json;

// One command being run: what its handler reads and writes. Thread-safe.
class Command {
 public:
  struct Id {
    std::string commander_id;  // empty: replies go to reply.broadcast
    std::string command_id;
  };
  Command(CommandLine line, Id id, std::function<void(Message)> publish, std::string sender);
  [[nodiscard]] const std::string& verb() const noexcept { return line_.verb; }
  [[nodiscard]] const std::vector<std::string>& args() const noexcept { return line_.args; }
  [[nodiscard]] const Id& id() const noexcept { return id_; }
  // A reply that does not end the command ('>', 'i', 'w', 'e', 'd'; a final code ends it).
  void write(MessageCode code, Keywords keywords);
  // The final reply: done (':') with these keywords, or failed ('f') with keyword `error`.
  void finish(Keywords keywords = Keywords::object());
  void fail(const std::string& reason, Keywords keywords = Keywords::object());
  [[nodiscard]] bool done() const noexcept { return done_; }

 private:
  CommandLine line_;
  Id id_;
  std::function<void(Message)> publish_;
  std::string sender_;
  std::mutex mutex_;
  std::atomic<bool> done_{false};
};

// How a verb sits with the other commands: `exclusive` verbs run one at a time (a second move while
// a move runs is refused, not queued); the others run whenever they come.
struct Verb {
  std::string name;
  std::string usage;  // "goto ID ALPHA BETA [ID ALPHA BETA ...]"
  bool exclusive = false;
  std::function<void(Command&)> run;
};

struct CoreCounters {
  std::uint64_t received = 0;
  std::uint64_t accepted = 0;
  std::uint64_t not_json = 0;    // bodies that are not a JSON object with a command_string
  std::uint64_t malformed = 0;   // command strings that do not split (empty, open quote)
  std::uint64_t unknown = 0;     // verbs the actor does not have
  std::uint64_t refused = 0;     // conflicting commands (an exclusive verb while one runs)
  std::uint64_t failed = 0;      // commands that ended with 'f' (their handler failed or threw)
  std::uint64_t oversized = 0;   // bodies over max_body_bytes, refused unparsed
  std::uint64_t busy = 0;        // commands refused because max_running were running (or no thread)
};

// What one actor takes on at once. A command's thread lives until its handler returns, so without
// a bound a commander flooding a slow verb would start threads until the process fails.
struct ActorLimits {
  std::size_t max_running = 32;            // commands running at once
  std::size_t max_body_bytes = 64 * 1024;  // a command line is a few hundred bytes at most
};

// The message that carries a reply: routing key reply.<commander_id> (reply.broadcast without a
// commander), headers message_code, commander_id, command_id, sender, internal; the command id as
// correlation id; the keywords as a JSON body.
Message reply_message(MessageCode code, const Keywords& keywords, const std::string& commander_id,
                      const std::string& command_id, const std::string& sender);

class ActorCore {
 public:
  ActorCore(std::string name, std::function<void(Message)> publish, ActorLimits limits = {});
  ~ActorCore();  // waits for the running commands
  ActorCore(const ActorCore&) = delete;
  ActorCore& operator=(const ActorCore&) = delete;

  [[nodiscard]] const std::string& name() const noexcept { return name_; }
  // Adds a verb (before the first command). `help`, `ping`, `version` and `get_schema` are built in.
  void add(Verb verb);
  // The keyword schema (JSON text) `get_schema` answers with, as keyword `schema` (a string).
  void set_schema(std::string schema);
  // One incoming command message. Returns once the command is refused or started.
  void handle(const Message& message);
  // An unsolicited reply to every listener (routing key reply.broadcast).
  void broadcast(MessageCode code, const Keywords& keywords);
  [[nodiscard]] CoreCounters counters() const;
  // Name of the exclusive command running, empty when none.
  [[nodiscard]] std::string busy_with() const;
  // Waits until no command runs.
  void wait_idle();
  // From now on every command is refused ("shutting down"); waits for the running ones. What owns
  // the verbs' devices calls this before it lets them go.
  void close();

 private:
  struct Running;
  void start(const Command::Id& who, CommandLine line, const Verb& verb);
  void refuse(const std::string& commander, const std::string& id, const std::string& reason, std::uint64_t CoreCounters::*counter);
  void reap();
  void add_builtins();

  std::string name_;
  std::function<void(Message)> publish_;
  ActorLimits limits_;
  std::vector<Verb> verbs_;
  std::string schema_;
  mutable std::mutex mutex_;
  CoreCounters counters_;
  std::string exclusive_running_;
  std::list<std::unique_ptr<Running>> running_;
  std::uint64_t next_id_ = 1;
  bool closed_ = false;
};

}  // namespace axon::actor
