// blmc control loop benchmark: the ControlLoop at 1 kHz over 1, 2 and 4 simulated boards
// (src/axon/blmc/sim, one board per virtual bus, as in service), each running a PD position hold.
//
// Reports per board count: loop period jitter (p50/p99/max of |period - 1 ms|), overruns and
// missed deadlines, and process CPU per board (the simulator's 1 kHz tick included). Latency: the
// time from a board's velocity frame (the frame that completes the data the controller uses) to
// the IqRef frame the loop sends in answer, with Pacing::measurements (cycle started by the
// burst) and Pacing::clock (the default, where the phase between board and loop adds up to one
// period). Baseline: the bare virtual-bus round trip (frame out, peer answers, frame back) on one
// io thread, measured in the same run. ratio = latency p50 (measurement pacing) / round trip p50.
//
//   blmc_loop [--seconds S]   (default 2 s per configuration; the whole run stays under ~20 s)
#include "axon/blmc/host/board.hpp"
#include "axon/blmc/host/control_loop.hpp"
#include "axon/blmc/host/pd_controller.hpp"
#include "axon/blmc/sim/runner.hpp"
#include "axon/can/virtual_bus.hpp"
#include "axon/core/log.hpp"
#include "axon/core/wakeup.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/io_context.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <ctime>
#include <memory>
#include <vector>

namespace {

using namespace axon;
using namespace std::chrono_literals;
namespace asio = boost::asio;
namespace bh = blmc::host;

double us(core::Duration d) { return std::chrono::duration<double, std::micro>(d).count(); }

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
}

double cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

struct RunResult {
  unsigned boards = 0;
  bh::LoopStats stats;
  std::vector<double> latency_us;
  double cpu_pct_per_board = 0;
  bool faulted = false;
  std::string fault;
};

asio::awaitable<void> run_config(asio::io_context& io, unsigned n, bh::Pacing pacing, double seconds, RunResult& out) {
  const asio::any_io_executor ex = io.get_executor();
  can::VirtualBusRegistry registry(ex);
  blmc::sim::Runner runner(ex);
  std::vector<std::unique_ptr<can::Bus>> buses;
  std::vector<std::unique_ptr<bh::Board>> boards;
  std::vector<core::TimePoint> last_velocity(n);
  blmc::sim::BoardConfig cfg;
  cfg.alignment_time = 100ms;
  for (unsigned i = 0; i < n; ++i) {
    const std::string name = fmt::format("can{}", i);
    (void)registry.add(name).value();
    buses.push_back(registry.open(name).value());
    (void)runner.add(cfg, {}, registry, name).value();
    boards.push_back(std::make_unique<bh::Board>(*buses.back()));
    boards.back()->set_tap([&out, &last_velocity, i](const can::Frame& f, bool outgoing) {
      const auto now = core::SteadyClock::instance().now();
      if (!outgoing && f.id() == 0x040) {
        last_velocity[i] = now;
      } else if (outgoing && f.id() == 0x005 && i == 0 && last_velocity[0] != core::TimePoint{}) {
        out.latency_us.push_back(us(now - last_velocity[0]));
        last_velocity[0] = {};
      }
    });
  }
  runner.start();
  // Enable every board at once (alignment and the 1 Hz status dominate).
  unsigned ready = 0;
  for (auto& b : boards) {
    bh::Board* bp = b.get();
    asio::co_spawn(
        ex,
        [bp, &ready]() -> asio::awaitable<void> {
          auto r = co_await bp->enable();
          if (!r) fmt::print(stderr, "enable: {}\n", r.error().message());
          auto c = co_await bp->start_cyclic();
          if (!c) fmt::print(stderr, "start_cyclic: {}\n", c.error().message());
          ++ready;
        },
        asio::detached);
  }
  while (ready < n) co_await core::sleep_for(10ms);

  std::vector<bh::CyclicPort*> ports;
  for (auto& b : boards) ports.push_back(&b->port());
  bh::PdController pd(n, {5.0, 0.05}, {bh::PdTarget{}, bh::PdTarget{}});
  bh::LoopOptions lo;
  lo.pacing = pacing;
  lo.realtime = true;  // SCHED_FIFO if permitted (warns otherwise)
  bh::ControlLoop loop(ports, pd, {bh::SafetyLimits{}}, lo);
  out.latency_us.clear();
  const double cpu0 = cpu_seconds();
  const auto t0 = core::SteadyClock::instance().now();
  if (!loop.start()) co_return;
  while (loop.running() && core::SteadyClock::instance().now() - t0 < std::chrono::duration<double>(seconds)) {
    co_await core::sleep_for(20ms);
    bh::CycleRecord rec;
    while (loop.pop_record(rec)) {
    }
  }
  loop.stop();
  const double wall = std::chrono::duration<double>(core::SteadyClock::instance().now() - t0).count();
  out.cpu_pct_per_board = 100.0 * (cpu_seconds() - cpu0) / wall / n;
  out.boards = n;
  out.stats = loop.stats();
  if (auto f = loop.fault()) {
    out.faulted = true;
    out.fault = f->fault.describe();
  }
  for (auto& b : boards) {
    b->set_tap({});
    auto s = co_await b->stop_cyclic();
    (void)s;
    auto d = co_await b->disable();
    (void)d;
  }
  co_await core::sleep_for(5ms);
  runner.stop();
  for (auto& b : boards) b.reset();
  for (auto& bus : buses) bus->close();
}

