// Shared set-up of the fps end-to-end benches: the default focal plane (500 robots, 24 buses, 6
// gateways) simulated behind CAN@net gateway emulators with the wire model and pacing at 1 Mbit/s,
// driven over loopback TCP by a FocalPlaneArray.
//
// The simulated plane runs on a thread of its own (its own io_context), the host on the main
// thread, as they would on two machines: each side's event loop only carries its own work, and
// the host's figures are not inflated by the simulator's CPU time (or the other way round).
// Everything of the simulator is touched on its thread only (in_sim()).
//
// The floor of an operation is the wire time of the busiest bus: the exact bits of every frame
// that crossed it during the operation (the media count them with can::frame_bits) at 1 Mbit/s.
#pragma once

#include "axon/fps/host/focal_plane_array.hpp"
#include "axon/fps/layout/layout_generator.hpp"
#include "axon/core/deadline_queue.hpp"
#include "axon/fps/sim/focal_plane_sim.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <sys/resource.h>
#include <time.h>

#include <chrono>
#include <string>
#include <tuple>
#include <cstdlib>
#include <future>
#include <map>
#include <memory>
#include <thread>

namespace bench {

namespace asio = boost::asio;
using namespace axon;

struct BusWire {
  std::uint64_t frames = 0;
  std::uint64_t bits = 0;
  core::Duration lateness{0};      // summed lateness of paced deliveries (see VirtualBusStats)
  core::Duration max_lateness{0};
};

inline double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) / 1e9;
}

struct FpsRig {
  asio::io_context io;      // the host
  asio::io_context sim_io;  // the simulated plane, run by sim_thread
  std::thread sim_thread;
  fps::FocalPlane plane = fps::generate_layout({}).value();
  std::unique_ptr<fps::sim::FocalPlaneSimulator> sim;
  std::unique_ptr<fps::host::FocalPlaneArray> fpa;
  std::unique_ptr<asio::executor_work_guard<asio::io_context::executor_type>> sim_work;

  // Runs f() on the simulator's thread and returns its result.
  template <class F>
  auto in_sim(F f) -> decltype(f()) {
    std::packaged_task<decltype(f())()> task(std::move(f));
    auto fut = task.get_future();
    asio::post(sim_io, [&task] { task(); });
    return fut.get();
  }

  // Starts the simulated focal plane (no PLC) on its thread and connects the array to its gateways.
  void start() {
    spdlog::set_level(spdlog::level::warn);
    fps::sim::FocalPlaneSimOptions so;
    so.random_start = false;
    so.plc = false;
    if (const char* v = std::getenv("FPS_BENCH_SLACK_US")) so.timer_slack = std::chrono::microseconds(std::strtoul(v, nullptr, 10));
    sim_work = std::make_unique<asio::executor_work_guard<asio::io_context::executor_type>>(sim_io.get_executor());
    sim_thread = std::thread([this] { sim_io.run(); });
    sim = in_sim([&] { return fps::sim::FocalPlaneSimulator::start(sim_io.get_executor(), plane, so).value(); });
    fps::host::FocalPlaneArrayOptions ao;
    for (const auto& g : sim->gateways()) ao.addresses[g.id] = g.endpoint;
    // Knobs for experiments (defaults: the library's).
    if (const char* v = std::getenv("FPS_BENCH_IN_FLIGHT")) ao.array.client.max_in_flight = std::strtoul(v, nullptr, 10);
    if (const char* v = std::getenv("FPS_BENCH_WINDOW")) ao.array.positioner.trajectory_window = std::strtoul(v, nullptr, 10);
    run([&]() -> asio::awaitable<void> {
      auto r = co_await fps::host::FocalPlaneArray::connect(io.get_executor(), plane, ao);
      if (!r) {
        fmt::print(stderr, "connect: {}\n", r.error().message());
        std::exit(1);
      }
      fpa = std::move(r).value();
    });
  }

  // Runs a coroutine to completion on the host's io_context.
  template <class F>
  void run(F f) {
    bool done = false;
    asio::co_spawn(io, f(), [&](std::exception_ptr e) {
      if (e) std::rethrow_exception(e);
      done = true;
    });
    while (!done) io.run_one();
  }

  std::map<fps::BusRef, BusWire> wire() {
    return in_sim([&] {
      std::map<fps::BusRef, BusWire> out;
      for (const auto& b : plane.buses()) {
        const auto& s = sim->medium(b)->stats();
        out[b] = BusWire{s.frames, s.bits, s.lateness, s.max_lateness};
      }
      return out;
    });
  }

