// AppSwitch: one server, many applications over its life. The server runs the switch for as long
// as it lives; the switch hands every cycle to the application in force (the monitor when none is)
// and lets other threads put an application in force, stop it and take it out again, between two
// cycles and without making the cycle thread allocate, lock or wait.
//
//   apps::AppSwitch sw;                                       // the monitor answers from the start
//   auto server = host::Server::start(sw, options).value();
//   sw.install(apps::make_app(config)).value();               // set up here, in force from the next cycle
//   sw.poll(*server);                                         // now and then: ends, refusals, stops
//   const auto ended = sw.stop(*server);                      // leaves the open modes, then the monitor again
//
// The hand-over. install() calls the new app's on_init with the last initialization packet on the
// caller's thread (so its setup may allocate there) and publishes it with one atomic store. The
// cycle thread reads that pointer once per call (setup, step, silence) and marks each call in an
// epoch counter (odd while inside); an app taken out is destroyed only once the counter shows the
// cycle thread outside any call that may have read it. The only lock the cycle thread takes is the
// one for the initialization packet copy (once per packet, as the Server itself does).
//
// The stop is ServeSession's graceful stop, as a state machine that poll() advances (so a thread
// that watches the switch and a thread that waits for a stop may share the work): the app is asked
// to leave its open modes (App::request_stop); once the controller shows every axis in mode 0 (or
// went silent, or obeyed a drive off) the monitor takes over; after
// stop_timeout_s without that the server is asked for drive off (505), and drive_off_wait_s later
// the app is taken out whatever the controller shows. The monitor, the echo and an open-mode app
// still waiting for its mode hold no mode and go at once. An app that finishes on its own is taken out
// at once (it already left its mode); one that refuses is stopped the same way, with drive off at
// once when the robot depends on it every cycle (App::drive_off_on_error, as ServeSession does).
//
// Threads: the server's cycle thread calls the App interface; every other member may be called
// from any other thread (an internal mutex serialises them; they never wait for the cycle thread
// except stop(), which polls until the stop is over). Events: drain() hands over the switch's own
// (modes per axis, drives per arm, initialization packets, silence) and the milestones of the
// application in force (its notes and exit requests), each in words.
#pragma once

#include "axon/c4g/apps/app.hpp"
#include "axon/c4g/apps/monitor.hpp"
#include "axon/core/error.hpp"

#include <array>
#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace axon::c4g::apps {

struct AppSwitchOptions {
  double stop_timeout_s = 5.0;    // leaving the open modes: then drive off
  double drive_off_wait_s = 1.0;  // after asking for drive off: then the app goes anyway
};

// How an application's time in force ended (poll() and stop() return it once).
struct AppEnded {
  std::string app;           // its name
  std::string reason;        // "finished", "stopped", "refused"
  bool finished = false;     // it did its job
  std::string error;         // why it refused (empty: it did not)
  bool left_cleanly = true;  // the controller was back in mode 0 (or silent) before it went
  bool drive_off = false;    // the switch asked the server for drive off to end it
  std::string summary;       // App::summary() at the end
  double in_force_s = 0;     // from install() to the end
  std::uint64_t serial = 0;  // which install (1 for the first app): the same end seen twice has one serial
};

// The application in force as the control side sees it.
struct AppInForce {
  std::string app = "monitor";  // "monitor" when none was installed
  bool installed = false;       // false: the switch's own monitor
  std::string phase;            // OpenModeApp's phase ("waiting", "running", ...), else empty
  std::string status;           // App::status()
  bool stopping = false;        // a stop is under way
  std::string error;            // its error so far
  std::uint64_t cycles = 0;     // cycles it has served
  double in_force_s = 0;
};

class AppSwitch final : public App {
 public:
  explicit AppSwitch(AppSwitchOptions options = {});
  ~AppSwitch() override;
  AppSwitch(const AppSwitch&) = delete;
  AppSwitch& operator=(const AppSwitch&) = delete;

