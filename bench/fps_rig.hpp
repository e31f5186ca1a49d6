// Shared set-up of the fps end-to-end benches: the default focal plane (500 robots, 24 buses, 6
// gateways) simulated behind CAN@net gateway emulators with the wire model and pacing at 1 Mbit/s,
// driven over loopback TCP by a FocalPlaneArray, everything on one io_context.
//
// The floor of an operation is the wire time of the busiest bus: the exact bits of every frame
// that crossed it during the operation (the media count them with can::frame_bits) at 1 Mbit/s.
#pragma once

#include "fps/host/focal_plane_array.hpp"
#include "fps/layout/layout_generator.hpp"
#include "fps/sim/focal_plane_sim.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/io_context.hpp>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <sys/resource.h>

#include <cstdlib>
#include <map>
#include <memory>

namespace bench {

namespace asio = boost::asio;
using namespace axon;

struct BusWire {
  std::uint64_t frames = 0;
  std::uint64_t bits = 0;
};

struct FpsRig {
  asio::io_context io;
  fps::FocalPlane plane = fps::generate_layout({}).value();
  std::unique_ptr<fps::sim::FocalPlaneSimulator> sim;
  std::unique_ptr<fps::host::FocalPlaneArray> fpa;

  // Starts the simulated focal plane (no PLC) and connects the array to its gateways.
  void start() {
    spdlog::set_level(spdlog::level::warn);
    fps::sim::FocalPlaneSimOptions so;
    so.random_start = false;
    so.plc = false;
    sim = fps::sim::FocalPlaneSimulator::start(io.get_executor(), plane, so).value();
    fps::host::FocalPlaneArrayOptions ao;
    for (const auto& g : sim->gateways()) ao.addresses[g.id] = g.endpoint;
    run([&]() -> asio::awaitable<void> {
      auto r = co_await fps::host::FocalPlaneArray::connect(io.get_executor(), plane, ao);
      if (!r) {
        fmt::print(stderr, "connect: {}\n", r.error().message());
        std::exit(1);
      }
      fpa = std::move(r).value();
    });
  }

  // Runs a coroutine to completion on the io_context (which keeps serving the simulator).
  template <class F>
  void run(F f) {
    bool done = false;
    asio::co_spawn(io, f(), [&](std::exception_ptr e) {
      if (e) std::rethrow_exception(e);
      done = true;
    });
    while (!done) io.run_one();
  }

  std::map<fps::BusRef, BusWire> wire() const {
    std::map<fps::BusRef, BusWire> out;
    for (const auto& b : plane.buses()) {
      const auto m = sim->medium(b);
      out[b] = BusWire{m->stats().frames, m->stats().bits};
    }
    return out;
  }

  // The busiest bus between two snapshots: its frames and wire time in seconds at 1 Mbit/s.
  static std::pair<BusWire, double> floor(const std::map<fps::BusRef, BusWire>& before, const std::map<fps::BusRef, BusWire>& after) {
    BusWire most;
    for (const auto& [b, w] : after) {
      const BusWire d{w.frames - before.at(b).frames, w.bits - before.at(b).bits};
      if (d.bits > most.bits) most = d;
    }
    return {most, static_cast<double>(most.bits) / 1e6};
  }

  void stop() {
    run([&]() -> asio::awaitable<void> { co_await fpa->close(); });
    sim->stop();
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
