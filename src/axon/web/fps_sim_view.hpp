// web::FpsSimView: the fps page's data from a simulated focal plane in this process: the
// simulator's truth (where the arms physically are, each robot's state and status word, who
// collided), not what a host believes.
//
// The collision lock is the plane's: it is on while any robot has a collision flag set, and the
// robot that caused it is the first one seen collided (robots seen in the same update: the lowest
// id); it goes off when every flag is cleared (STOP_TRAJECTORY). Robot states: ready, moving,
// not-initialised (a datum unknown or the motors not calibrated), collided, offline (no power,
// booting), bootloader.
//
// Threading: the simulator's (its executor's thread): the owner calls publish() from a timer
// there; the Source hands the result to the web server's thread. Both references must outlive
// the view.
#pragma once

#include "axon/web/source.hpp"

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace axon::fps {
class FocalPlane;
}
namespace axon::fps::sim {
class FocalPlaneSimulator;
}

namespace axon::web {

struct FpsLock {
  bool locked = false;
  std::uint16_t robot = 0;        // who caused it
  std::string bus;                // its bus ("gw2/1")
  std::string arm;                // "alpha" or "beta"
  std::vector<std::uint16_t> collided;  // every robot with a collision flag, first seen first
  std::uint64_t count = 0;        // times the lock went on
};

class FpsSimView {
 public:
  FpsSimView(const fps::FocalPlane& plane, fps::sim::FocalPlaneSimulator& sim);
  ~FpsSimView();
  FpsSimView(const FpsSimView&) = delete;
  FpsSimView& operator=(const FpsSimView&) = delete;

  // What does not change (Source::set_info): every robot's base, orientation, arm lengths, bus and
  // sextant; the fiducials; the status word's documented bits; the state names.
  [[nodiscard]] std::string info_json() const;

  // Reads every robot now and updates the lock.
  void update();
  // The state after the last update(): {time_s, sync_line, moving, states, lock, robots: [{id, a, b,
  // s, st, fw, req, rej, col, ovf}, ...]} (angles in degrees, st the status word in hex).
  [[nodiscard]] std::string state_json() const;
  // Prometheus text: the simulator's counters, per robot and per bus (metrics_text.hpp).
  [[nodiscard]] std::string metrics() const;
  [[nodiscard]] const FpsLock& lock() const noexcept;

  // update(), then the state to `source`; the metrics too every `metrics_every`-th call (they are
  // larger and scraped rarely).
  void publish(Source& source, unsigned metrics_every = 10);

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace axon::web
