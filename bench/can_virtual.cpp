// Virtual CAN bus throughput and wire-model fidelity.
//
// 1. Frames per second from one node to another through the virtual bus (no wire model), against
//    a baseline measured in the same run: the same frames pushed into and popped from a plain
//    std::deque in the same batches. ratio = virtual_fps / baseline_fps (below 1: the price of
//    the bus, its coroutines and statistics over a bare queue).
// 2. With pacing on at 1 Mbit/s, how long sample workloads take to arrive compared with their
//    exact wire time (the floor no real bus can beat). wire_ratio = achieved / floor (1 is
//    perfect; above 1 is the timer overshoot).
//
// Plain std::chrono; each throughput figure is the best of several runs because the machine is
// shared. Build: cmake --preset release && cmake --build --preset release --target can_virtual
#include "axon/can/virtual_bus.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/use_awaitable.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <deque>
#include <random>
#include <vector>

using namespace axon;
using namespace axon::can;
using Clock = std::chrono::steady_clock;

namespace {

constexpr std::size_t kFrames = 400'000;
constexpr std::size_t kBatch = 512;  // frames a sender hands over before it lets the medium run
constexpr int kRuns = 5;

std::vector<Frame> throughput_frames() {
  std::vector<Frame> out;
  out.reserve(kFrames);
  for (std::size_t i = 0; i < kFrames; ++i) {
    const std::uint8_t b = static_cast<std::uint8_t>(i);
    const std::array<std::uint8_t, 8> data{b, 1, 2, 3, 4, 5, 6, 7};
    out.push_back(Frame::standard(static_cast<std::uint32_t>(i % 0x800), data).value());
  }
  return out;
}

volatile std::uint64_t g_sink = 0;

double virtual_bus_seconds(const std::vector<Frame>& frames) {
  asio::io_context io;
  auto medium = VirtualBus::create(io.get_executor(), "bench");
  auto tx = medium->attach("tx");
  auto rx = medium->attach("rx");
  std::uint64_t sum = 0;
  std::size_t received = 0;
  asio::co_spawn(io, [&]() -> asio::awaitable<void> {
    for (std::size_t i = 0; i < frames.size(); i += kBatch) {
      const std::size_t end = std::min(frames.size(), i + kBatch);
      for (std::size_t k = i; k < end; ++k)
        if (!co_await tx->send(frames[k])) std::abort();
      co_await asio::post(io.get_executor(), asio::use_awaitable);
    }
  }, asio::detached);
  asio::co_spawn(io, [&]() -> asio::awaitable<void> {
    while (received < frames.size()) {
      auto f = co_await rx->receive();
      if (!f) std::abort();
      sum += f.value().id();
      ++received;
    }
  }, asio::detached);
  const auto t0 = Clock::now();
  io.run();
  const auto t1 = Clock::now();
  g_sink = g_sink + sum;
  return std::chrono::duration<double>(t1 - t0).count();
}

double deque_seconds(const std::vector<Frame>& frames) {
  std::deque<Frame> q;
  std::uint64_t sum = 0;
  const auto t0 = Clock::now();
  for (std::size_t i = 0; i < frames.size(); i += kBatch) {
    const std::size_t end = std::min(frames.size(), i + kBatch);
    for (std::size_t k = i; k < end; ++k) q.push_back(frames[k]);
    while (!q.empty()) {
      sum += q.front().id();
      q.pop_front();
    }
  }
  const auto t1 = Clock::now();
  g_sink = g_sink + sum;
  return std::chrono::duration<double>(t1 - t0).count();
}

// The longest extended 8-byte frame among patterns known to provoke stuffing.
Frame worst_extended_frame() {
  const std::uint32_t ids[] = {0x0, 0x1FFFFFFF, 0x0F0F0F0F, 0x10F0F0F0, 0x1E1E1E1E, 0x03C3C3C3, 0x07878787, 0x18787878};
  const std::uint8_t bytes[] = {0x00, 0xFF, 0x0F, 0xF0, 0x3C, 0xC3, 0x1E, 0xE1, 0x78, 0x87};
  Frame best;
  std::uint32_t best_bits = 0;
  for (auto id : ids)
    for (auto b : bytes) {
      const std::array<std::uint8_t, 8> data{b, b, b, b, b, b, b, b};
      auto f = Frame::extended(id, data).value();
      if (frame_bits(f).total > best_bits) {
        best_bits = frame_bits(f).total;
        best = f;
      }
    }
  return best;
}

std::vector<Frame> mixed_frames(std::size_t n) {
  std::mt19937_64 rng(12345);
  std::vector<Frame> out;
  out.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    std::array<std::uint8_t, 8> data{};
    const auto len = static_cast<std::size_t>(rng() % 9);
    for (auto& d : data) d = static_cast<std::uint8_t>(rng());
    if (rng() % 3 == 0)
      out.push_back(Frame::extended(static_cast<std::uint32_t>(rng() & Frame::kMaxExtendedId), std::span(data.data(), len)).value());
    else
      out.push_back(Frame::standard(static_cast<std::uint32_t>(rng() & Frame::kMaxStandardId), std::span(data.data(), len)).value());
  }
  return out;
}

