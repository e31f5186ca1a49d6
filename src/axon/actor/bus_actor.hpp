// BusActor: an ActorCore on a broker. It binds the queue `<name>_commands` to `command.<name>.#`
// on the exchange (as clu's actors do), hands every command to the core and publishes the core's
// replies. The broker may come and go (AmqpLink reconnects); replies written meanwhile go out on
// reconnection, so a command in flight when the broker died is reported when it is back.
//
//   axon::actor::BusActor actor({.name = "fps", .link = {.host = "10.0.0.5"}});
//   actor.core().add({"status", "status", false, [](axon::actor::Command& c) { c.finish({...}); }});
//
// Errors: the constructor throws axon::Exception when the link cannot start (not when the broker
// is away: it keeps trying). The destructor waits for running commands, then closes the link.
#pragma once

#include "axon/actor/actor_core.hpp"
#include "axon/actor/amqp_link.hpp"

#include <atomic>
#include <functional>
#include <memory>
#include <string>

namespace axon::actor {

struct BusActorConfig {
  std::string name = "axon";
  LinkConfig link;  // queue and bindings are set from the name
};

class BusActor {
 public:
  explicit BusActor(BusActorConfig config);
  ~BusActor();
  BusActor(const BusActor&) = delete;
  BusActor& operator=(const BusActor&) = delete;

  ActorCore& core() noexcept { return core_; }
  [[nodiscard]] bool connected() const noexcept;
  [[nodiscard]] LinkCounters link_counters() const;
  // Called on the link's thread when the broker connection comes or goes (quick, no waiting).
  void on_state(std::function<void(bool connected)> f);
  // Starts consuming commands (add the verbs first).
  void start();

 private:
  BusActorConfig config_;
  std::unique_ptr<AmqpLink> link_;  // declared first: destroyed last, after the core's commands ended
  ActorCore core_;
  std::atomic<AmqpLink*> live_{nullptr};  // what the core publishes through (replies before start() are dropped)
  std::function<void(bool)> on_state_;
};

}  // namespace axon::actor
