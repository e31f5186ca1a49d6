// web::C4gView: the c4g page's data for a server that answers one robot controller (`axon c4g
// serve`): per open axis its mode (code, name, the manual's label) and where the mode stands in
// the manual's START / CRUISE / END sequence; per arm the drives; the phase of the application in
// force (an OpenModeApp's waiting / running / fading / holding / idle / exiting / done / refused);
// the cycle timing as two histograms, receive-to-send (the PC's processing time, against the answer
// deadline) and the controller's inter-packet period; late and unanswered packets; the Safety
// layer's following-error and drive-off replies and the fault in force; per open axis the
// following error |D1 - D3| the cycle last measured and its peak since the axis entered its mode
// (Safety::following_error, relaxed atomics the cycle thread writes); the controller's errors as
// the packets showed them.
//
// Where the data comes from, and why nothing here touches the cycle thread:
//   - the modes and drives: the application's events (mode changes, drives on/off, exit from open,
//     initialization packets, silence), which the app queues lock-free on the cycle thread and
//     ServeSession::run() drains on its own thread. Only one consumer may drain them, so the view
//     is fed what run() hands to its event hook (ServeSession::Hooks::on_event -> add_event);
//   - everything else: the server's, the timing's and the Safety's atomics and histograms, and the
//     app's atomic phase, read when the state is built (state_json(), metrics()).
// Modes are known from the first packet on as mode 0 (the controller starts there) and after an
// initialization packet as its start-up modes; only changes are events, so a view attached to a
// session already in an open mode shows mode 0 until the next change.
//
// START / CRUISE / END (the manual's state-machine chapter): modes 1 and 2 have a soft switch (the
// start), shown as "start" for T1 + T2 + T3 after the mode appeared and "cruise" after; the other
// open modes run at once ("running"); a standby code, or an exit from open the PC asked while the
// arm is still in the mode, is "end". Mode 0 and 0' have no open phase ("").
//
// Threading: add_event(), state_json(), metrics() and publish() on one thread, run()'s (its hooks);
// the server and the app must outlive the view. Throws nothing but std::bad_alloc.
#pragma once

#include "axon/c4g/apps/app.hpp"
#include "axon/c4g/host/server.hpp"
#include "axon/c4g/protocol/soft_switch.hpp"
#include "axon/web/source.hpp"

#include <memory>
#include <string>

namespace axon::web {

struct C4gViewOptions {
  std::string command;                      // what the process runs, shown on the page ("serve --app stream")
  c4g::protocol::SwitchTimes soft_switch{};  // the controller's T1, T2, T3 (START of modes 1 and 2)
  std::size_t event_log = 60;               // the last events kept, in words, for the page (10 per axis of a six-axis arm)
};

class C4gView {
 public:
  C4gView(const c4g::apps::App& app, const c4g::host::Server& server, C4gViewOptions options = {});
  ~C4gView();
  C4gView(const C4gView&) = delete;
  C4gView& operator=(const C4gView&) = delete;

  // Each event of the app, in order, with its text (App::describe): ServeSession::Hooks::on_event.
  void add_event(const c4g::apps::Event& event, const std::string& text);

  // What does not change: the modes' table (code, name, label, description), the histograms' bins
  // and the metric bounds.
  [[nodiscard]] std::string info_json() const;
  // {t_s, command, app: {...}, server: {...}, axes: [...], arms: [...], counters: {...}, safety:
  // {...}, timing: {..., cycle_hist, period_hist}, controller_errors: {...}, events: [...]}
  // (docs/dashboard.md).
  [[nodiscard]] std::string state_json() const;
  // Prometheus text (metrics_text.hpp): axon_c4g_* (docs/dashboard.md).
  [[nodiscard]] std::string metrics() const;

  // The state to `source`; the metrics too every `metrics_every`-th call.
  void publish(Source& source, unsigned metrics_every = 10);

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

// The open interface's modes as the pages' info carries them: [{code, name, label, kind,
// description}, ...].
[[nodiscard]] std::string c4g_modes_json();

// The phase of an application as the page names it: an OpenModeApp's (for handover: the part now
// serving an open mode, else "waiting"), empty for an app without one (monitor, echo). Any thread.
[[nodiscard]] std::string c4g_app_phase(const c4g::apps::App& app);

}  // namespace axon::web
