// web::FpsHostView: the fps page's data as the host sees a focal plane it drives through a
// host::FocalPlaneArray: what it believes from the robots' replies, not where the arms are (that is
// web::FpsSimView's, the simulator's truth). Same info and state shapes as FpsSimView, so the same
// page draws either; the per-robot counters the host has not (requests a robot answered, its
// receive overflows) are left out, and the host's own counters (per bus) go to the metrics.
//
// What a robot shows:
//   - angles: its last GET_CURRENT_POSITION reply read by this view (absent until one came);
//   - status word and firmware: the latest the array's handle of the robot holds, whoever read
//     it (this view, discovery, a move's polling);
//   - state: offline while this view's last read of it failed (no reply) or before anything was
//     heard from it; bootloader, collided, moving (the array set it moving, or its status says a
//     move has not completed), not-initialised (datums unknown or motors not calibrated), ready.
// The lock is the array's (host::LockState): on after a collision report or a stop of every robot,
// naming the robot whose report caused it (none for a stop without a collision, then the reason
// says why), until unlock().
//
// Reading. read() asks every known robot once, concurrently: firmware (once), status and position
// with HostReading::all; the position only with HostReading::positions (during a move the move's
// own polling reads the status words already); nothing with HostReading::none (the view then shows
// what other operations read). The owner chooses the mode around operations that must not be
// disturbed (an upload, a discovery, which replaces robot handles), with set_reading().
//
// Threading: the array's executor (its io_context thread): read(), update(), publish() and run()
// there; the Source hands the result to the web server's thread. The array must outlive the view
// and every read() of it.
#pragma once

#include "axon/web/fps_sim_view.hpp"
#include "axon/web/source.hpp"

#include <chrono>
#include <memory>
#include <string>
#include <utility>  // before asio's awaitable.hpp, which uses std::exchange

#include <boost/asio/awaitable.hpp>

namespace axon::fps::host {
class FocalPlaneArray;
}

namespace axon::web {

enum class HostReading { all, positions, none };

// The host's lock: FpsLock plus why the array is locked (empty when not).
struct FpsHostLock : FpsLock {
  std::string reason;
};

class FpsHostView {
 public:
  explicit FpsHostView(fps::host::FocalPlaneArray& array);
  ~FpsHostView();
  FpsHostView(const FpsHostView&) = delete;
  FpsHostView& operator=(const FpsHostView&) = delete;

  // What does not change: the layout's robots (base, orientation, arms, bus, sextant), fiducials,
  // status bits, state names, and "view":"host".
  [[nodiscard]] std::string info_json() const;

  void set_reading(HostReading mode) noexcept;
  [[nodiscard]] HostReading reading() const noexcept;
  // True while a read() round is under way (its requests may still go out).
  [[nodiscard]] bool reading_now() const noexcept;
  // One round of reads of every known robot (see above).
  boost::asio::awaitable<void> read();
  // Rebuilds the rows and the lock from what was read (no I/O).
  void update();
  // {wall_s, moving, states, lock: {..., reason}, robots: [{id, a, b (null: never read), s, st, fw,
  // col, ago (seconds since this view's last reply from it, null: none), err}]}.
  [[nodiscard]] std::string state_json() const;
  // Prometheus text: axon_fps_host_* (robots by state, the lock, per bus the command clients'
  // counters and receive overflows, per robot collision reports and failed reads).
  [[nodiscard]] std::string metrics() const;
  [[nodiscard]] const FpsHostLock& lock() const noexcept;

  // update(), the state to `source`, the metrics every `metrics_every`-th call.
  void publish(Source& source, unsigned metrics_every = 10);
  // Until `alive` turns false: read() rounds at most every `read_period`, and publish() every
  // `publish_period` (rounds that wait for silent robots do not hold the page up).
  boost::asio::awaitable<void> run(Source& source, std::chrono::milliseconds publish_period,
                                   std::chrono::milliseconds read_period, std::shared_ptr<const bool> alive);

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace axon::web
