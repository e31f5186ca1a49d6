// SocketCanBus over a socketpair standing in for the kernel's CAN_RAW socket: the test writes and
// reads raw struct can_frame records on the other end. Plus open() on this machine's kernel.
#include "axon/can/socketcan_bus.hpp"

#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/io_context.hpp>
#include <gtest/gtest.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <functional>
#include <optional>
#include <vector>

using namespace std::chrono_literals;
using axon::Result;
using axon::can::BusState;
using axon::can::CanErrc;
using axon::can::Filter;
using axon::can::Frame;
using axon::can::IdFormat;
using axon::can::SocketCanBus;
using axon::can::SocketCanOptions;
namespace asio = boost::asio;

namespace {

// Runs the io_context until pred() holds; false if it did not within the (generous) limit.
bool run_until(asio::io_context& io, const std::function<bool()>& pred, std::chrono::seconds limit = 10s) {
  const auto end = std::chrono::steady_clock::now() + limit;
  while (!pred()) {
    if (std::chrono::steady_clock::now() > end) return false;
    if (io.stopped()) io.restart();  // it stops whenever it runs out of work
    io.run_one_for(10ms);
  }
  return true;
}

// Runs a coroutine to completion on io (the bus's receive loop keeps io busy forever, so io.run()
// would never return).
template <class T>
T run(asio::io_context& io, asio::awaitable<T> aw) {
  std::optional<T> out;
  asio::co_spawn(io, [&]() -> asio::awaitable<void> { out.emplace(co_await std::move(aw)); },
                 [](std::exception_ptr e) {
                   if (e) std::rethrow_exception(e);
                 });
  if (!run_until(io, [&] { return out.has_value(); }, 30s)) throw std::runtime_error("coroutine did not finish");
  return std::move(*out);
}

struct can_frame raw_frame(canid_t id, std::initializer_list<std::uint8_t> data) {
  struct can_frame cf {};
  cf.can_id = id;
  cf.len = static_cast<std::uint8_t>(data.size());
  std::copy(data.begin(), data.end(), cf.data);
  return cf;
}

struct Pair {
  int bus_end = -1;
  int peer = -1;
  explicit Pair(int type) {
    int fds[2];
    if (::socketpair(AF_UNIX, type | SOCK_CLOEXEC, 0, fds) != 0) throw std::runtime_error("socketpair");
    bus_end = fds[0];
    peer = fds[1];
  }
  ~Pair() {
    if (peer >= 0) ::close(peer);
  }
  void write(const void* data, std::size_t size) const {
    ASSERT_EQ(::send(peer, data, size, 0), static_cast<ssize_t>(size)) << std::strerror(errno);
  }
  void write(const struct can_frame& cf) const { write(&cf, sizeof cf); }
};

std::unique_ptr<SocketCanBus> adopt(asio::io_context& io, Pair& pair, SocketCanOptions opts = {}) {
  auto bus = SocketCanBus::adopt(io.get_executor(), pair.bus_end, "test0", {}, std::move(opts));
  EXPECT_TRUE(bus) << bus.error().message();
  return std::move(bus).value();
}

std::int64_t wall_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace

TEST(SocketCanBus, ReceivesRawFramesWithKernelTimestamps) {
  asio::io_context io;
  Pair pair(SOCK_SEQPACKET);
  auto bus = adopt(io, pair);
  EXPECT_FALSE(bus->is_can_socket());

  const auto before = wall_now_ns();
  pair.write(raw_frame(0x123, {0xDE, 0xAD}));
  pair.write(raw_frame(0x12345678 | CAN_EFF_FLAG, {1, 2, 3, 4, 5, 6, 7, 8}));
  pair.write(raw_frame(0x7FF | CAN_RTR_FLAG, {}));
  auto a = run(io, bus->receive(5s));
  auto b = run(io, bus->receive(5s));
  auto c = run(io, bus->receive(5s));
  const auto after = wall_now_ns();
  ASSERT_TRUE(a && b && c);

  EXPECT_EQ(a.value(), Frame::standard(0x123, std::array<std::uint8_t, 2>{0xDE, 0xAD}).value());
  EXPECT_EQ(b.value(), Frame::extended(0x12345678, std::array<std::uint8_t, 8>{1, 2, 3, 4, 5, 6, 7, 8}).value());
  EXPECT_EQ(c.value(), Frame::remote(0x7FF, IdFormat::standard, 0).value());
  for (const auto* f : {&a.value(), &b.value(), &c.value()}) {
    EXPECT_GE(f->timestamp().count(), before);
    EXPECT_LE(f->timestamp().count(), after);
  }
  // The stamps came from the kernel, not from the fallback clock.
  EXPECT_TRUE(bus->kernel_timestamps());
  EXPECT_EQ(bus->socketcan_stats().timestamp_fallbacks, 0u);
  EXPECT_EQ(bus->stats().frames_in, 3u);
}

TEST(SocketCanBus, SendsRawFrames) {
  asio::io_context io;
  Pair pair(SOCK_SEQPACKET);
  auto bus = adopt(io, pair);
  const auto f1 = Frame::extended(0x1ABCDEF0, std::array<std::uint8_t, 3>{9, 8, 7}).value();
  const auto f2 = Frame::remote(0x42, IdFormat::standard, 2).value();
  ASSERT_TRUE(run(io, bus->send(f1)));
  ASSERT_TRUE(run(io, bus->send(f2)));
  EXPECT_EQ(bus->stats().frames_out, 2u);

  for (const auto& expected : {raw_frame(0x1ABCDEF0 | CAN_EFF_FLAG, {9, 8, 7}), raw_frame(0x42 | CAN_RTR_FLAG, {})}) {
    std::array<std::uint8_t, 64> buf{};
    const ssize_t n = ::recv(pair.peer, buf.data(), buf.size(), MSG_DONTWAIT);
    ASSERT_EQ(n, static_cast<ssize_t>(sizeof(struct can_frame)));
    struct can_frame got {};
    std::memcpy(&got, buf.data(), sizeof got);
    EXPECT_EQ(got.can_id, expected.can_id);
    if (got.can_id & CAN_RTR_FLAG) {
      EXPECT_EQ(got.len, 2);
    } else {
      EXPECT_EQ(got.len, expected.len);
      EXPECT_EQ(0, std::memcmp(got.data, expected.data, expected.len));
    }
  }
}

TEST(SocketCanBus, ErrorReportsMoveTheBusStateAndAreNotDelivered) {
  asio::io_context io;
  Pair pair(SOCK_SEQPACKET);
  auto bus = adopt(io, pair);

  pair.write(raw_frame(CAN_ERR_FLAG | CAN_ERR_CRTL, {0, CAN_ERR_CRTL_TX_WARNING, 0, 0, 0, 0, 0, 0}));
  pair.write(raw_frame(0x100, {1}));
  ASSERT_TRUE(run(io, bus->receive(5s)));  // the report was handled before this frame
  EXPECT_EQ(bus->state(), BusState::error_warning);
  EXPECT_EQ(bus->stats().error_warning_events, 1u);
  EXPECT_EQ(bus->pending(), 0u);  // the report itself was not queued as a frame
  EXPECT_EQ(bus->stats().frames_in, 1u);

  pair.write(raw_frame(CAN_ERR_FLAG | CAN_ERR_CRTL, {0, CAN_ERR_CRTL_TX_PASSIVE, 0, 0, 0, 0, 0, 0}));
  ASSERT_TRUE(run_until(io, [&] { return bus->state() == BusState::error_passive; }));

  pair.write(raw_frame(CAN_ERR_FLAG | CAN_ERR_BUSOFF, {0, 0, 0, 0, 0, 0, 0, 0}));
  ASSERT_TRUE(run_until(io, [&] { return bus->state() == BusState::bus_off; }));
  EXPECT_EQ(bus->stats().bus_off_events, 1u);
  EXPECT_EQ(bus->stats().error_frames, 3u);
  EXPECT_TRUE(bus->is_open());

  // Bus-off: sending fails fast with a typed error.
  auto sent = run(io, bus->send(Frame::standard(0x1, {}).value()));
  ASSERT_FALSE(sent);
  EXPECT_EQ(sent.error(), CanErrc::bus_off);

  // The controller restarts: active again, sending works.
  pair.write(raw_frame(CAN_ERR_FLAG | CAN_ERR_RESTARTED, {0, 0, 0, 0, 0, 0, 0, 0}));
  ASSERT_TRUE(run_until(io, [&] { return bus->state() == BusState::active; }));
  EXPECT_EQ(bus->socketcan_stats().restarts, 1u);
  EXPECT_TRUE(run(io, bus->send(Frame::standard(0x1, {}).value())));
  EXPECT_EQ(bus->pending(), 0u);
}

TEST(SocketCanBus, FrameFromTheBusEndsBusOffWhenTheRestartReportWasLost) {
  asio::io_context io;
  Pair pair(SOCK_SEQPACKET);
  auto bus = adopt(io, pair);
  pair.write(raw_frame(CAN_ERR_FLAG | CAN_ERR_BUSOFF, {0, 0, 0, 0, 0, 0, 0, 0}));
  ASSERT_TRUE(run_until(io, [&] { return bus->state() == BusState::bus_off; }));
  pair.write(raw_frame(0x55, {5}));
  ASSERT_TRUE(run(io, bus->receive(5s)));
  EXPECT_EQ(bus->state(), BusState::active);
}

TEST(SocketCanBus, ErrorReportCounters) {
  asio::io_context io;
  Pair pair(SOCK_SEQPACKET);
  auto bus = adopt(io, pair);
  pair.write(raw_frame(CAN_ERR_FLAG | CAN_ERR_LOSTARB | CAN_ERR_ACK | CAN_ERR_BUSERROR | 0x200 /* counters */,
                       {3, 0, 0, 0, 0, 0, 100, 7}));
  pair.write(raw_frame(CAN_ERR_FLAG | CAN_ERR_CRTL | CAN_ERR_TX_TIMEOUT, {0, CAN_ERR_CRTL_RX_OVERFLOW, 0, 0, 0, 0, 0, 0}));
  pair.write(raw_frame(0x1, {}));
  ASSERT_TRUE(run(io, bus->receive(5s)));
  const auto& s = bus->socketcan_stats();
  EXPECT_EQ(s.lost_arbitration, 1u);
  EXPECT_EQ(s.no_ack, 1u);
  EXPECT_EQ(s.bus_errors, 1u);
  EXPECT_EQ(s.tx_timeout_reports, 1u);
  EXPECT_EQ(s.controller_rx_overflows, 1u);
  EXPECT_EQ(s.tx_error_counter, 100);
  EXPECT_EQ(s.rx_error_counter, 7);
  EXPECT_EQ(bus->stats().rx_dropped, 1u);  // the controller lost a frame
  EXPECT_EQ(bus->stats().error_frames, 2u);
  EXPECT_EQ(bus->state(), BusState::active);
}

TEST(SocketCanBus, BadRecordsAreCountedAndTheBusStaysOpen) {
  asio::io_context io;
  Pair pair(SOCK_SEQPACKET);
  auto bus = adopt(io, pair);
  const std::array<std::uint8_t, 10> short_record{};
  const std::array<std::uint8_t, 72> fd_record{};
  std::array<std::uint8_t, 300> huge{};
  pair.write(short_record.data(), short_record.size());
  pair.write(fd_record.data(), fd_record.size());
  pair.write(huge.data(), huge.size());
  auto too_long = raw_frame(0x123, {});
  too_long.len = 9;
  pair.write(too_long);
  pair.write(raw_frame(0x321, {3, 2, 1}));
  auto f = run(io, bus->receive(5s));
  ASSERT_TRUE(f);
  EXPECT_EQ(f.value().id(), 0x321u);
  EXPECT_EQ(bus->stats().protocol_errors, 4u);
  EXPECT_TRUE(bus->is_open());
}

TEST(SocketCanBus, ZeroLengthDatagramIsABadRecordNotTheEnd) {
  asio::io_context io;
  Pair pair(SOCK_DGRAM);
  auto bus = adopt(io, pair);
  pair.write("", 0);
  pair.write(raw_frame(0x10, {}));
  ASSERT_TRUE(run(io, bus->receive(5s)));
  EXPECT_EQ(bus->stats().protocol_errors, 1u);
  EXPECT_TRUE(bus->is_open());
}

TEST(SocketCanBus, PeerClosingClosesTheBus) {
  asio::io_context io;
  Pair pair(SOCK_SEQPACKET);
  auto bus = adopt(io, pair);
  pair.write(raw_frame(0x10, {}));
  ::close(std::exchange(pair.peer, -1));
  EXPECT_TRUE(run(io, bus->receive(5s)));  // what came before the close is still delivered
  auto r = run(io, bus->receive(5s));
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error(), CanErrc::closed);
  EXPECT_FALSE(bus->is_open());
}

