// The virtual bus's wire model: exact bit accounting, real-time pacing and its effect on senders.
// No upper bounds on time anywhere: the machine may be slow, it can never be faster than the wire.
#include "axon/can/virtual_bus.hpp"
#include "frame_text.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/use_awaitable.hpp>
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <chrono>
#include <thread>
#include <vector>

using namespace axon;
using namespace axon::can;

namespace {

using axon::can::test::F;

// A mix of shapes: best case, heavy stuffing, extended, remote, empty.
std::vector<Frame> mix() {
  return {F("085#AAAAAAAAAAAAAAAA"), F("7FF#FFFFFFFFFFFFFFFF"), F("00000000#0000000000000000"),
          F("123#DEADBEEF"),         F("1ABCDEF0#R8"),         F("000#"),
          F("02F#3C3C3C3C3C3C3C3C")};
}

// The coroutine runs later (in io.run()), so it keeps its own copy of the frames.
void send_all(asio::io_context& io, Bus& bus, std::vector<Frame> frames) {
  asio::co_spawn(io, [&bus, frames = std::move(frames)]() -> asio::awaitable<void> {
    for (const auto& f : frames) EXPECT_TRUE((co_await bus.send(f)).has_value());
  }, asio::detached);
}

}  // namespace

TEST(VirtualBusWire, BusyTimeIsTheSumOfExactFrameBits) {
  asio::io_context io;
  WireModel wire;
  wire.enabled = true;
  wire.bitrate = 250'000;
  auto medium = VirtualBus::create(io.get_executor(), "vcan0", wire);
  auto a = medium->attach(), b = medium->attach();
  const auto frames = mix();
  send_all(io, *a, frames);
  io.run();

  std::uint64_t bits = 0;
  for (const auto& f : frames) bits += frame_bits(f).total;
  EXPECT_EQ(medium->stats().frames, frames.size());
  EXPECT_EQ(medium->stats().bits, bits);
  // 4 us per bit at 250 kbit/s: exact in nanoseconds.
  EXPECT_EQ(medium->stats().busy, core::Duration(static_cast<std::int64_t>(bits) * 4000));
  EXPECT_EQ(b->stats().bits_in, bits);
}

TEST(VirtualBusWire, NoAccountingWithoutTheWireModel) {
  asio::io_context io;
  auto medium = VirtualBus::create(io.get_executor(), "vcan0");
  auto a = medium->attach(), b = medium->attach();
  send_all(io, *a, mix());
  io.run();
  EXPECT_EQ(medium->stats().frames, mix().size());
  EXPECT_EQ(medium->stats().bits, 0u);
  EXPECT_EQ(medium->stats().busy, core::Duration::zero());
  EXPECT_EQ(medium->load(core::SteadyClock::instance().now()), 0.0);
}

TEST(VirtualBusWire, LoadIsBusyTimeOverElapsedTime) {
  asio::io_context io;
  WireModel wire;
  wire.enabled = true;
  auto medium = VirtualBus::create(io.get_executor(), "vcan0", wire);
  auto a = medium->attach(), b = medium->attach();
  send_all(io, *a, mix());
  io.run();
  const auto busy = medium->stats().busy;
  ASSERT_GT(busy, core::Duration::zero());
  const auto created = medium->stats().created;
  EXPECT_DOUBLE_EQ(medium->load(created + 4 * busy), 0.25);
  EXPECT_EQ(medium->load(created), 0.0);
}

TEST(VirtualBusWire, PacedDeliveryTakesAtLeastTheWireTime) {
  asio::io_context io;
  WireModel wire;
  wire.enabled = true;
  wire.pace_realtime = true;
  wire.bitrate = 125'000;  // 8 us a bit: 40 frames are several milliseconds of wire time
  auto medium = VirtualBus::create(io.get_executor(), "vcan0", wire);
  auto a = medium->attach(), b = medium->attach();
  std::vector<Frame> frames;
  for (int i = 0; i < 5; ++i)
    for (const auto& f : mix()) frames.push_back(f);
  core::Duration floor{0};
  for (const auto& f : frames) floor += frame_time(f, wire.bitrate);

  const auto start = std::chrono::steady_clock::now();
  send_all(io, *a, frames);
  io.run();
  const auto elapsed = std::chrono::steady_clock::now() - start;
  EXPECT_EQ(b->pending(), frames.size());
  EXPECT_GE(elapsed, floor);
}

