// `axon sim blmc`: simulated motor driver boards, one per bus (can0, can1 ...), served over
// socketcand until Ctrl-C or --duration: the library's SimulatedBoard (blmc/sim/simulated_board.hpp)
// and a wait.
#include "axon/blmc/sim/board_config.hpp"
#include "axon/blmc/sim/fault_plan.hpp"
#include "axon/blmc/sim/simulated_board.hpp"
#include "axon/core/config.hpp"
#include "checks.hpp"
#include "commands.hpp"
#include "run.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <memory>

namespace axon::app {
namespace {

namespace bsim = blmc::sim;

struct SimBlmcOptions {
  unsigned boards = 1;
  std::string socketcand = "127.0.0.1:29536";  // loopback, socketcand's usual port
  std::string config;
  std::string fault_plan;
  double duration_s = 0;
  bool realtime = true;
};

void log_end(const bsim::SimulatedBoard& sim) {
  for (unsigned i = 0; i < sim.boards(); ++i) {
    const auto r = sim.report(i);
    spdlog::info("sim: can{}: status {}; IqRef {:g} {:g} A; {} frames in ({} malformed, {} ignored), {} out; bus load {:.1f} %",
                 i, r.status.to_string(), r.motors[0].iq_ref_a, r.motors[1].iq_ref_a, r.stats.frames_received,
                 r.stats.malformed, r.stats.ignored, r.stats.frames_sent, 100.0 * r.bus_load);
  }
  const auto rs = sim.runner_stats();
  spdlog::info("sim: {} ticks, {} schedule restarts, {} send errors", rs.ticks, rs.schedule_restarts, rs.send_errors);
}

int run_sim_blmc(const SimBlmcOptions& o) {
  bsim::SimulatedBoardOptions so;
  so.boards = o.boards;
  if (!o.config.empty()) so.config = need(bsim::BoardConfig::from_config(need(core::ConfigNode::load_file(o.config))));
  so.faults = need(bsim::load_fault_plans(o.fault_plan, o.boards));
  so.socketcand = o.socketcand;
  // Below the host's control loop (SCHED_FIFO 80): on one machine the host's deadline comes first.
  if (o.realtime) so.realtime.fifo_priority = 70;
  return run_command([&](asio::io_context& io, auto set_on_signal) -> asio::awaitable<int> {
    bsim::SimulatedBoard sim(so);
    std::printf("listening socketcand %s\n", sim.endpoint().c_str());
    std::fflush(stdout);
    std::vector<std::string> channels;
    for (unsigned i = 0; i < o.boards; ++i) channels.push_back(fmt::format("can{}", i));
    spdlog::info("sim: {} blmc board{} on {} (Ctrl-C to stop)", o.boards, o.boards == 1 ? "" : "s", fmt::join(channels, ", "));
    co_await wait_for_stop(io, o.duration_s, set_on_signal);
    sim.stop();
    log_end(sim);
    co_return 0;
  });
}

}  // namespace

void add_sim_blmc_command(CLI::App& sim_cmd, GlobalOptions& global) {
  auto o = std::make_shared<SimBlmcOptions>();
  auto* b = sim_cmd.add_subcommand("blmc", "simulated blmc motor driver boards, one per bus (can0, can1 ...)");
  b->add_option("--boards", o->boards, "number of boards (default 1)")->check(CLI::Range(1u, 64u));
  b->add_option("--socketcand", o->socketcand, "serve socketcand on HOST:PORT (default 127.0.0.1:29536; port 0: any)");
  b->add_option("--config", o->config, "board/motor parameters YAML (docs/blmc-simulator.md)");
  b->add_option("--fault-plan", o->fault_plan, "fault plan YAML (docs/blmc-simulator.md)");
  b->add_option("--duration", o->duration_s, "stop after this many seconds (default: until Ctrl-C)")->check(non_negative());
  b->add_flag("!--no-realtime", o->realtime, "do not ask for SCHED_FIFO 70 for the boards' 1 kHz loop");
  b->callback([o, &global] { global.exit_code = run_sim_blmc(*o); });
}

}  // namespace axon::app
