// Homing on the encoder index: each motor turns slowly (a ramped position target under a soft,
// current-limited PD) until the board reports the index mark of its encoder, then holds there.
// The position of the mark is the motor's offset: joint zero = offset (+ your mechanism's own).
// With the simulated board the marks sit at 0.3 and 0.7 rev (set below) and the program checks
// that homing found them within 0.001 rev; on a real board it checks that each motor found its
// mark within one revolution of where it started. It exits 0 only then.
//
//   blmc_homing                    an in-process simulated board
//   blmc_homing socketcan:can0     a real board (any bus spec: socketcand://HOST:29536/can0 ...)
#include <axon/blmc/host/motor_board.hpp>
#include <axon/blmc/sim/simulated_board.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <exception>
#include <optional>
#include <string>

namespace blmc = axon::blmc;
using namespace std::chrono_literals;

constexpr std::array<double, 2> kSimulatedIndexRev{0.3, 0.7};
constexpr double kSimulatedToleranceRev = 0.001;

int main(int argc, char** argv) try {
  std::optional<blmc::sim::SimulatedBoard> sim;
  std::string bus = argc > 1 ? argv[1] : "";
  if (bus.empty()) {
    blmc::sim::SimulatedBoardOptions o;
    for (std::size_t k = 0; k < 2; ++k) o.config.motors[k].index_offset_rev = kSimulatedIndexRev[k];
    bus = sim.emplace(o).bus_spec();
  }
  // A simulator shares this machine's cores with the loop: its timing checks get slack that a real
  // board's (10 ms stale data, 50 ms receive timeout) do not.
  blmc::MotorBoardOptions options;
  if (sim) options.recv_timeout_ms = 250;
  blmc::MotorBoard board(bus, options);
  board.enable();
  std::printf("board on %s enabled\n", bus.c_str());

  blmc::host::HomingOptions homing;
  homing.speed_rev_s = 0.5;     // positive direction, half a turn per second
  homing.max_current_a = 0.5;   // homing never pushes harder than this
  homing.max_travel_rev = 1.2;  // a mark comes once per revolution
  blmc::ControlSettings settings;  // the safety limits apply as in any control
  if (sim) settings.limits.stale_after = 200ms;
  const auto report = board.home(homing, settings, 10s);
  board.disable();

  bool ok = !report.control.fault && report.all_found;
  if (report.control.fault) std::printf("safety stop: %s\n", report.control.fault_text.c_str());
  for (std::size_t k = 0; k < 2; ++k) {
    const auto& m = report.motors[k];
    const bool found = m.state == blmc::host::MotorHoming::State::found;
    const bool good = found && (sim ? std::abs(m.index_rev - kSimulatedIndexRev[k]) < kSimulatedToleranceRev
                                    : std::abs(m.index_rev - m.start_rev) <= 1.0);
    if (found)
      std::printf("motor %zu: started at %+.5f rev, index (offset) at %+.5f rev%s: %s\n", k + 1, m.start_rev,
                  m.index_rev, sim ? (" (simulated mark at " + std::to_string(kSimulatedIndexRev[k]) + ")").c_str() : "",
                  good ? "ok" : "FAILED");
    else
      std::printf("motor %zu: %s, no index within %.1f rev: FAILED\n", k + 1, blmc::host::to_string(m.state),
                  homing.max_travel_rev);
    ok = ok && good;
  }
  std::printf("%s\n", ok ? "PASS" : "FAIL");
  return ok ? 0 : 1;
} catch (const std::exception& e) {
  std::fprintf(stderr, "blmc_homing: %s\n", e.what());
  return 1;
}
