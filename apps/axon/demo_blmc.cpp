// `axon demo`, blmc part: a simulated dual motor driver board on the in-process virtual bus, both
// motors under PD control at 1 kHz in the real-time ControlLoop following a sine; then the
// tracking error, the loop's timing and the board's state after the motors were disabled.
#include "axon/blmc/host/board.hpp"
#include "axon/blmc/host/control_run.hpp"
#include "axon/blmc/host/motor_session.hpp"
#include "axon/blmc/sim/runner.hpp"
#include "axon/can/virtual_bus.hpp"
#include "axon/core/wakeup.hpp"
#include "demo_parts.hpp"
#include "run.hpp"

#include <fmt/format.h>

namespace axon::app {
namespace {

namespace bh = blmc::host;
namespace bsim = blmc::sim;
using namespace std::chrono_literals;

constexpr double kAmplitudeRev = 0.5, kFrequencyHz = 1.0, kRunS = 3.0;

double blmc_us(core::Duration d) { return std::chrono::duration<double, std::micro>(d).count(); }

// The run's options: the library's defaults, except the stale-data limit. The simulated board
// ticks on this process's event-loop thread, which a busy machine can hold for longer than the
// 10 ms a real board's data may age; a hardware loop keeps the default.
bh::ControlOptions demo_options() {
  bh::ControlOptions o;
  o.limits.stale_after = 100ms;
  o.duration = std::chrono::duration_cast<core::Duration>(std::chrono::duration<double>(kRunS));
  o.refresh = 20ms;
  return o;
}

}  // namespace

asio::awaitable<int> demo_blmc(asio::any_io_executor ex, std::function<void(std::function<void()>)> set_on_signal) {
  fmt::print("\naxon demo: blmc, a dual brushless motor driver board at 1 kHz\n\n");
  can::VirtualBusRegistry registry(ex);
  need(registry.add("can0"));
  bsim::Runner runner(ex);
  auto* board_sim = need(runner.add(bsim::BoardConfig{}, {}, registry, "can0"));
  runner.start();
  auto bus = need(registry.open("can0"));
  bh::Board board(*bus);
  fmt::print("1. simulated board on the virtual bus can0 (motor physics, alignment, receive timeout)\n");

  fmt::print("2. enable and align, then PD control of both motors (kp 10 A/rev, kd 0.1 A/(rev/s)), a {:g} rev {:g} Hz sine, {:g} s\n",
             kAmplitudeRev, kFrequencyHz, kRunS);
  const bh::PdGains gains{10.0, 0.1};
  const bh::PdTarget sine{true, kAmplitudeRev, kFrequencyHz, 0.0};
  const std::array<bh::PdTarget, 2> targets{sine, sine};
  bool stop = false;
  set_on_signal([&stop, &board] {
    stop = true;
    board.interrupt();  // ends a wait for the alignment at once, and the run
  });
  // Every way out of the body (its end, a fault, an exception, a failed enable) leaves the motors
  // with zero current and disabled: the library's MotorSession.
  const bh::ControlOptions options = demo_options();
  const std::function<asio::awaitable<Result<bh::PdRun>>()> body = [&]() -> asio::awaitable<Result<bh::PdRun>> {
    bh::ControlHooks none;
    auto r = co_await bh::run_pd(board, gains, targets, options, std::move(none), 300ms);
    co_return r;
  };
  auto run = co_await bh::with_motors_enabled<Result<bh::PdRun>>(board, body);
  set_on_signal([] {});
  co_await core::sleep_for(50ms);
  const auto status = board_sim->status();
  runner.stop();
  bus->close();
  need(std::move(run.enable));
  need(std::move(run.disable));
  const auto pd = need(std::move(*run.value));
  const auto& st = pd.control.stats;
  const auto& fault = pd.control.fault;

  fmt::print("\n3. result\n");
  for (int k = 0; k < 2; ++k) {
    const auto& t = pd.tracking[static_cast<std::size_t>(k)];
    fmt::print("   motor {}: tracking error rms {:.4f} rev, max {:.4f} rev ({} samples)\n", k + 1, t.rms_rev(),
               t.max_abs_error_rev, t.samples);
  }
  fmt::print("   loop: {} cycles, period mean {:.1f} us, jitter p50 {:.0f} us p99 {:.0f} us max {:.0f} us, {} overruns, {} missed\n",
             st.cycles, blmc_us(st.period_mean), blmc_us(st.jitter_p50), blmc_us(st.jitter_p99), blmc_us(st.jitter_max),
             st.overruns, st.missed);
  fmt::print("   safety: {}\n", fault ? fault->fault.describe() : std::string("no fault"));
  fmt::print("   after the run: system {}, motor 1 {}, motor 2 {}\n", status.system_enabled ? "ENABLED" : "disabled",
             status.motor1_enabled ? "ENABLED" : "disabled", status.motor2_enabled ? "ENABLED" : "disabled");
  const bool safe = !status.system_enabled && !status.motor1_enabled && !status.motor2_enabled;
  if (stop) fmt::print("   stopped early by {}: motors disabled\n", signal_name(received_stop_signal().load()));
  co_return (!fault && safe) ? exit_code_value::ok : exit_code_value::failed;
}

}  // namespace axon::app