TEST(SocketCanBus, FiltersApplyOnAnAdoptedSocket) {
  asio::io_context io;
  Pair pair(SOCK_SEQPACKET);
  SocketCanOptions opts;
  opts.filters = {Filter::parse("200:700").value()};
  auto bus = adopt(io, pair, opts);
  pair.write(raw_frame(0x100, {}));
  pair.write(raw_frame(0x2AB, {}));
  auto f = run(io, bus->receive(5s));
  ASSERT_TRUE(f);
  EXPECT_EQ(f.value().id(), 0x2ABu);
  EXPECT_EQ(bus->stats().rx_filtered, 1u);

  bus->set_filters({Filter::parse("100:7FF").value()});
  pair.write(raw_frame(0x2AB, {}));
  pair.write(raw_frame(0x100, {}));
  f = run(io, bus->receive(5s));
  ASSERT_TRUE(f);
  EXPECT_EQ(f.value().id(), 0x100u);
  EXPECT_EQ(bus->stats().rx_filtered, 2u);
}

namespace {
// Fills the peer's receive queue through the bus until a send has to wait; returns frames sent.
std::size_t fill_until_blocked(asio::io_context& io, SocketCanBus& bus, std::vector<Result<void>>& results) {
  std::size_t started = 0;
  while (bus.socketcan_stats().tx_retries == 0 && started < 100000) {
    const auto f = Frame::extended(static_cast<std::uint32_t>(started), {}).value();
    asio::co_spawn(io, [&bus, &results, f]() -> asio::awaitable<void> { results.push_back(co_await bus.send(f)); },
                   asio::detached);
    ++started;
    io.poll();
  }
  return started;
}
}  // namespace