TEST(VirtualBusWire, PacedMediumTakesOneFrameAtATime) {
  // The medium carries one frame at a time: the k-th frame cannot arrive before k frame times
  // have passed, so five frames sent at once arrive over five frame times, not together at the
  // first one's end. (A thread that wakes up late may then hand over several frames whose wire
  // end has passed in one go, so the test checks times, not how many arrived per wake-up.)
  asio::io_context io;
  WireModel wire;
  wire.pace_realtime = true;
  auto medium = VirtualBus::create(io.get_executor(), "vcan0", wire);
  auto a = medium->attach(), b = medium->attach();
  const std::vector<Frame> frames{F("001#"), F("002#"), F("003#"), F("004#"), F("005#")};
  const auto start = std::chrono::steady_clock::now();
  send_all(io, *a, frames);
  std::vector<core::Duration> arrived;  // when b held k + 1 frames
  while (io.run_one() > 0)
    while (arrived.size() < b->pending()) arrived.push_back(std::chrono::steady_clock::now() - start);
  ASSERT_EQ(arrived.size(), frames.size());
  core::Duration wire_end{0};
  for (std::size_t k = 0; k < frames.size(); ++k) {
    wire_end += frame_time(frames[k], wire.bitrate);
    EXPECT_GE(arrived[k], wire_end) << "frame " << k + 1 << " arrived before its wire end";
  }
  EXPECT_EQ(a->tx_pending(), 0u);
}

namespace {

// A sender that hands over a frame and then lets the executor run: an unpaced medium drains the
// queue at every turn, a paced one only once per frame time, so the queue fills and refuses.
int refused_while_yielding(bool pace) {
  asio::io_context io;
  WireModel wire;
  wire.pace_realtime = pace;
  wire.bitrate = 10'000;  // about 11 ms per frame: far longer than the sender's whole burst
  auto medium = VirtualBus::create(io.get_executor(), "vcan0", wire);
  BusOptions opts;
  opts.tx_capacity = 4;
  auto a = medium->attach("a", opts), b = medium->attach();
  int refused = 0;
  asio::co_spawn(io, [&]() -> asio::awaitable<void> {
    for (int i = 0; i < 10; ++i) {
      if (!(co_await a->send(F("123#1122334455667788")))) ++refused;
      co_await asio::post(io.get_executor(), asio::use_awaitable);
    }
  }, asio::detached);
  io.run();
  EXPECT_EQ(b->pending() + static_cast<std::size_t>(refused), 10u);
  EXPECT_EQ(a->stats().tx_dropped, static_cast<std::uint64_t>(refused));
  return refused;
}

}  // namespace

TEST(VirtualBusWire, PacedSenderQueueFillsUpLikeAController) {
  EXPECT_EQ(refused_while_yielding(false), 0);
  EXPECT_GT(refused_while_yielding(true), 0);
}

TEST(VirtualBusWire, FramesQueuedDuringATransmissionCompeteForTheNext) {
  asio::io_context io;
  WireModel wire;
  wire.pace_realtime = true;
  wire.bitrate = 10'000;  // about 5 ms per frame: b surely queues while 0x500 is on the wire
  auto medium = VirtualBus::create(io.get_executor(), "vcan0", wire);
  auto a = medium->attach(), b = medium->attach(), rx = medium->attach();
  asio::co_spawn(io, [&]() -> asio::awaitable<void> {
    (void)co_await a->send(F("500#"));  // wins the idle bus alone
    (void)co_await a->send(F("400#"));
  }, asio::detached);
  // Once 0x500 is on the wire, b queues a frame that beats a's next one.
  while (medium->stats().frames == 0 && io.run_one() > 0) {
  }
  asio::co_spawn(io, [&]() -> asio::awaitable<void> { (void)co_await b->send(F("100#")); }, asio::detached);
  io.run();
  std::vector<std::string> got;
  while (auto f = rx->try_receive()) got.push_back(f->to_string());
  EXPECT_EQ(got, (std::vector<std::string>{"500#", "100#", "400#"}));
}