  // CPU seconds the simulator's thread used so far.
  double sim_cpu_seconds() { return in_sim([] { return thread_cpu_seconds(); }); }

  // The busiest bus between two snapshots: its frames and wire time in seconds at 1 Mbit/s.
  static std::pair<BusWire, double> floor(const std::map<fps::BusRef, BusWire>& before, const std::map<fps::BusRef, BusWire>& after) {
    BusWire most;
    for (const auto& [b, w] : after) {
      const BusWire d{w.frames - before.at(b).frames, w.bits - before.at(b).bits, w.lateness - before.at(b).lateness,
                      w.max_lateness};
      if (d.bits > most.bits) most = d;
    }
    return {most, static_cast<double>(most.bits) / 1e6};
  }

  // Mean lateness of paced deliveries per frame over all buses between two snapshots (ms): how far
  // the simulator's thread lagged behind the wire schedule.
  static double mean_lateness_ms(const std::map<fps::BusRef, BusWire>& before, const std::map<fps::BusRef, BusWire>& after) {
    double late = 0, frames = 0;
    for (const auto& [b, w] : after) {
      late += std::chrono::duration<double, std::milli>(w.lateness - before.at(b).lateness).count();
      frames += static_cast<double>(w.frames - before.at(b).frames);
    }
    return frames > 0 ? late / frames : 0.0;
  }

  // Frames on all buses between two snapshots.
  static std::uint64_t total_frames(const std::map<fps::BusRef, BusWire>& before, const std::map<fps::BusRef, BusWire>& after) {
    std::uint64_t n = 0;
    for (const auto& [b, w] : after) n += w.frames - before.at(b).frames;
    return n;
  }

  // One measured round of an operation: what measure() returns.
  struct Round {
    double achieved_s = 0;
    BusWire busiest;       // the busiest bus's frames and bits in this round
    double floor_s = 0;    // its wire time at 1 Mbit/s
    double lateness_ms = 0;  // mean_lateness_ms over all buses
    std::uint64_t frames = 0;  // frames on all buses
    [[nodiscard]] double ratio() const { return achieved_s / floor_s; }
  };

  // Runs body() (which drives the host's io_context, e.g. with run()) and measures it against the
  // wire.
  template <class F>
  Round measure(F body) {
    const auto before = wire();
    const auto t0 = std::chrono::steady_clock::now();
    body();
    Round r;
    r.achieved_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const auto after = wire();
    std::tie(r.busiest, r.floor_s) = floor(before, after);
    r.lateness_ms = mean_lateness_ms(before, after);
    r.frames = total_frames(before, after);
    return r;
  }

  // Kernel timer waits the simulator's thread started for its deadlines (pacing, processing).
  std::uint64_t sim_timer_waits() {
    return in_sim([&] { return core::DeadlineQueue::of(sim_io.get_executor()).timer_waits(); });
  }

  // CPU of both threads from construction (start of the measurement) to report().
  struct Cpu {
    explicit Cpu(FpsRig& rig)
        : rig_(rig), host0_(thread_cpu_seconds()), sim0_(rig.sim_cpu_seconds()), waits0_(rig.sim_timer_waits()) {}
    // "host X s CPU (Y us/frame), simulator ..." over `frames` frames (all buses, all rounds).
    [[nodiscard]] std::string report(std::uint64_t frames) const {
      const double host = thread_cpu_seconds() - host0_, sim = rig_.sim_cpu_seconds() - sim0_;
      const double n = frames > 0 ? static_cast<double>(frames) : 1.0;
      const double waits = static_cast<double>(rig_.sim_timer_waits() - waits0_);
      return fmt::format("host {:.2f} s CPU ({:.2f} us/frame), simulator {:.2f} s CPU ({:.2f} us/frame) for {} frames, "
                         "{:.2f} simulator timer waits per frame",
                         host, host / n * 1e6, sim, sim / n * 1e6, frames, waits / n);
    }

   private:
    FpsRig& rig_;
    double host0_, sim0_;
    std::uint64_t waits0_;
  };

  void stop() {
    run([&]() -> asio::awaitable<void> { co_await fpa->close(); });
    in_sim([&] {
      sim->stop();
      return 0;
    });
    sim_work.reset();
    sim_io.stop();
    sim_thread.join();
    sim.reset();
    io.poll();
  }
};

inline double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec) / 1e6;
}

inline long peak_rss_kb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss;
}

}  // namespace bench