struct WireResult {
  double floor_s;
  double achieved_s;
};

// All frames are queued at once (as a controller with a deep FIFO would hold them); the clock
// stops when the last one has arrived.
WireResult paced(const std::vector<Frame>& frames, std::uint32_t bitrate) {
  asio::io_context io;
  WireModel wire;
  wire.enabled = true;
  wire.pace_realtime = true;
  wire.bitrate = bitrate;
  auto medium = VirtualBus::create(io.get_executor(), "paced", wire);
  BusOptions opts;
  opts.tx_capacity = frames.size();
  auto tx = medium->attach("tx", opts);
  auto rx = medium->attach("rx");
  std::uint64_t bits = 0;
  for (const auto& f : frames) bits += frame_bits(f).total;

  Clock::time_point done{};
  std::size_t received = 0;
  const auto t0 = Clock::now();
  asio::co_spawn(io, [&]() -> asio::awaitable<void> {
    for (const auto& f : frames)
      if (!co_await tx->send(f)) std::abort();
  }, asio::detached);
  asio::co_spawn(io, [&]() -> asio::awaitable<void> {
    while (received < frames.size()) {
      if (!co_await rx->receive()) std::abort();
      ++received;
    }
    done = Clock::now();
  }, asio::detached);
  io.run();
  if (medium->stats().bits != bits) std::abort();
  return {static_cast<double>(bits) / bitrate, std::chrono::duration<double>(done - t0).count()};
}

}  // namespace

int main() {
  const auto frames = throughput_frames();
  double best_virtual = 1e9, best_deque = 1e9;
  for (int r = 0; r < kRuns; ++r) {
    best_virtual = std::min(best_virtual, virtual_bus_seconds(frames));
    best_deque = std::min(best_deque, deque_seconds(frames));
  }
  const double fps = static_cast<double>(kFrames) / best_virtual;
  const double baseline_fps = static_cast<double>(kFrames) / best_deque;
  fmt::print("throughput: {} frames, 2 nodes, no wire model, best of {}\n", kFrames, kRuns);
  fmt::print("  virtual bus   {:>14.0f} frames/s ({:.1f} ns/frame)\n", fps, 1e9 / fps);
  fmt::print("  std::deque    {:>14.0f} frames/s ({:.1f} ns/frame)\n", baseline_fps, 1e9 / baseline_fps);
  fmt::print("  ratio (virtual/deque) {:.4f}\n", fps / baseline_fps);

  constexpr std::uint32_t kBitrate = 1'000'000;
  const auto best_case = Frame::parse("085#AAAAAAAAAAAAAAAA").value();
  const auto worst_ext = worst_extended_frame();
  struct Workload {
    const char* name;
    std::vector<Frame> frames;
  };
  const Workload workloads[] = {
      {"1000 x best-case standard 8-byte", std::vector<Frame>(1000, best_case)},
      {"1000 x worst-pattern extended 8-byte", std::vector<Frame>(1000, worst_ext)},
      {"1000 x random mix (1/3 extended, 0..8 bytes)", mixed_frames(1000)},
  };
  fmt::print("wire model at {} bit/s, paced (best case {} = {} bits; worst extended {} = {} bits, "
             "shape budget {} bits)\n",
             kBitrate, best_case.to_string(), frame_bits(best_case).total, worst_ext.to_string(),
             frame_bits(worst_ext).total, worst_case_bits(IdFormat::extended, 8));
  double floor_total = 0, achieved_total = 0;
  for (const auto& w : workloads) {
    const auto r = paced(w.frames, kBitrate);
    floor_total += r.floor_s;
    achieved_total += r.achieved_s;
    fmt::print("  {:<46} floor_s={:.6f} achieved_s={:.6f} ratio={:.4f}\n", w.name, r.floor_s, r.achieved_s,
               r.achieved_s / r.floor_s);
  }

  fmt::print("BENCH can_virtual fps={:.0f} baseline_fps={:.0f} ratio={:.4f} wire_floor_s={:.6f} wire_achieved_s={:.6f} "
             "wire_ratio={:.4f}\n",
             fps, baseline_fps, fps / baseline_fps, floor_total, achieved_total, achieved_total / floor_total);
  std::fflush(stdout);
  return 0;
}
