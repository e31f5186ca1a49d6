#include "axon/c4g/apps/correct.hpp"
#include "axon/c4g/apps/sensor_feed.hpp"

#include "harness.hpp"
#include "axon/net/udp_socket.hpp"

#include <fmt/format.h>

#include <array>
#include <chrono>
#include <cmath>
#include <string>
#include <thread>

using namespace axon;
using namespace axon::c4g;
using namespace axon::c4g::apps;
using namespace axon::c4g::apps::test;
using protocol::code;
using protocol::Mode;
using namespace std::chrono_literals;

namespace {

TEST(SensorFeedParse, AcceptsSpacesCommasSemicolonsAndDegrees) {
  std::array<double, 3> v{};
  ASSERT_TRUE(parse_feed_datagram("0.5, -1;2\n", v, false));
  EXPECT_EQ(v, (std::array<double, 3>{0.5, -1.0, 2.0}));
  ASSERT_TRUE(parse_feed_datagram("  90\t0 180 ", v, true));
  EXPECT_NEAR(v[0], std::numbers::pi / 2, 1e-12);
  EXPECT_NEAR(v[2], std::numbers::pi, 1e-12);
}

TEST(SensorFeedParse, RejectsWrongCountsWordsAndNonFiniteValues) {
  std::array<double, 3> v{};
  auto few = parse_feed_datagram("1 2", v, false);
  ASSERT_FALSE(few);
  EXPECT_NE(few.error().detail.find("2 values, the arm has 3 axes"), std::string::npos);
  EXPECT_FALSE(parse_feed_datagram("1 2 3 4", v, false));
  auto word = parse_feed_datagram("1 x 3", v, false);
  ASSERT_FALSE(word);
  EXPECT_NE(word.error().detail.find("value 2"), std::string::npos);
  EXPECT_FALSE(parse_feed_datagram("1 nan 3", v, false));
  EXPECT_FALSE(parse_feed_datagram("1 inf 3", v, false));
  EXPECT_FALSE(parse_feed_datagram("1 2 3x", v, false));
  EXPECT_FALSE(parse_feed_datagram("", v, false));
}

// Sends text datagrams to the feed from a separate socket, over loopback.
struct Sender {
  net::UdpSocket socket = net::UdpSocket::open(net::Endpoint{"127.0.0.1", 0}).value();
  net::SocketAddress to;
  explicit Sender(std::uint16_t port) : to{0x7f000001u, port} {}
  void send(const std::string& text) {
    ASSERT_TRUE(socket.send_to(std::as_bytes(std::span<const char>(text.data(), text.size())), to));
  }
};

// Polls until `done` or 5 s (loopback delivery is fast; the bound only keeps a broken test finite).
template <class F>
bool eventually(F done) {
  for (int i = 0; i < 5000 && !done(); ++i) std::this_thread::sleep_for(1ms);
  return done();
}

std::unique_ptr<SensorFeed> open_feed(std::size_t axes = 6) {
  SensorFeedOptions o;
  o.listen = net::Endpoint{"127.0.0.1", 0};
  o.axes = axes;
  return SensorFeed::open(o).value();
}

TEST(SensorFeed, PublishesTheLatestValuesAndCountsRejects) {
  auto feed = open_feed(3);
  Sender tx(feed->port());
  SensorFeed::Reading r;
  ASSERT_TRUE(feed->latest(r));
  EXPECT_EQ(r.steady_ns, 0);  // nothing yet
  tx.send("0.1 0.2 0.3");
  tx.send("oops");
  tx.send("0.4 0.5 0.6\n");
  ASSERT_TRUE(eventually([&] { return feed->accepted() == 2 && feed->rejected() == 1; }));
  ASSERT_TRUE(feed->latest(r));
  EXPECT_EQ(r.values[0], 0.4);
  EXPECT_EQ(r.values[2], 0.6);
  EXPECT_EQ(r.sequence, 2u);
  EXPECT_GT(r.steady_ns, 0);
  EXPECT_NE(feed->last_error().find("not a number"), std::string::npos);
}

TEST(SensorFeed, WithASourceOnlyThatSenderIsRead) {
  Sender sensor(0), stranger(0);
  SensorFeedOptions o;
  o.listen = net::Endpoint{"127.0.0.1", 0};
  o.axes = 1;
  o.source = net::Endpoint{"127.0.0.1", sensor.socket.local_port()};
  auto feed = SensorFeed::open(o).value();
  sensor.to.port = stranger.to.port = feed->port();
  stranger.send("0.7");
  sensor.send("0.1");
  ASSERT_TRUE(eventually([&] { return feed->accepted() == 1 && feed->foreign() == 1; }));
  SensorFeed::Reading r;
  ASSERT_TRUE(feed->latest(r));
  EXPECT_EQ(r.values[0], 0.1);
  EXPECT_EQ(feed->rejected(), 0u);
  o.source = net::Endpoint{"0.0.0.0", 0};
  EXPECT_FALSE(SensorFeed::open(o));  // names no host
}

TEST(SensorFeed, RejectsImpossibleAxisCounts) {
  SensorFeedOptions o;
  o.axes = 0;
  EXPECT_FALSE(SensorFeed::open(o));
  o.axes = SensorFeed::kMaxAxes + 1;
  EXPECT_FALSE(SensorFeed::open(o));
}

TEST(CorrectFeed, SlewsToTheSensorValuesWithinTheSpeedLimit) {
  std::shared_ptr<SensorFeed> feed = open_feed();
  Sender tx(feed->port());
  CorrectOptions o;
  o.feed = feed;
  o.feed_timeout_s = 60;  // no staleness in this test
  o.max_motor_speed = 10;  // 0.02 turns per 2 ms cycle
  o.limits.max_abs_rad = {30 * kDeg};  // the correction bounds allow it: the motors' limit decides
  o.limits.max_step_rad = {1.0};
  CorrectApp app(o);
  Harness h;
  h.start(app);
  h.set_modes(code(Mode::mode7));
  tx.send(fmt::format("0 0 0 {} 0 0", 20 * kDeg));  // a jump on axis 4: motors 4, 5 and 6 move
  ASSERT_TRUE(eventually([&] { return feed->accepted() == 1; }));
  std::array<double, 6> sum{};
  const double limit = o.max_motor_speed * h.period();
  for (int k = 0; k < 2000; ++k) {
    h.run(app);
    for (std::size_t j = 0; j < 6; ++j) {
      EXPECT_LE(std::fabs(h.rep.axes[j].d1), limit * (1 + 1e-6));
      sum[j] += h.rep.axes[j].d1;
    }
  }
  EXPECT_NEAR(sum[3], motor_of(h, 3, 20 * kDeg, 3), 1e-3);
  EXPECT_NEAR(sum[4], motor_of(h, 3, 20 * kDeg, 4), 1e-3);
  EXPECT_NEAR(sum[0], 0.0, 1e-9);
  EXPECT_EQ(app.stale_cycles(), 0u);
}

TEST(CorrectFeed, AStaleFeedReturnsTheCorrectionToZero) {
  std::shared_ptr<SensorFeed> feed = open_feed();
  Sender tx(feed->port());
  CorrectOptions o;
  o.feed = feed;
  o.feed_timeout_s = 0.05;
  CorrectApp app(o);
  Harness h;
  h.start(app);
  h.set_modes(code(Mode::mode7));
  h.run(app);  // nothing received yet: stale, zero correction
  EXPECT_EQ(h.rep.axes[0].d1, 0.0f);
  EXPECT_GE(app.stale_cycles(), 1u);
  tx.send(fmt::format("{} 0 0 0 0 0", 1 * kDeg));
  ASSERT_TRUE(eventually([&] { return feed->accepted() == 1; }));
  double sum = 0;
  for (int k = 0; k < 10; ++k) sum += h.run(app).axes[0].d1;
  EXPECT_NEAR(sum, motor_of(h, 0, 1 * kDeg, 0), 1e-5);
  std::this_thread::sleep_for(100ms);  // the sensor falls silent for longer than the timeout
  const auto stale_before = app.stale_cycles();
  for (int k = 0; k < 10; ++k) sum += h.run(app).axes[0].d1;
  EXPECT_NEAR(sum, 0.0, 1e-6);
  EXPECT_EQ(app.stale_cycles(), stale_before + 10);
  EXPECT_TRUE(contains(event_texts(app), "no feed values"));
}

TEST(CorrectFeed, AFeedWithTheWrongAxisCountIsRefused) {
  std::shared_ptr<SensorFeed> feed = open_feed(4);
  CorrectOptions o;
  o.feed = feed;
  CorrectApp app(o);
  Harness h;
  h.start(app);
  EXPECT_EQ(app.phase(), Phase::refused);
}

TEST(CorrectFeed, StopFadesToZeroThenExits) {
  std::shared_ptr<SensorFeed> feed = open_feed();
  Sender tx(feed->port());
  CorrectOptions o;
  o.feed = feed;
  o.feed_timeout_s = 60;
  o.ramp_s = 0.1;
  CorrectApp app(o);
  Harness h;
  h.start(app);
  h.set_modes(code(Mode::mode7));
  tx.send(fmt::format("{} 0 0 0 0 0", 2 * kDeg));
  ASSERT_TRUE(eventually([&] { return feed->accepted() == 1; }));
  double sum = 0;
  for (int k = 0; k < 20; ++k) sum += h.run(app).axes[0].d1;
  EXPECT_NEAR(sum, motor_of(h, 0, 2 * kDeg, 0), 1e-5);
  app.request_stop();
  int k = 0;
  for (; k < 1000 && !h.exit_requested(); ++k) sum += h.run(app).axes[0].d1;
  EXPECT_TRUE(h.exit_requested());
  EXPECT_NEAR(k, 51, 2);  // the 0.1 s fade at 2 ms
  EXPECT_NEAR(sum, 0.0, 1e-6);
}

TEST(CorrectFeed, ReadingsBeyondTheLimitAreRefusedAndNeverApplied) {
  std::shared_ptr<SensorFeed> feed = open_feed();
  Sender tx(feed->port());
  CorrectOptions o;
  o.feed = feed;
  o.feed_timeout_s = 60;
  CorrectApp app(o);
  Harness h;
  h.start(app);
  h.set_modes(code(Mode::mode7));
  tx.send(fmt::format("{} 0 0 0 0 0", 1 * kDeg));
  ASSERT_TRUE(eventually([&] { return feed->accepted() == 1; }));
  double sum = 0;
  for (int k = 0; k < 20; ++k) sum += h.run(app).axes[0].d1;
  EXPECT_NEAR(sum, motor_of(h, 0, 1 * kDeg, 0), 1e-5);
  // 90 deg, 9999 deg and 1e308 deg: each refused, the correction stays at the last good reading.
  for (const std::string& bad : {fmt::format("{} 0 0 0 0 0", 90 * kDeg), fmt::format("0 {} 0 0 0 0", 9999 * kDeg),
                                std::string("0 0 1e306 0 0 0")}) {
    const auto before = feed->accepted();
    tx.send(bad);
    ASSERT_TRUE(eventually([&] { return feed->accepted() == before + 1; }));
    for (int k = 0; k < 20; ++k) {
      const auto& r = h.run(app);
      for (std::size_t j = 0; j < 6; ++j) {
        ASSERT_TRUE(std::isfinite(r.axes[j].d1));
        if (j == 0) {
          sum += r.axes[j].d1;
        } else {
          EXPECT_EQ(r.axes[j].d1, 0.0f);
        }
      }
    }
    EXPECT_NEAR(sum, motor_of(h, 0, 1 * kDeg, 0), 1e-5) << bad;
  }
  EXPECT_EQ(app.refused_samples(), 3u);
  EXPECT_FALSE(app.has_error());
  EXPECT_EQ(app.phase(), Phase::running);
  const auto texts = event_texts(app);
  EXPECT_TRUE(contains(texts, "feed reading refused: a value is beyond the correction limit")) << texts.size();
  EXPECT_NE(app.summary().find("3 readings refused beyond the limits"), std::string::npos) << app.summary();
  EXPECT_NE(app.summary().find("last refused reading: axis 3 = 5.72958e+307 deg, beyond the correction limit 5 deg"),
            std::string::npos) << app.summary();
  // A good reading again: followed, at most 0.1 deg per cycle.
  tx.send(fmt::format("{} 0 0 0 0 0", 3 * kDeg));
  ASSERT_TRUE(eventually([&] { return feed->accepted() == 5; }));
  for (int k = 0; k < 30; ++k) {
    const double d = h.run(app).axes[0].d1;
    EXPECT_LE(std::fabs(d), std::fabs(motor_of(h, 0, 0.1 * kDeg, 0)) * (1 + 1e-5));
    sum += d;
  }
  EXPECT_NEAR(sum, motor_of(h, 0, 3 * kDeg, 0), 1e-5);
  EXPECT_GT(app.slewed_cycles(), 0u);
}

TEST(CorrectFeed, ExactlyOneSourceIsRequired) {
  std::shared_ptr<SensorFeed> feed = open_feed();
  CorrectOptions o;
  o.feed = feed;
  o.amplitude_rad = {0.01};
  EXPECT_THROW(CorrectApp{o}, Exception);
}

}  // namespace
