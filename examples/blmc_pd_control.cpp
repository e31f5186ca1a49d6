// PD position control of both motors of a motor driver board, under safety limits: each motor
// moves from where it stands by its own distance (+0.5 and -0.25 motor revolutions) along a smooth
// 1 s ramp, then holds. The control law runs at 1 kHz on the library's real-time thread. The
// program checks that the following error stayed under 0.05 rev, that no safety stop happened and
// that each motor ends within 0.02 rev of its target; it exits 0 only then.
//
//   blmc_pd_control                    an in-process simulated board
//   blmc_pd_control socketcan:can0     a real board (any bus spec: socketcand://HOST:29536/can0 ...)
#include <axon/blmc/host/motor_board.hpp>
#include <axon/blmc/sim/simulated_board.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <exception>
#include <optional>
#include <string>

namespace blmc = axon::blmc;
using namespace std::chrono_literals;

constexpr std::array<double, 2> kMoveRev{0.5, -0.25};
constexpr double kRampS = 1.0, kKp = 8.0, kKd = 0.1;  // A/rev, A/(rev/s)
constexpr double kFollowingBoundRev = 0.05, kFinalBoundRev = 0.02;

int main(int argc, char** argv) try {
  std::optional<blmc::sim::SimulatedBoard> sim;
  std::string bus = argc > 1 ? argv[1] : "";
  if (bus.empty()) bus = sim.emplace().bus_spec();
  // A simulator shares this machine's cores with the loop: its timing checks get slack that a real
  // board's (10 ms stale data, 50 ms receive timeout) do not.
  blmc::MotorBoardOptions options;
  if (sim) options.recv_timeout_ms = 250;
  blmc::MotorBoard board(bus, options);
  board.enable();  // aligns the motors on the first enable after power-up
  std::printf("board on %s enabled\n", bus.c_str());

  // Shared with the real-time thread through atomics only (lock-free for double on x86-64).
  std::array<std::atomic<double>, 2> start{}, target{}, worst{};
  std::atomic<bool> started{false};
  blmc::ControlLaw law = [&](const blmc::ControlState& s) {
    if (!started.load(std::memory_order_relaxed)) {
      for (std::size_t k = 0; k < 2; ++k) start[k] = s.position_rev[k];
      started = true;
    }
    const double f = std::min(1.0, s.time_s / kRampS);
    const double shape = f * f * (3 - 2 * f), rate = 6 * f * (1 - f) / kRampS;  // smoothstep
    blmc::Command c;
    for (std::size_t k = 0; k < 2; ++k) {
      target[k] = start[k] + kMoveRev[k] * shape;
      worst[k] = std::max(worst[k].load(), std::abs(target[k] - s.position_rev[k]));
      c[k] = blmc::MotorCommand::pd(target[k], kMoveRev[k] * rate, kKp, kKd);
    }
    return c;
  };

  blmc::ControlSettings settings;
  settings.limits.max_current_a = 1.5;        // clamp
  settings.limits.max_velocity_krpm = 0.5;    // zero current above 500 rpm
  if (sim) settings.limits.stale_after = 200ms;
  const auto report = board.run_control(law, 2500ms, settings);
  const auto end = board.measurements();
  board.disable();

  const std::array<double, 2> final_rev{end.position.value.motor1, end.position.value.motor2};
  bool ok = !report.fault;
  std::printf("loop: %llu cycles, jitter p99 %.0f us, %llu overruns; safety: %s\n",
              static_cast<unsigned long long>(report.stats.cycles),
              std::chrono::duration<double, std::micro>(report.stats.jitter_p99).count(),
              static_cast<unsigned long long>(report.stats.overruns),
              report.fault ? report.fault_text.c_str() : "no fault");
  for (std::size_t k = 0; k < 2; ++k) {
    const double goal = start[k] + kMoveRev[k], miss = std::abs(final_rev[k] - goal);
    const bool good = worst[k] < kFollowingBoundRev && miss < kFinalBoundRev;
    std::printf("motor %zu: %+.4f -> %+.4f rev (target %+.4f): following error max %.4f rev (< %.2f), "
                "final error %.4f rev (< %.2f): %s\n",
                k + 1, start[k].load(), final_rev[k], goal, worst[k].load(), kFollowingBoundRev, miss, kFinalBoundRev,
                good ? "ok" : "FAILED");
    ok = ok && good;
  }
  std::printf("%s\n", ok ? "PASS" : "FAIL");
  return ok ? 0 : 1;
} catch (const std::exception& e) {
  std::fprintf(stderr, "blmc_pd_control: %s\n", e.what());
  return 1;
}