// The bare virtual-bus round trip: node A sends, node B answers, A receives; one io thread.
asio::awaitable<void> round_trip(asio::io_context& io, int count, std::vector<double>& rtt) {
  const asio::any_io_executor ex = io.get_executor();
  can::VirtualBusRegistry registry(ex);
  (void)registry.add("rt").value();
  auto a = registry.open("rt").value();
  auto b = registry.open("rt").value();
  can::Bus* bp = b.get();
  asio::co_spawn(
      ex,
      [bp]() -> asio::awaitable<void> {
        for (;;) {
          auto f = co_await bp->receive();
          if (!f) co_return;
          const auto reply = can::Frame::standard(0x005, f.value().payload()).value();
          auto s = co_await bp->send(reply);
          if (!s) co_return;
        }
      },
      asio::detached);
  const auto frame = can::Frame::standard(0x040, std::vector<std::uint8_t>(8, 0x11)).value();
  for (int i = 0; i < count; ++i) {
    const auto t = core::SteadyClock::instance().now();
    auto s = co_await a->send(frame);
    auto r = co_await a->receive(1s);
    if (!s || !r) {
      fmt::print(stderr, "round trip: {}\n", !s ? s.error().message() : r.error().message());
      break;
    }
    rtt.push_back(us(core::SteadyClock::instance().now() - t));
    co_await core::sleep_for(200us);  // one exchange at a time, like the loop's rate
  }
  b->close();
  a->close();
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 2.0;
  for (int i = 1; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], "--seconds") == 0) seconds = std::atof(argv[i + 1]);
  core::init_logging(-1);

  std::vector<double> rtt;
  {
    // The baseline on its own io_context.
    asio::io_context rio;
    asio::co_spawn(rio, round_trip(rio, 2000, rtt), [](std::exception_ptr e) {
      if (e) std::rethrow_exception(e);
    });
    rio.run();
  }
  asio::io_context io;
  std::vector<RunResult> results(3);
  RunResult measured;
  asio::co_spawn(
      io,
      [&]() -> asio::awaitable<void> {
        const unsigned counts[] = {1, 2, 4};
        for (std::size_t k = 0; k < 3; ++k) co_await run_config(io, counts[k], bh::Pacing::clock, seconds, results[k]);
        co_await run_config(io, 1, bh::Pacing::measurements, seconds, measured);
        io.stop();
      },
      [](std::exception_ptr e) {
        if (e) std::rethrow_exception(e);
      });
  io.run();

  const double rtt50 = percentile(rtt, 0.5), rtt99 = percentile(rtt, 0.99);
  fmt::print("bare virtual-bus round trip: p50 {:.1f} us, p99 {:.1f} us ({} exchanges)\n", rtt50, rtt99, rtt.size());
  fmt::print("{:>6} {:>8} {:>10} {:>10} {:>10} {:>9} {:>7} {:>12} {:>12} {:>10}\n", "boards", "cycles", "jit p50us",
             "jit p99us", "jit maxus", "overruns", "missed", "lat p50 us", "lat p99 us", "cpu%/board");
  for (const auto& r : results) {
    fmt::print("{:>6} {:>8} {:>10.0f} {:>10.0f} {:>10.0f} {:>9} {:>7} {:>12.1f} {:>12.1f} {:>10.1f}{}\n", r.boards,
               r.stats.cycles, us(r.stats.jitter_p50), us(r.stats.jitter_p99), us(r.stats.jitter_max),
               r.stats.overruns, r.stats.missed, percentile(r.latency_us, 0.5), percentile(r.latency_us, 0.99),
               r.cpu_pct_per_board, r.faulted ? "  FAULT: " + r.fault : "");
  }
  const double lat50 = percentile(measured.latency_us, 0.5), lat99 = percentile(measured.latency_us, 0.99);
  fmt::print("measurement pacing, 1 board: latency velocity frame -> IqRef p50 {:.1f} us, p99 {:.1f} us; jitter p99 {:.0f} us{}\n",
             lat50, lat99, us(measured.stats.jitter_p99), measured.faulted ? "  FAULT: " + measured.fault : "");
  const double ratio = rtt50 > 0 ? lat50 / rtt50 : 0;
  fmt::print(
      "BENCH blmc_loop rate_hz=1000 jitter_p99_us_1={:.0f} jitter_p99_us_2={:.0f} jitter_p99_us_4={:.0f} "
      "overruns_4={} cpu_pct_per_board_4={:.1f} latency_p50_us={:.1f} latency_clock_p50_us={:.1f} rtt_p50_us={:.1f} "
      "ratio={:.2f}\n",
      us(results[0].stats.jitter_p99), us(results[1].stats.jitter_p99), us(results[2].stats.jitter_p99),
      results[2].stats.overruns, results[2].cpu_pct_per_board, lat50, percentile(results[0].latency_us, 0.5), rtt50,
      ratio);
  return 0;
}