TEST(SocketCanBus, FullKernelQueueWaitsAndKeepsOrder) {
  asio::io_context io;
  Pair pair(SOCK_DGRAM);
  SocketCanOptions opts;
  opts.tx_timeout = 60s;  // never reached here
  auto bus = adopt(io, pair, opts);
  std::vector<Result<void>> results;
  const std::size_t blocked_at = fill_until_blocked(io, *bus, results);
  ASSERT_GT(bus->socketcan_stats().tx_retries, 0u) << "the socket never filled up";
  // More senders queue up behind the blocked one.
  const std::size_t total = blocked_at + 20;
  for (std::size_t i = blocked_at; i < total; ++i) {
    const auto f = Frame::extended(static_cast<std::uint32_t>(i), {}).value();
    asio::co_spawn(io, [&, f]() -> asio::awaitable<void> { results.push_back(co_await bus->send(f)); }, asio::detached);
  }
  io.poll();
  EXPECT_GT(bus->tx_pending(), 20u);
  EXPECT_LT(results.size(), total);

  // Now read everything on the other end: every frame arrives once, in the order sent.
  std::vector<std::uint32_t> ids;
  ASSERT_TRUE(run_until(io, [&] {
    struct can_frame cf {};
    while (::recv(pair.peer, &cf, sizeof cf, MSG_DONTWAIT) == static_cast<ssize_t>(sizeof cf))
      ids.push_back(cf.can_id & CAN_EFF_MASK);
    return ids.size() == total && results.size() == total;
  }));
  for (std::size_t i = 0; i < total; ++i) ASSERT_EQ(ids[i], i);
  for (const auto& r : results) EXPECT_TRUE(r) << r.error().message();
  EXPECT_EQ(bus->stats().frames_out, total);
  EXPECT_EQ(bus->tx_pending(), 0u);
}