  [[nodiscard]] std::string_view name() const noexcept override { return "switch"; }
  // The status and summary of the app in force (any thread but the cycle thread).
  [[nodiscard]] std::string status() const override;
  [[nodiscard]] std::string summary() const override;

  // ---- control side: any thread but the cycle thread ----
  // Puts `app` in force from the next cycle. Refused (invalid_argument) while another one is in
  // force: stop it first. A null app is refused too.
  Result<void> install(std::unique_ptr<App> app);
  // Starts the graceful stop of the app in force (no-op when none, or already stopping).
  void begin_stop();
  // Advances what is under way (an end, a refusal, a stop) and returns how an app's time ended,
  // once, when it did. Quick: never waits. `server` is the one that runs this switch.
  std::optional<AppEnded> poll(host::Server& server);
  // begin_stop() and poll() every 10 ms (calling `between` after each) until the app is out;
  // nullopt when none was in force. When another thread's poll() took it out first, its end is
  // returned here too (same serial).
  std::optional<AppEnded> stop(host::Server& server, const std::function<void()>& between = {});
  [[nodiscard]] AppInForce in_force() const;
  [[nodiscard]] bool has_app() const;
  // Events since the last call, oldest first per source, each in words (App::describe).
  struct Described {
    Event event;
    std::string app;   // who reported it: "switch" for modes, drives, init packets and silence
    std::string text;
  };
  std::vector<Described> drain();
  // The last initialization packet and its axis map (nullopt until one came).
  [[nodiscard]] std::optional<std::pair<protocol::InitPacket, protocol::AxisMap>> init_packet() const;
  // The last packet's view: each open axis's mode, each arm's drives (any thread; relaxed).
  [[nodiscard]] std::vector<std::int32_t> modes() const;
  [[nodiscard]] bool drives_on(std::size_t arm) const noexcept;
  // Apps installed since construction.
  [[nodiscard]] std::uint64_t installs() const noexcept { return installs_.load(std::memory_order_relaxed); }

 protected:
  void setup(const protocol::InitPacket& init, const protocol::AxisMap& axes) override;
  void step(const host::CycleContext& ctx, host::ReplyBuilder& reply) override;
  void silence() noexcept override;

 private:
  using Clock = std::chrono::steady_clock;
  enum class Stage : std::uint8_t { serving, leaving, driving_off };
  struct Epoch;  // marks a cycle-thread call in epoch_

  // The app the cycle thread serves now (the monitor when none); cycle thread only.
  App& serving() noexcept;
  // Takes the app out (control mutex held): the monitor again, the app destroyed once unused.
  AppEnded take_out(std::string reason, bool left_cleanly);
  void wait_unused() const noexcept;
  bool settled(const host::Server& server) const;
  void drain_app_locked(std::vector<Described>& out);

  AppSwitchOptions options_;
  MonitorApp monitor_;
  std::atomic<App*> current_{nullptr};      // the installed app; nullptr: the monitor
  std::atomic<std::uint64_t> epoch_{0};     // odd while the cycle thread is inside a call
  std::atomic<std::uint64_t> installs_{0};
  std::array<std::atomic<bool>, protocol::kMaxArms> shown_drives_{};

  mutable std::mutex init_mutex_;  // what follows; the cycle thread takes it once per init packet
  std::optional<protocol::InitPacket> init_;
  protocol::AxisMap map_{};
  std::uint64_t init_generation_ = 0;

  mutable std::mutex control_;  // the control side's state below
  std::unique_ptr<App> app_;    // the app in force (what current_ points to)
  Clock::time_point since_{};
  Stage stage_ = Stage::serving;
  Clock::time_point deadline_{};
  bool drive_off_asked_ = false;
  std::vector<Described> leftover_;  // the events of an app taken out before they were drained
  std::optional<AppEnded> last_ended_;
};

}  // namespace axon::c4g::apps
