// FpsActor: the fiber positioners of a focal plane as an actor (docs/actor.md, keywords in
// docs/schema/fps.json). It adds the fps verbs to an ActorCore and drives an open fps::Client:
//
//   status                       every robot's state and arms, the lock, the command counters
//   goto ID ALPHA BETA [...]     moves one robot or several at once (ID `all`: every robot)
//   plan ID ALPHA BETA [...]     plans collision-free moves there (the others fold) and runs them;
//   plan FILE                    the same with a target file (fps::Client::plan_and_move)
//   discover                     GET_ID on every bus again, firmware and status of every robot
//   check                        GET_ID on every bus against the layout (fps::Client::check_layout)
//   cold                         the cold policy once, PLC temperatures to every robot
//   stop | abort                 aborts every robot (during a move this also locks the array)
//   unlock                       clears collision flags and the lock
//   backoff [ID ...]             moves robots out of a contact (fps::Client::back_off)
//   upgrade FILE [XX.YY.ZZ]      firmware of every robot through the PLC (fps::Client::upgrade_firmware)
//   friction [ID ...]            the friction trend (fps::Client::friction_survey, 9.4.2)
//   halltest ID [alpha|beta]     the hall sensor and motor test (fps::Client::hall_test, 9.4.3)
//   plc                          the PLC's relays and sensors (FpsActorOptions::plc_address)
//   power|gateway SEXTANT on|off a sextant's positioner power or gateway power (off: at any time)
//   sync pulse [HOLD_S]|high|low the sync line that starts loaded trajectories
//
// and writes unsolicited keywords to every listener: `locked`/`locked_by` and a `collision_alert`
// when the array locks (checked every FpsActorOptions::watch_period_s, 20 ms by default, on a
// thread of its own), the status every status_period_s, and `move_progress` to the commander of a
// running move every progress_period_s.
//
// goto, plan, discover, check, cold, unlock, backoff, upgrade, friction, halltest and sync are exclusive:
// a second one while one runs is refused (and power or gateway on while one runs). The client is called by
// one command at a time; a status asked during a move answers from the status read before it
// (keyword `stale`), with the move's progress. The collision safety stays the client's own
// (fps::Client: any collision report locks the array and aborts every robot), bus or no bus.
//
// The client must be open and outlive the actor; the constructor discovers the robots (throws
// axon::Exception as fps::Client::discover does). The destructor closes the core (later commands
// are refused), waits for the running ones and stops the watcher; it never throws.
#pragma once

#include "axon/actor/actor_core.hpp"

#include <functional>
#include <memory>
#include <string>

namespace axon::fps {
class Client;
enum class BusUse;  // fps/host/client.hpp
}

namespace axon::actor {

struct FpsActorOptions {
  double status_period_s = 10.0;   // 0: no periodic status
  double watch_period_s = 0.02;    // how often the lock is checked
  double progress_period_s = 1.0;  // move_progress while a goto runs
  std::string friction_history{};  // friction's CSV history ("": none, every arm a baseline)
  std::string plc_address{};       // the PLC at HOST[:PORT] for plc, power, gateway, sync ("": none)
  // Told what a command does with the buses, on the command's thread, before the command calls the
  // client (goto: moving; plan, discover, check, cold, unlock, backoff, upgrade, friction, halltest:
  // exclusive) and after it (shared), so that a reader beside the actor (a web view) keeps its own
  // traffic out of the way; the command waits for it. Empty: nobody is told.
  std::function<void(fps::BusUse)> on_bus_use{};
};

class FpsActor {
 public:
  FpsActor(ActorCore& core, fps::Client& client, FpsActorOptions options = {});
  ~FpsActor();
  FpsActor(const FpsActor&) = delete;
  FpsActor& operator=(const FpsActor&) = delete;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace axon::actor