TEST(SocketCanBus, FullKernelQueueTimesOutWithTxOverflow) {
  asio::io_context io;
  Pair pair(SOCK_DGRAM);
  SocketCanOptions opts;
  opts.tx_timeout = 20ms;
  auto bus = adopt(io, pair, opts);
  std::vector<Result<void>> results;
  const std::size_t started = fill_until_blocked(io, *bus, results);
  ASSERT_TRUE(run_until(io, [&] { return results.size() == started; }));
  const auto& last = results.back();
  ASSERT_FALSE(last);
  EXPECT_EQ(last.error(), CanErrc::tx_overflow);
  EXPECT_EQ(bus->socketcan_stats().tx_timeouts, 1u);
  EXPECT_EQ(bus->stats().tx_dropped, 1u);
  EXPECT_EQ(bus->stats().frames_out, started - 1);
  EXPECT_TRUE(bus->is_open());  // a full queue is not fatal
}

TEST(SocketCanBus, CloseWakesWaitingSenders) {
  asio::io_context io;
  Pair pair(SOCK_DGRAM);
  SocketCanOptions opts;
  opts.tx_timeout = 60s;
  auto bus = adopt(io, pair, opts);
  std::vector<Result<void>> results;
  const std::size_t started = fill_until_blocked(io, *bus, results);
  const auto f = Frame::standard(0x1, {}).value();
  asio::co_spawn(io, [&]() -> asio::awaitable<void> { results.push_back(co_await bus->send(f)); }, asio::detached);
  io.poll();
  bus->close();
  ASSERT_TRUE(run_until(io, [&] { return results.size() == started + 1; }));
  EXPECT_EQ(results[started - 1].error(), CanErrc::closed);
  EXPECT_EQ(results[started].error(), CanErrc::closed);
  auto again = run(io, bus->send(f));
  EXPECT_EQ(again.error(), CanErrc::closed);
}

