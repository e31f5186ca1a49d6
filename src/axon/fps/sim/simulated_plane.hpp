// axon::fps::sim::SimulatedPlane: a whole simulated focal plane in this process, for tests,
// examples and notebooks, without Asio. Every robot of a layout on its bus, one CAN@net gateway
// emulator per gateway of the layout listening on loopback, and the PLC emulator
// (FocalPlaneSimulator), all on an event loop of its own thread (core::LoopThread), so a
// fps::Client in the same process reaches it over real TCP as it would reach a site:
//
//   axon::fps::sim::SimulatedPlane plane("benchtop");
//   axon::fps::Client fps;
//   fps.open(plane.plane());   // the layout with the emulators' addresses
//
// Robots start calibrated and folded (beta 180; alpha 0, or random per the seed). Simulated time
// runs `time_scale` times faster than the wall clock (moves take less wall time; the protocol is
// the same). Errors (bind failures, an unknown layout or robot) throw axon::Exception. The
// destructor stops everything and never throws.
#pragma once

#include "axon/fps/host/client.hpp"
#include "axon/fps/layout/focal_plane.hpp"

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace axon::fps::sim {

struct SimulatedPlaneOptions {
  double time_scale = 10.0;   // simulated seconds per wall second
  std::uint64_t seed = 1;     // random start alphas, per-robot noise
  bool random_start = false;  // false: alpha 0, beta 180
  bool plc = true;            // run the PLC emulator (on loopback, any free port)
};

class SimulatedPlane {
 public:
  // `layout`: a layout file, `default` (500 robots) or `benchtop` (6) (fps/layout/layout_name.hpp).
  explicit SimulatedPlane(const std::string& layout = "benchtop", SimulatedPlaneOptions options = {});
  explicit SimulatedPlane(const FocalPlane& plane, SimulatedPlaneOptions options = {});
  ~SimulatedPlane();
  SimulatedPlane(const SimulatedPlane&) = delete;
  SimulatedPlane& operator=(const SimulatedPlane&) = delete;

  // The layout with each gateway's address where its emulator listens: what a Client opens.
  [[nodiscard]] const FocalPlane& plane() const noexcept;
  [[nodiscard]] std::map<std::uint16_t, std::string> gateway_addresses() const;
  // "cannet://127.0.0.1:PORT/N" for every bus of the layout.
  [[nodiscard]] std::vector<std::string> bus_specs() const;
  // The PLC emulator's HOST:PORT (empty without it).
  [[nodiscard]] std::string plc_address() const;

  // Where the simulated arms really are (not what the robot reports); empty for an unknown robot.
  [[nodiscard]] std::optional<Angles> arms(std::uint16_t id) const;
  // Collisions the simulator saw (neighbours and obstacles).
  [[nodiscard]] std::uint64_t collisions() const;
  // Rising edges of the sync line the PLC emulator drove (a start by the sync line is one).
  [[nodiscard]] std::uint64_t sync_edges() const;
  // Makes robot `id` report a collision of its beta arm now (it stops and sets the flag), whatever
  // the geometry.
  void inject_collision(std::uint16_t id);
  // Troubleshooting faults (interface document 9.4.2, 9.4.3) on one arm ('a' or 'b') of robot
  // `id`: extra friction of `level` on the collision margin's scale (0 removes it; moves collide
  // falsely while it exceeds the margin, and the current grows with it), or a hall sensor that
  // reads "stuck", a motor that is "dead", or "none" (PositionerModel::set_hall_fault). An unknown
  // robot, arm or fault throws axon::Exception.
  void set_friction_fault(std::uint16_t id, char arm, int level);
  void set_hall_fault(std::uint16_t id, char arm, const std::string& fault);

  // Stops the emulators and the simulator. Idempotent.
  void stop() noexcept;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace axon::fps::sim