TEST(VirtualBusWire, ALateWakeUpIsCountedAndKeepsTheSchedule) {
  asio::io_context io;
  WireModel wire;
  wire.pace_realtime = true;
  wire.bitrate = 125'000;  // 8 us a bit: an 8-byte frame takes about 1 ms
  auto medium = VirtualBus::create(io.get_executor(), "vcan0", wire);
  auto a = medium->attach(), b = medium->attach();
  std::vector<Frame> frames;
  for (int i = 0; i < 10; ++i) frames.push_back(F("123#1122334455667788"));
  send_all(io, *a, frames);
  while (b->pending() == 0 && io.run_one() > 0) {
  }
  // The process is descheduled for a while (what a loaded machine does to a simulator).
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  io.run();
  EXPECT_EQ(b->pending(), frames.size());
  // The stall shows up as lateness of the frame whose end fell into it...
  EXPECT_GE(medium->stats().max_lateness, std::chrono::milliseconds(20) - frame_time(frames[0], wire.bitrate));
  EXPECT_GE(medium->stats().lateness, medium->stats().max_lateness);
  // ... and the wire carried each frame for exactly its bits, no more, no less.
  std::uint64_t bits = 0;
  for (const auto& f : frames) bits += frame_bits(f).total;
  EXPECT_EQ(medium->stats().bits, bits);
}

// Media on one executor share one pacing timer (core::DeadlineQueue): each still hands every frame
// over no earlier than the end of its own schedule, in order, and the schedules do not mix.
TEST(VirtualBusWire, PacedMediaOnOneExecutorKeepTheirOwnSchedules) {
  asio::io_context io;
  WireModel wire;
  wire.pace_realtime = true;
  wire.bitrate = 250'000;  // 4 us a bit
  struct Lane {
    std::shared_ptr<VirtualBus> medium;
    std::unique_ptr<Bus> tx, rx;
    std::vector<Frame> frames;
    std::vector<std::chrono::steady_clock::time_point> arrived;
    std::vector<std::string> got;
  };
  std::vector<Lane> lanes(3);
  for (std::size_t i = 0; i < lanes.size(); ++i) {
    auto& l = lanes[i];
    l.medium = VirtualBus::create(io.get_executor(), fmt::format("vcan{}", i), wire);
    l.tx = l.medium->attach();
    l.rx = l.medium->attach();
    for (int k = 0; k < 12; ++k) l.frames.push_back(i == 1 ? F("7FF#FFFFFFFFFFFFFFFF") : mix()[static_cast<std::size_t>(k) % mix().size()]);
  }
  const auto t0 = std::chrono::steady_clock::now();
  for (auto& l : lanes) {
    send_all(io, *l.tx, l.frames);
    asio::co_spawn(io, [&l]() -> asio::awaitable<void> {
      for (std::size_t k = 0; k < l.frames.size(); ++k) {
        auto f = co_await l.rx->receive();
        l.arrived.push_back(std::chrono::steady_clock::now());
        l.got.push_back(f.value().to_string());
      }
    }, asio::detached);
  }
  io.run();
  for (auto& l : lanes) {
    ASSERT_EQ(l.got.size(), l.frames.size());
    core::Duration end{0};
    std::uint64_t bits = 0;
    for (std::size_t k = 0; k < l.frames.size(); ++k) {
      EXPECT_EQ(l.got[k], l.frames[k].to_string());
      end += frame_time(l.frames[k], wire.bitrate);
      bits += frame_bits(l.frames[k]).total;
      EXPECT_GE(l.arrived[k], t0 + end) << l.medium->name() << " frame " << k;
    }
    EXPECT_EQ(l.medium->stats().bits, bits);
  }
}