TEST(SocketCanBus, DestroyingTheBusWithPendingReceiveWaitIsSafe) {
  asio::io_context io;
  Pair pair(SOCK_SEQPACKET);
  auto bus = adopt(io, pair);
  io.poll();  // the receive loop is now waiting on the socket
  bus.reset();
  io.poll();  // the loop's cancelled wait completes after the bus is gone
  EXPECT_EQ(::send(pair.peer, "x", 1, MSG_NOSIGNAL), -1);  // and the socket was closed

}

TEST(SocketCanBus, AdoptRefusesWhatIsNotADatagramSocket) {
  asio::io_context io;
  auto bad = SocketCanBus::adopt(io.get_executor(), -1, "x");
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error(), CanErrc::io);

  Pair stream(SOCK_STREAM);
  auto r = SocketCanBus::adopt(io.get_executor(), stream.bus_end, "x");
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error(), CanErrc::not_supported);
}

TEST(SocketCanBus, OpenOnThisKernelGivesATypedError) {
  asio::io_context io;
  const int probe = ::socket(PF_CAN, SOCK_RAW, CAN_RAW);
  const int probe_errno = errno;
  if (probe >= 0) ::close(probe);

  auto r = SocketCanBus::open(io.get_executor(), "axonnosuch0");
  ASSERT_FALSE(r);
  if (probe < 0 && probe_errno == EAFNOSUPPORT) {
    EXPECT_EQ(r.error(), CanErrc::not_supported);
    EXPECT_NE(r.error().detail.find("no SocketCAN (AF_CAN)"), std::string::npos) << r.error().message();
    EXPECT_NE(r.error().detail.find("socketcand"), std::string::npos);
  } else if (probe >= 0) {
    EXPECT_EQ(r.error(), CanErrc::io);
    EXPECT_NE(r.error().detail.find("axonnosuch0"), std::string::npos) << r.error().message();
  } else {
    EXPECT_TRUE(r.error() == CanErrc::not_supported || r.error() == CanErrc::io) << r.error().message();
  }

  // can0: opens on a machine that has one; otherwise the same kind of typed error.
  auto can0 = SocketCanBus::open(io.get_executor(), "can0");
  if (!can0) {
    EXPECT_TRUE(can0.error() == CanErrc::not_supported || can0.error() == CanErrc::io) << can0.error().message();
  }

  EXPECT_EQ(SocketCanBus::open(io.get_executor(), "").error(), CanErrc::bad_spec);
  EXPECT_EQ(SocketCanBus::open(io.get_executor(), "a-name-far-too-long-for-linux").error(), CanErrc::bad_spec);
}
