// Serving a robot controller with an application, as `axon c4g serve` does, from a program: the
// blocking face of the c4g host side.
//
//   axon::c4g::apps::StreamApp app(options);           // or any App: a built-in one or your own
//   axon::c4g::apps::ServeSession session(app, {.server = {.listen = {"127.0.0.1", 11000}}});
//   session.start();                                   // binds, answers packets from now on
//   const auto report = session.run();                 // until the app is done (or stop())
//   report.finished, report.stats.cyclic_packets ...   // plain values
//
// What a session assembles: the host::Server (its cycle thread answers every packet; the app runs
// inline there, under the real-time rules of app.hpp), an optional per-cycle CSV recorder (moni
// views), the loop that waits for the end (the app finished or failed, the controller ended the
// exchange or went silent after the app finished, a duration, stop()), the graceful stop (the app leaves its open modes; if the
// controller is not back in mode 0 within stop_timeout_s, drive off), and the final report. A
// safety fault of the server (stroke end, jump, following error...) ends run() too ("safety
// stop: ..."), once the controller has obeyed the drive off or the stop timeout passed.
//
// Threads: start(), run() and the destructor on the caller's thread; stop() from any thread (or a
// signal handler: it only sets an atomic). Hooks run on run()'s thread between polls.
// Errors: start() throws axon::Exception (a port in use, a pcap or CSV file that cannot be opened;
// the Error carries the errno or CoreErrc::invalid_argument). An app's own failure is not an
// exception: it ends run() with reason "application error" and the report carries the text.
// The destructor stops the server (graceful stop first if run() was interrupted); never throws.
#pragma once

#include "axon/c4g/apps/app.hpp"
#include "axon/c4g/host/server.hpp"
#include "axon/core/rotating_file.hpp"

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace axon::c4g::apps {

struct ServeOptions {
  host::ServerOptions server{};
  double duration_s = 0;          // 0: until the app finishes, fails, the controller ends, or stop()
  double stop_timeout_s = 5.0;    // graceful stop: wait this long for mode 0, then drive off
  std::string csv{};              // record every cycle into this CSV file (empty: none)
  int moni = 0;                   // the CSV's view: 0 every field, 19..24 the manual's monitoring types
  core::RotationLimits csv_rotation{};
  double status_interval_s = 0;   // Hooks::on_status every this many seconds (0: never)
  // Once the app has finished, keep answering until the controller ends the exchange (504) or
  // stops sending, so that its program's last cycles are answered too (else run() ends at once).
  bool until_controller_ends = false;
};

// The server's timing figures [s] (null-like: nominal_known false while the period is unknown).
struct ServeTiming {
  std::uint64_t cycles = 0;
  bool nominal_known = false;
  double nominal_period_s = 0, worst_cycle_time_s = 0;
  double inter_packet_min_s = 0, inter_packet_max_s = 0, inter_step_p50_s = 0;
  double jitter_min_s = 0, jitter_max_s = 0, jitter_min_percent = 0, jitter_max_percent = 0;
  double cycle_time_p50_s = 0, cycle_time_p99_s = 0, cycle_time_p999_s = 0, cycle_time_max_s = 0;
  std::uint64_t missed_deadlines = 0;
  double deadline_s = 0;
};

// The server's counters as plain values (host::ServerCounters, safety).
struct ServeStats {
  std::string controller;   // the session's controller HOST:PORT (empty: none came)
  std::uint64_t sessions = 0, foreign = 0;
  std::string last_foreign_source;
  std::uint64_t packets = 0, init_packets = 0, cyclic_packets = 0, protocol_errors = 0, safe_replies = 0;
  std::uint64_t refused_mode_changes = 0, controller_late = 0, freezes = 0, frozen_cycles = 0;
  std::string safety_fault = "none";
  // The controller's errors the packets showed, by the manual's names ("none", or "NAME xN, ...").
  std::string controller_errors = "none";
  std::uint64_t currents_clamped = 0;
  ServeTiming timing;
  // Recorders (csv_*: only with a CSV; pcap_*: only with a capture).
  bool csv = false, pcap = false;
  std::uint64_t csv_rows = 0, csv_rotations = 0, csv_write_errors = 0;
  std::uint64_t pcap_written = 0, pcap_rotations = 0, pcap_write_failures = 0;
};

// The server's counters and timing figures as they stand (any thread): what ServeReport::stats holds
// at the end of a run, for a server that runs on (the CSV figures are the session's, left unset).
ServeStats serve_stats(const host::Server& server);

struct ServeReport {
  std::string app;             // the app's name
  std::string reason;          // why run() ended: "application finished", "duration reached", "signal", ...
  std::uint64_t app_cycles = 0;
  bool finished = false;       // the app did its job
  std::string error;           // the app's error (empty: none)
  bool safety_fault = false;   // the server's Safety latched a fault other than our own drive off
  std::string app_summary, server_summary;
  std::string csv_path;
  int moni = 0;
  ServeStats stats;
  // 0 done, 1 the app failed, 4 a safety stop (exit_codes of the CLI).
  [[nodiscard]] int exit_code() const noexcept;
  // `axon c4g serve`'s final words: text lines, or one JSON document.
  [[nodiscard]] std::string text() const;
  [[nodiscard]] std::string json() const;
};

class ServeSession {
 public:
  struct Hooks {
    std::function<void(const Event&, const std::string& text)> on_event;  // the app's events, in words
    std::function<void(const std::string& controller)> on_session;        // a controller started the session
    std::function<void(const std::string& line)> on_status;               // every status_interval_s
    std::function<void()> on_poll;                                        // every poll (~20 ms)
    std::function<void()> on_stopping;                                    // once, as the graceful stop begins
    // Stop requests from outside (e.g. signals counted): 1 ends run() ("signal"), 2 or more during
    // the graceful stop asks for drive off at once.
    std::function<int()> interruptions;
  };

  // The app must outlive the session. Opens the CSV if asked (throws axon::Exception).
  ServeSession(App& app, ServeOptions options);
  ~ServeSession();
  ServeSession(const ServeSession&) = delete;
  ServeSession& operator=(const ServeSession&) = delete;

  // Binds and starts answering; throws axon::Exception.
  void start();
  // Blocks until the end (see above), stops gracefully, stops the server and returns the report.
  ServeReport run(const Hooks& hooks = {});
  // Asks run() to end (any thread, async-signal-safe).
  void stop() noexcept { stop_.store(true, std::memory_order_release); }
  // The server while the session lives (address, counters, freezing, safety).
  [[nodiscard]] host::Server& server();
  [[nodiscard]] std::string local_address() const;
  // A status line: app status, server state, cycle times, foreign datagrams.
  [[nodiscard]] std::string status_line() const;

 private:
  void pump(const Hooks& hooks);
  bool settled() const;
  void graceful_stop(const Hooks& hooks);
  [[nodiscard]] ServeReport report(std::string reason) const;

  App& app_;
  ServeOptions options_;
  struct Recorder;
  std::unique_ptr<Recorder> recorder_;
  std::unique_ptr<host::Server> server_;
  std::atomic<bool> stop_{false};
  std::optional<std::string> shown_peer_;
  bool stopped_ = false;
};

}  // namespace axon::c4g::apps
