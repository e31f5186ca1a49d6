// `axon demo`, fps section: 20 simulated fiber positioners on one virtual bus, 20x faster than real
// time, found, inspected, moved and run through a trajectory by the host driver.
#include "demo_fps.hpp"

#include "can/virtual_bus.hpp"
#include "fps/host/array.hpp"
#include "fps/sim/simulator_config.hpp"
#include "run.hpp"

#include <fmt/format.h>

#include <chrono>
#include <map>

namespace axon::app {

namespace host = fps::host;
namespace protocol = fps::protocol;

asio::awaitable<void> demo_fps(asio::any_io_executor ex) {
  fmt::print("\naxon demo: fiber positioners (fps)\n\n");
  can::VirtualBusRegistry registry(ex);
  need(registry.add("fps0"));
  const std::vector<std::string> channels{"fps0"};
  auto config = need(fps::sim::SimulatorConfig::grid(20, channels));
  config.options.time_scale = 20;
  auto simulator = need(fps::sim::make_simulator(ex, config, registry));
  fmt::print("1. simulator: 20 robots (ids 1-20) on a hexagonal grid, virtual bus fps0, time x20;\n"
             "   calibrated, datums initialised, arms folded (alpha 0, beta 180)\n");

  auto bus = need(registry.open("fps0"));
  host::Array array(std::vector<can::Bus*>{bus.get()});
  const auto t0 = std::chrono::steady_clock::now();
  auto since = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };

  auto r1 = co_await array.discover();
  const auto report = need(std::move(r1));
  const auto& table = report.table;
  std::map<std::string, int> states;
  for (const auto& row : table.rows) ++states[row.state()];
  std::string state_text;
  for (const auto& [s, n] : states) state_text += fmt::format("{}{} {}", state_text.empty() ? "" : ", ", n, s);
  fmt::print("2. discover (GET_ID broadcast, then firmware and status of each): {} robots, {} ({:.2f} s)\n",
             table.rows.size(), state_text, since());
  if (!table.rows.empty() && table.rows.front().firmware && table.rows.front().status)
    fmt::print("   robot {}: firmware {}, {} status flags set, e.g. DATUM_ALPHA_INITIALIZED: {}\n", table.rows.front().id,
               table.rows.front().firmware->to_string(), table.rows.front().status->names().size(),
               table.rows.front().status->has(protocol::StatusBit::datum_alpha_initialized) ? "yes" : "no");
  std::map<std::uint16_t, host::ArmAngles> targets{{1, {90, 170}}, {2, {180, 160}}, {3, {270, 175}}, {4, {45, 150}}};
  const auto t_move = since();
  auto r2 = co_await array.goto_absolute(targets);
  const auto moves = need(std::move(r2));
  fmt::print("3. goto, robots 1-4 at once (12 deg/s simulated, precise approach), {:.2f} s:\n", since() - t_move);
  for (const auto& [id, res] : moves) {
    if (res) fmt::print("   robot {}: at alpha {:7.3f} beta {:7.3f}\n", id, res.value().reached.alpha, res.value().reached.beta);
    else fmt::print("   robot {}: {}\n", id, res.error().message());
  }

  const std::vector<protocol::ArmPoint> a5{{20, 1.0}, {40, 2.0}, {30, 3.0}}, b5{{170, 1.5}, {178, 3.0}};
  const std::vector<protocol::ArmPoint> a6{{-3, 1.0}, {60, 4.0}}, b6{};
  std::map<std::uint16_t, protocol::Trajectory> trajectories;
  trajectories.emplace(5, need(protocol::Trajectory::from_physical(a5, b5)));
  trajectories.emplace(6, need(protocol::Trajectory::from_physical(a6, b6)));
  const auto t_traj = since();
  auto r3 = co_await array.run_trajectories(trajectories);
  const auto run = need(std::move(r3));
  fmt::print("4. trajectories for robots 5 and 6 (upload with every reply checked, start by broadcast), {:.2f} s:\n",
             since() - t_traj);
  for (const auto& rr : run.robots)
    fmt::print("   robot {}: {}{}\n", rr.id, host::to_string(rr.state),
               rr.reached ? fmt::format(", ended at alpha {:.3f} beta {:.3f}", rr.reached->alpha, rr.reached->beta) : "");
  fmt::print("   {}\n", run.outcome);

  const auto totals = array.client_totals();
  const auto& s = simulator->stats();
  fmt::print("5. host: {} requests, {} replies, {} timeouts; simulator: {} frames processed, {} receive overflows, "
             "{} collisions\n",
             totals.sent, totals.replies, totals.timeouts, s.frames_processed, simulator->receive_overflows(),
             s.neighbour_collisions + s.obstacle_collisions);
  co_await array.close();
  bus->close();
  simulator->stop();
  fmt::print("   the same commands from a shell: `axon sim fps --gateway 127.0.0.1:19228 --time-scale 20` and\n"
             "   `axon fps --gateway 127.0.0.1:19228 status` (docs/fps-cli.md)\n");
}

}  // namespace axon::app
