// `axon sim blmc`: simulated motor driver boards, one per bus (can0, can1 ...), served over
// socketcand until Ctrl-C or --duration: the library's SimulatedBoard (blmc/sim/simulated_board.hpp)
// and a wait. --http serves the boards' truth (currents, positions, velocities, status) on the blmc
// page (docs/dashboard.md), sampled from the simulator at 50 Hz on the page's own thread.
#include "axon/blmc/sim/board_config.hpp"
#include "axon/blmc/sim/fault_plan.hpp"
#include "axon/blmc/sim/simulated_board.hpp"
#include "axon/core/config.hpp"
#include "axon/web/live_page.hpp"
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
  std::string http;  // HOST:PORT of the boards' live page (empty: none)
};

// ---- --http: the boards' page -------------------------------------------------------------------

constexpr auto kSamplePeriod = std::chrono::milliseconds(20);  // 50 Hz, the page's scope rate
constexpr unsigned kSamplesPerPublish = 5;                     // 10 updates a second

// What the simulator knows of board i, as a host's measurements would carry it.
blmc::host::Measurements sampled(const bsim::SimulatedBoardReport& r) {
  blmc::host::Measurements m;
  const auto now = core::steady_now();
  auto stamp = [now](auto& field, auto value) {
    field.value = value;
    field.at = now;
    field.count = 1;
  };
  stamp(m.status_byte, r.status_byte);
  stamp(m.current, blmc::protocol::MotorPair{r.current_a[0], r.current_a[1]});
  stamp(m.position, blmc::protocol::MotorPair{r.position_rev[0], r.position_rev[1]});
  stamp(m.velocity, blmc::protocol::MotorPair{r.velocity_krpm[0], r.velocity_krpm[1]});
  return m;
}

// The page (web::BlmcPage): its own thread samples every board each kSamplePeriod and publishes
// every kSamplesPerPublish samples; nothing runs on the boards' 1 kHz thread.
std::unique_ptr<web::BlmcPage> open_boards_page(const std::string& address, const bsim::SimulatedBoard& sim) {
  const unsigned boards = sim.boards();
  web::BlmcPageOptions po;
  po.server = web::server_address(address);
  for (unsigned i = 0; i < boards; ++i) po.view.boards.push_back({fmt::format("can{}", i), std::nullopt});
  po.view.sample_hz = 1000.0 / static_cast<double>(kSamplePeriod.count());
  po.view.command = "sim";
  po.title = fmt::format("blmc: {} simulated board{}", boards, boards == 1 ? "" : "s");
  po.period = kSamplePeriod;
  po.publish_every = kSamplesPerPublish;
  po.sample = [&sim](web::BlmcView& view, double t_s) {
    for (unsigned i = 0; i < sim.boards(); ++i) view.add_measurements(i, t_s, sampled(sim.report(i)));
  };
  return std::make_unique<web::BlmcPage>(std::move(po));
}

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
    const auto page = o.http.empty() ? nullptr : open_boards_page(o.http, sim);
    if (page) {
      std::printf("listening http %s\n", page->where().c_str());
      std::fflush(stdout);
    }
    co_await wait_for_stop(io, o.duration_s, set_on_signal);
    if (page) page->stop();  // its sampling reads the simulator
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
  b->add_option("--http", o->http, "serve the boards' live page (the simulator's truth), /api/state and /metrics on "
                                   "HOST:PORT (port 0: any; docs/dashboard.md)");
  b->callback([o, &global] { global.exit_code = run_sim_blmc(*o); });
}

}  // namespace axon::app
