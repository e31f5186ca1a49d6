// C4gActor: the PC-side server of a C4G controller's open interface as an actor (docs/actor.md,
// keywords in docs/schema/c4g.json). The server answers the controller every cycle for the actor's
// whole life; commands put the built-in applications in force and take them out again through an
// apps::AppSwitch (the monitor answers when none is in force):
//
//   status                      the server (address, state, controller, cycles), each open axis's
//                               mode with its label, each arm's drives, the app in force with its
//                               phase and status line, the safety state
//   start APP [OPTION ...]      puts a built-in app in force, options as `axon c4g serve` names them
//                               (--file, --mode, --relative, --amplitude 1,2 ...; apps::AppConfig)
//   stop                        the app in force leaves its open modes, then the monitor answers
//                               (drive off when the controller does not get back to mode 0 in time)
//   stats                       counters and timing: receive-to-send and period figures, late
//                               cycles, wake-up and reply latency
//   driveoff                    asks the controller for drive off now (505)
//   reset                       clears a latched safety fault once the controller obeyed it
//   freeze | release            active freezing (500) from the next packet in mode 0 / its end
//
// and writes unsolicited keywords to every listener from a thread of its own (watch_period_s):
// mode changes, drives on and off, the app's milestones, its end (finished, stopped, refused with
// its error), the server's drive off and its being obeyed, late cycles (at most once per
// late_period_s while the counts rise), the session's state, and the status every status_period_s.
//
// Real time: nothing of the actor runs on the server's cycle thread. The watcher reads the
// switch's and the server's atomics and drains the apps' event queues; JSON and the bus stay on
// the actor's threads. The broker coming and going changes nothing for the controller.
//
// start, stop, driveoff, reset, freeze and release are exclusive: one at a time, a second is refused. The switch and
// the server must outlive the actor; the server must run the switch. The destructor closes the core
// (later commands are refused), stops the watcher and then the app in force cleanly (as `stop`);
// it never throws.
#pragma once

#include "axon/actor/actor_core.hpp"

#include <functional>
#include <memory>
#include <string>

namespace axon::c4g::apps {
class AppSwitch;
struct Event;
}
namespace axon::c4g::host {
class Server;
}

namespace axon::actor {

struct C4gActorOptions {
  double status_period_s = 10.0;  // 0: no periodic status
  double watch_period_s = 0.02;   // how often events, the safety state and the counters are read
  double late_period_s = 1.0;     // at most one `late` broadcast this often
  double drive_off_wait_s = 2.0;  // driveoff: how long to wait for the controller to obey
  // Each event the watcher drains from the switch (AppSwitch::drain, the only consumer), with its
  // text, oldest first, on the watcher's thread (never the cycle's): for a view beside the actor
  // (web::C4gView::add_event). Keep it short. Empty: none.
  std::function<void(const c4g::apps::Event&, const std::string&)> on_event{};
};

class C4gActor {
 public:
  C4gActor(ActorCore& core, c4g::apps::AppSwitch& apps, c4g::host::Server& server, C4gActorOptions options = {});
  ~C4gActor();
  C4gActor(const C4gActor&) = delete;
  C4gActor& operator=(const C4gActor&) = delete;

  // Closes the core, stops the watcher and the app in force (as `stop`); idempotent. What owns the
  // server calls this before it stops it.
  void shutdown() noexcept;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace axon::actor
