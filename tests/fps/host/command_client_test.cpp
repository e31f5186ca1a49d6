// The command client against a scripted fake device on a virtual bus: uid allocation and reuse,
// the 63-in-flight limit, timeouts, retries (reads only), late and unmatched replies, broadcast
// collection, response codes as typed errors, unsolicited frames, and the bus in-flight bound.
#include "axon/fps/host/command_client.hpp"

#include "fake_device.hpp"
#include "rig.hpp"

#include "axon/fps/host/concurrent.hpp"
#include "axon/fps/protocol/error.hpp"

#include <gtest/gtest.h>

#include <set>

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::host;
using namespace axon::fps::host::testing;
using protocol::CommandId;
using protocol::ResponseCode;

namespace {

protocol::Payload status_payload(std::uint64_t raw) { return protocol::PositionerStatus(raw).encode(); }

// Answers every unicast request to positioners in `ids` with COMMAND_ACCEPTED (GET_STATUS with a
// fixed status word, GET_ID with the id); broadcasts are answered by every positioner in `ids`.
FakeDevice::Script accept_all(std::set<std::uint16_t> ids) {
  return [ids](const protocol::Message& m) {
    std::vector<Outgoing> out;
    auto answer = [&](std::uint16_t id) {
      protocol::Payload p;
      if (m.id.command == protocol::number(CommandId::get_status)) p = status_payload(0x0C000101);
      if (m.id.command == protocol::number(CommandId::get_id)) p = protocol::Payload().put_u32(id);
      if (m.id.command == protocol::number(CommandId::get_current_position)) {
        p = protocol::ArmPositions{protocol::Angle::from_steps(268435456), protocol::Angle::from_steps(0)}.encode();
      }
      out.push_back({reply_to(m, id, ResponseCode::accepted, p)});
    };
    if (m.id.is_broadcast()) {
      for (auto id : ids) answer(id);
    } else if (ids.contains(m.id.positioner)) {
      answer(m.id.positioner);
    }
    return out;
  };
}

class CommandClientTest : public ::testing::Test {
 protected:
  void make(FakeDevice::Script script, ClientOptions options = {}) {
    fake = std::make_unique<FakeDevice>(*medium, std::move(script));
    client = std::make_unique<CommandClient>(*host_bus, std::move(options));
    runner.on_stop([this]() -> asio::awaitable<void> {
      co_await client->stop();
      fake->stop();
    });
  }

  Runner runner;
  std::shared_ptr<can::VirtualBus> medium = can::VirtualBus::create(runner.io.get_executor(), "fps0");
  std::unique_ptr<can::Bus> host_bus = medium->attach("host");
  std::unique_ptr<FakeDevice> fake;
  std::unique_ptr<CommandClient> client;
};

}  // namespace

TEST_F(CommandClientTest, RequestGetsItsReplyDecoded) {
  make(accept_all({5}));
  runner.run([&]() -> asio::awaitable<void> {
    auto st = co_await client->call<CommandId::get_status>(5);
    EXPECT_TRUE(st.has_value());
    if (st) { EXPECT_EQ(st.value().status.raw(), 0x0C000101u); }
    auto pos = co_await client->call<CommandId::get_current_position>(5);
    EXPECT_TRUE(pos.has_value());
    if (pos) { EXPECT_DOUBLE_EQ(pos.value().alpha.degrees(), 90.0); }
  });
  ASSERT_EQ(fake->requests().size(), 2u);
  EXPECT_EQ(fake->requests()[0].id.positioner, 5);
  EXPECT_EQ(fake->requests()[0].id.command, 3);
  EXPECT_NE(fake->requests()[0].id.uid, 0);
  EXPECT_EQ(client->counters().sent, 2u);
  EXPECT_EQ(client->counters().replies, 2u);
  EXPECT_EQ(client->counters().by_code[0], 2u);
  EXPECT_EQ(client->in_flight(), 0u);
}

TEST_F(CommandClientTest, UidsCountUpPerPositionerAndCommandAndWrapAfter63) {
  make(accept_all({5, 6}));
  runner.run([&]() -> asio::awaitable<void> {
    for (int i = 0; i < 65; ++i) {
      const bool ok_ = (co_await client->request(5, CommandId::switch_on_led)).has_value();
      EXPECT_TRUE(ok_);
    }
    {
      const bool ok_ = (co_await client->request(6, CommandId::switch_on_led)).has_value();
      EXPECT_TRUE(ok_);
    }
    {
      const bool ok_ = (co_await client->request(5, CommandId::get_status)).has_value();
      EXPECT_TRUE(ok_);
    }
  });
  const auto& reqs = fake->requests();
  ASSERT_EQ(reqs.size(), 67u);
  for (int i = 0; i < 63; ++i) EXPECT_EQ(reqs[i].id.uid, i + 1) << i;
  EXPECT_EQ(reqs[63].id.uid, 1);  // wraps to 1, never 0
  EXPECT_EQ(reqs[64].id.uid, 2);
  EXPECT_EQ(reqs[65].id.uid, 1);  // another positioner has its own pool
  EXPECT_EQ(reqs[66].id.uid, 1);  // another command too
}

TEST_F(CommandClientTest, AtMost63OfOneCommandInFlightToOneRobotTheRestWait) {
  ClientOptions o;
  o.timeout = 30s;  // replies are held back on purpose; never let them time out
  make(silent(), o);
  std::vector<Result<Reply>> results;
  runner.run([&]() -> asio::awaitable<void> {
    for (int i = 0; i < 70; ++i) {
      spawn(runner.io, client->request(9, CommandId::switch_on_led),
            [&](Result<Reply> r) { results.push_back(std::move(r)); });
    }
    {
      const bool ok_ = co_await eventually([&] { return fake->requests().size() >= 63 && client->counters().uid_waits == 7; });
      EXPECT_TRUE(ok_);
    }
    EXPECT_EQ(fake->requests().size(), 63u);
    EXPECT_EQ(client->in_flight(), 63u);
    std::set<int> uids;
    for (const auto& m : fake->requests()) uids.insert(m.id.uid);
    EXPECT_EQ(uids.size(), 63u);
    EXPECT_EQ(*uids.begin(), 1);
    EXPECT_EQ(*uids.rbegin(), 63);
    // Answer everything that arrived so far, then everything that follows.
    fake->set_script(accept_all({9}));
    for (const auto& m : std::vector<protocol::Message>(fake->requests())) co_await fake->send(reply_to(m, 9));
    {
      const bool ok_ = co_await eventually([&] { return results.size() == 70; });
      EXPECT_TRUE(ok_);
    }
  });
  ASSERT_EQ(results.size(), 70u);
  for (const auto& r : results) EXPECT_TRUE(r.has_value());
  EXPECT_EQ(fake->requests().size(), 70u);
  for (std::size_t i = 63; i < 70; ++i) EXPECT_EQ(fake->requests()[i].id.uid, i - 62) << "uids are reused from 1";
  EXPECT_EQ(client->counters().timeouts, 0u);
}

TEST_F(CommandClientTest, TimeoutWithoutRetryForCommandsThatChangeState) {
  ClientOptions o;
  o.timeout = 30ms;
  make(silent(), o);
  runner.run([&]() -> asio::awaitable<void> {
    auto r = co_await client->request(4, CommandId::go_to_absolute_position,
                                      protocol::ArmPositions{}.encode());
    EXPECT_FALSE(r.has_value());
    if (!r) {
      EXPECT_EQ(r.error(), HostErrc::timeout);
      EXPECT_NE(r.error().message().find("GO_TO_ABSOLUTE_POSITION"), std::string::npos) << r.error().message();
    }
  });
  EXPECT_EQ(fake->count(CommandId::go_to_absolute_position), 1u);
  EXPECT_EQ(client->counters().timeouts, 1u);
  EXPECT_EQ(client->counters().retries, 0u);
}

TEST_F(CommandClientTest, ReadsAreRetriedAfterATimeoutWithFreshUids) {
  ClientOptions o;
  o.timeout = 30ms;
  o.read_retries = 2;
  make(silent(), o);
  runner.run([&]() -> asio::awaitable<void> {
    auto r = co_await client->request(4, CommandId::get_status);
    EXPECT_FALSE(r.has_value());
    if (!r) { EXPECT_EQ(r.error(), HostErrc::timeout); }
  });
  ASSERT_EQ(fake->requests().size(), 3u);
  EXPECT_EQ(fake->requests()[0].id.uid, 1);
  EXPECT_EQ(fake->requests()[1].id.uid, 2);
  EXPECT_EQ(fake->requests()[2].id.uid, 3);
  EXPECT_EQ(client->counters().timeouts, 3u);
  EXPECT_EQ(client->counters().retries, 2u);
}

TEST_F(CommandClientTest, ARetriedReadSucceedsWhenALaterAttemptIsAnswered) {
  ClientOptions o;
  o.timeout = 30ms;
  int seen = 0;
  make(
      [&](const protocol::Message& m) {
        if (++seen == 1) return std::vector<Outgoing>{};  // the first reply is lost
        return std::vector<Outgoing>{{reply_to(m, 4, ResponseCode::accepted, status_payload(1))}};
      },
      o);
  runner.run([&]() -> asio::awaitable<void> {
    auto r = co_await client->call<CommandId::get_status>(4);
    EXPECT_TRUE(r.has_value());
  });
  EXPECT_EQ(fake->requests().size(), 2u);
  EXPECT_EQ(client->counters().retries, 1u);
  EXPECT_EQ(client->counters().timeouts, 1u);
}

TEST_F(CommandClientTest, LateAndUnmatchedRepliesAreCountedAndIgnored) {
  ClientOptions o;
  o.timeout = 20ms;
  o.read_retries = 0;
  make(silent(), o);
  runner.run([&]() -> asio::awaitable<void> {
    auto r = co_await client->request(4, CommandId::get_offsets);
    EXPECT_FALSE(r.has_value());
    EXPECT_EQ(fake->requests().size(), 1u);
    // The reply to the timed-out request comes after all, then one nobody ever asked for.
    co_await fake->send(reply_to(fake->requests()[0], 4));
    co_await fake->send(protocol::make_reply(4, protocol::number(CommandId::get_offsets), 40,
                                             ResponseCode::accepted, {}).value());
    {
      const bool ok_ = co_await eventually([&] { return client->counters().late + client->counters().unmatched == 2; });
      EXPECT_TRUE(ok_);
    }
    // The client still works, and the late reply did not complete anything.
    fake->set_script(accept_all({4}));
    auto r2 = co_await client->request(4, CommandId::get_offsets);
    EXPECT_TRUE(r2.has_value());
  });
  EXPECT_EQ(client->counters().late, 1u);
  EXPECT_EQ(client->counters().unmatched, 1u);
  EXPECT_EQ(client->counters().replies, 1u);
  ASSERT_EQ(fake->requests().size(), 2u);
  EXPECT_NE(fake->requests()[0].id.uid, fake->requests()[1].id.uid);
}

TEST_F(CommandClientTest, BroadcastCollectsRepliesUntilTheExpectedCount) {
  make(accept_all({3, 7, 9}));
  runner.run([&]() -> asio::awaitable<void> {
    BroadcastOptions b;
    b.expected = 3;
    b.window = 30s;  // reaching the count ends the collection, not the window
    auto r = co_await client->broadcast(CommandId::get_id, {}, b);
    EXPECT_TRUE(r.has_value());
    if (r) {
      EXPECT_TRUE(r.value().complete);
      EXPECT_EQ(r.value().replies.size(), 3u);
      EXPECT_NE(r.value().from(7), nullptr);
      EXPECT_EQ(r.value().from(8), nullptr);
    }
  });
  ASSERT_EQ(fake->requests().size(), 1u);
  EXPECT_EQ(fake->requests()[0].id.positioner, 0);
  EXPECT_EQ(fake->requests()[0].id.uid, 0);
  EXPECT_EQ(client->counters().broadcasts, 1u);
  EXPECT_EQ(client->counters().replies, 3u);
}

TEST_F(CommandClientTest, BroadcastWithoutCountCollectsForTheWindowAndCountsDuplicates) {
  ClientOptions o;
  o.broadcast_window = 50ms;
  make(
      [](const protocol::Message& m) {
        return std::vector<Outgoing>{{reply_to(m, 3)}, {reply_to(m, 7)}, {reply_to(m, 7)},
                                     {reply_to(m, 9, ResponseCode::invalid_command)}};
      },
      o);
  runner.run([&]() -> asio::awaitable<void> {
    auto r = co_await client->broadcast(CommandId::get_firmware_version);
    EXPECT_TRUE(r.has_value());
    if (r) {
      EXPECT_FALSE(r.value().complete);
      EXPECT_EQ(r.value().positioners(), (std::vector<std::uint16_t>{3, 7, 9}));
      EXPECT_EQ(r.value().duplicates, 1u);
      EXPECT_NE(r.value().from(9), nullptr);
      if (r.value().from(9)) { EXPECT_EQ(r.value().from(9)->code, ResponseCode::invalid_command); }
    }
  });
  EXPECT_EQ(client->counters().broadcast_duplicates, 1u);
  EXPECT_EQ(client->counters().by_code[12], 1u);
}

TEST_F(CommandClientTest, BroadcastOfAUnicastOnlyCommandIsRefusedBeforeSending) {
  make(silent());
  runner.run([&]() -> asio::awaitable<void> {
    auto r = co_await client->broadcast(CommandId::go_to_datums);
    EXPECT_FALSE(r.has_value());
    if (!r) { EXPECT_EQ(r.error(), protocol::ProtocolErrc::broadcast_not_allowed); }
    auto u = co_await client->request(0, CommandId::get_status);
    EXPECT_FALSE(u.has_value());
    if (!u) { EXPECT_EQ(u.error(), HostErrc::invalid_argument); }
    auto w = co_await client->request(3, CommandId::set_speed, protocol::Payload().put_u32(1));
    EXPECT_FALSE(w.has_value());
    if (!w) { EXPECT_EQ(w.error(), protocol::ProtocolErrc::wrong_length); }
    auto c = co_await client->request(3, CommandId::collision_detected);
    EXPECT_FALSE(c.has_value());
    if (!c) { EXPECT_EQ(c.error(), protocol::ProtocolErrc::not_sendable); }
  });
  EXPECT_TRUE(fake->requests().empty());
  EXPECT_EQ(client->counters().sent, 0u);
}

TEST_F(CommandClientTest, ResponseCodesComeBackAsTypedErrorsWithNameAndAdvice) {
  make([](const protocol::Message& m) {
    if (m.id.command == protocol::number(CommandId::go_to_absolute_position)) {
      return std::vector<Outgoing>{{reply_to(m, m.id.positioner, ResponseCode::already_in_motion)}};
    }
    return std::vector<Outgoing>{{reply_to(m, m.id.positioner, ResponseCode::datum_not_initialized)}};
  });
  runner.run([&]() -> asio::awaitable<void> {
    auto r = co_await client->request(12, CommandId::go_to_absolute_position, protocol::ArmPositions{}.encode());
    EXPECT_FALSE(r.has_value());
    if (!r) {
      EXPECT_EQ(r.error(), ResponseCode::already_in_motion);
      const auto msg = r.error().message();
      EXPECT_NE(msg.find("ALREADY_IN_MOTION"), std::string::npos) << msg;
      EXPECT_NE(msg.find("STOP_TRAJECTORY"), std::string::npos) << msg;  // the advice
      EXPECT_NE(msg.find("positioner 12"), std::string::npos) << msg;
    }
    // A refusal is an answer: reads are not retried after one.
    auto g = co_await client->request(12, CommandId::get_current_position);
    EXPECT_FALSE(g.has_value());
    if (!g) { EXPECT_EQ(g.error(), ResponseCode::datum_not_initialized); }
  });
  EXPECT_EQ(fake->requests().size(), 2u);
  EXPECT_EQ(client->counters().by_code[3], 1u);
  EXPECT_EQ(client->counters().by_code[4], 1u);
  EXPECT_EQ(client->counters().errors(), 2u);
  EXPECT_EQ(client->counters().retries, 0u);
}

TEST_F(CommandClientTest, RepliesWhoseDataDoesNotFitAreTypedErrorsAndCounted) {
  make([](const protocol::Message& m) {
    return std::vector<Outgoing>{
        {reply_to(m, m.id.positioner, ResponseCode::accepted, protocol::Payload().put_u8(1).put_u8(2).put_u8(3))}};
  });
  runner.run([&]() -> asio::awaitable<void> {
    auto r = co_await client->call<CommandId::get_status>(3);
    EXPECT_FALSE(r.has_value());
    if (!r) { EXPECT_EQ(r.error(), HostErrc::bad_reply); }
  });
  EXPECT_EQ(client->counters().bad_replies, 1u);
}

TEST_F(CommandClientTest, UnsolicitedFramesGoToSubscribersAndBroadcastRepliesToTheirCollection) {
  make(silent());
  std::vector<Unsolicited> seen;
  runner.run([&]() -> asio::awaitable<void> {
    client->subscribe([&](const Unsolicited& u) { seen.push_back(u); });
    co_await fake->send(unsolicited(21, CommandId::collision_detected, ResponseCode::beta_collision));
    co_await fake->send(unsolicited(22, CommandId::start_trajectory));  // started by the sync line
    {
      const bool ok_ = co_await eventually([&] { return seen.size() == 2; });
      EXPECT_TRUE(ok_);
    }
    // While a START_TRAJECTORY broadcast collects, uid-0 replies of that command belong to it;
    // collision reports still go to the subscribers.
    fake->set_script([](const protocol::Message& m) {
      return std::vector<Outgoing>{{reply_to(m, 22)}, {unsolicited(23, CommandId::collision_detected, ResponseCode::alpha_collision)}};
    });
    BroadcastOptions b;
    b.expected = 1;
    auto r = co_await client->broadcast(CommandId::start_trajectory, {}, b);
    EXPECT_TRUE(r.has_value());
    if (r) { EXPECT_EQ(r.value().positioners(), (std::vector<std::uint16_t>{22})); }
    {
      const bool ok_ = co_await eventually([&] { return seen.size() == 3; });
      EXPECT_TRUE(ok_);
    }
  });
  ASSERT_EQ(seen.size(), 3u);
  EXPECT_TRUE(seen[0].is_collision());
  EXPECT_EQ(seen[0].positioner, 21);
  EXPECT_EQ(seen[0].code, ResponseCode::beta_collision);
  EXPECT_FALSE(seen[1].is_collision());
  EXPECT_EQ(seen[1].command, protocol::number(CommandId::start_trajectory));
  EXPECT_TRUE(seen[2].is_collision());
  EXPECT_EQ(seen[2].positioner, 23);
  EXPECT_EQ(client->counters().collisions, 2u);
  EXPECT_EQ(client->counters().unsolicited, 3u);
}

TEST_F(CommandClientTest, FramesThatAreNotPositionerRepliesAreCountedAsForeign) {
  make(silent());
  const std::vector<std::uint8_t> one{1};  // built outside the coroutine (gcc 12 trips over it inside)
  const auto standard = can::Frame::standard(0x123, one).value();
  runner.run([&]() -> asio::awaitable<void> {
    co_await fake->send(standard);
    co_await fake->send(protocol::make_request(0, CommandId::get_id, 0).value());  // another host's broadcast
    {
      const bool ok_ = co_await eventually([&] { return client->counters().foreign == 2; });
      EXPECT_TRUE(ok_);
    }
  });
  EXPECT_EQ(client->counters().foreign, 2u);
  EXPECT_EQ(client->counters().unmatched, 0u);
}

TEST_F(CommandClientTest, TheBusInFlightBoundHoldsRequestsBack) {
  ClientOptions o;
  o.max_in_flight = 4;
  o.timeout = 30s;
  make(silent(), o);
  std::size_t done = 0;
  runner.run([&]() -> asio::awaitable<void> {
    for (std::uint16_t id = 1; id <= 10; ++id) {
      spawn(runner.io, client->request(id, CommandId::switch_on_led), [&](Result<Reply> r) {
        EXPECT_TRUE(r.has_value());
        ++done;
      });
    }
    {
      const bool ok_ = co_await eventually([&] { return client->counters().slot_waits == 6 && fake->requests().size() == 4; });
      EXPECT_TRUE(ok_);
    }
    EXPECT_EQ(fake->requests().size(), 4u);
    EXPECT_EQ(client->in_flight(), 4u);
    fake->set_script(accept_all({1, 2, 3, 4, 5, 6, 7, 8, 9, 10}));
    for (const auto& m : std::vector<protocol::Message>(fake->requests())) co_await fake->send(reply_to(m, m.id.positioner));
    {
      const bool ok_ = co_await eventually([&] { return done == 10; });
      EXPECT_TRUE(ok_);
    }
  });
  EXPECT_EQ(done, 10u);
  EXPECT_EQ(fake->requests().size(), 10u);
}

TEST_F(CommandClientTest, StopCancelsWaitingRequests) {
  ClientOptions o;
  o.timeout = 30s;
  make(silent(), o);
  std::optional<Result<Reply>> result;
  runner.run([&]() -> asio::awaitable<void> {
    spawn(runner.io, client->request(3, CommandId::switch_on_led), [&](Result<Reply> r) { result = std::move(r); });
    {
      const bool ok_ = co_await eventually([&] { return fake->requests().size() == 1; });
      EXPECT_TRUE(ok_);
    }
    co_await client->stop();
    {
      const bool ok_ = co_await eventually([&] { return result.has_value(); });
      EXPECT_TRUE(ok_);
    }
    EXPECT_FALSE(client->running());
  });
  ASSERT_TRUE(result.has_value());
  EXPECT_FALSE(result->has_value());
  if (!result->has_value()) { EXPECT_EQ(result->error(), HostErrc::cancelled); }
}

TEST_F(CommandClientTest, AClosedBusFailsRequests) {
  make(silent());
  runner.run([&]() -> asio::awaitable<void> {
    host_bus->close();
    {
      const bool ok_ = co_await eventually([&] { return !client->running(); });
      EXPECT_TRUE(ok_);
    }
    auto r = co_await client->request(3, CommandId::get_status);
    EXPECT_FALSE(r.has_value());
    if (!r) { EXPECT_EQ(r.error(), HostErrc::closed); }
  });
}

// --- fault injection on the medium ------------------------------------------------------------

TEST_F(CommandClientTest, DuplicatedRepliesAreCountedNotMisattributed) {
  make(accept_all({8}));
  // Requests and replies of positioner 8's GET_STATUS share the identifier (only the sender
  // differs), so they alternate on the medium: duplicate every second matching frame, the replies.
  // A rule that fires hides the frame from the rules after it, so rule k has seen k frames fewer.
  can::FaultPlan plan;
  for (std::uint64_t k = 0; k < 5; ++k) {
    can::FaultRule dup;
    dup.action = can::FaultRule::Action::duplicate;
    dup.match = can::Filter{(8u << 18) | (3u << 10), (0x7FFu << 18) | (0xFFu << 10), can::Filter::Format::extended};
    dup.skip = k + 1;
    dup.count = 1;
    plan.rules.push_back(dup);
  }
  medium->set_fault_plan(plan);
  runner.run([&]() -> asio::awaitable<void> {
    for (int i = 0; i < 5; ++i) {
      const bool ok_ = (co_await client->call<CommandId::get_status>(8)).has_value();
      EXPECT_TRUE(ok_);
    }
    {
      const bool ok_ = co_await eventually([&] { return client->counters().unmatched >= 5; });
      EXPECT_TRUE(ok_);
    }
  });
  EXPECT_EQ(client->counters().replies, 5u);
  EXPECT_EQ(client->counters().unmatched, 5u);
  EXPECT_EQ(client->counters().timeouts, 0u);
}

TEST_F(CommandClientTest, DroppedRepliesToReadsAreRecoveredByRetry) {
  ClientOptions o;
  o.timeout = 30ms;
  make(accept_all({8}), o);
  can::FaultPlan plan;
  can::FaultRule drop;
  drop.action = can::FaultRule::Action::drop;
  drop.match = can::Filter{(8u << 18) | (32u << 10), (0x7FFu << 18) | (0xFFu << 10), can::Filter::Format::extended};
  drop.skip = 1;   // the request passes (it matches the same filter) ...
  drop.count = 1;  // ... its reply is lost
  plan.rules.push_back(drop);
  medium->set_fault_plan(plan);
  runner.run([&]() -> asio::awaitable<void> {
    auto r = co_await client->call<CommandId::get_current_position>(8);
    EXPECT_TRUE(r.has_value());
  });
  EXPECT_EQ(fake->count(CommandId::get_current_position), 2u);
  EXPECT_EQ(client->counters().retries, 1u);
}

TEST_F(CommandClientTest, DelayedRepliesWithinTheTimeoutAreStillMatched) {
  ClientOptions o;
  o.timeout = 10s;
  make(accept_all({8}), o);
  can::FaultPlan plan;
  can::FaultRule delay;
  delay.action = can::FaultRule::Action::delay;
  delay.delay = 20ms;
  delay.match = can::Filter{8u << 18, 0x7FFu << 18, can::Filter::Format::extended};
  plan.rules.push_back(delay);
  medium->set_fault_plan(plan);
  runner.run([&]() -> asio::awaitable<void> {
    auto r = co_await client->call<CommandId::get_status>(8);
    EXPECT_TRUE(r.has_value());
  });
  EXPECT_EQ(client->counters().timeouts, 0u);
  EXPECT_EQ(client->counters().replies, 1u);
}

// Many robots pipelining at once behind a small bus in-flight bound, with replies coming back after
// varied delays: every robot must receive its requests in the order of the run (a trajectory point
// that overtakes the one before it is refused by the robot). A request woken with a freed slot
// resumes a little later; a later request of the same pipeline must not slip past it meanwhile.
TEST(CommandClientPipeline, ReachesEachRobotInOrderUnderTheInFlightBound) {
  constexpr std::uint16_t kRobots = 24;
  constexpr std::size_t kRequests = 40;
  std::size_t out_of_order = 0, failed = 0, checked = 0;
  for (std::uint32_t seed = 1; seed <= 12; ++seed) {
    Runner runner;
    auto medium = can::VirtualBus::create(runner.io.get_executor(), "fps0");
    auto host_bus = medium->attach("host");
    std::uint32_t x = seed;
    FakeDevice fake(*medium, [&x](const protocol::Message& m) {
      x = x * 1664525u + 1013904223u;
      // Some replies at once, some a little later: completions interleave with slot grants.
      const auto delay = (x >> 24) % 2 == 0 ? std::chrono::microseconds((x >> 8) % 200) : core::Duration::zero();
      return std::vector<Outgoing>{{reply_to(m, m.id.positioner), delay}};
    });
    ClientOptions o;
    o.max_in_flight = 4 + seed % 3 * 6;
    CommandClient client(*host_bus, o);
    std::vector<std::vector<protocol::Request>> runs(kRobots + 1);
    for (std::uint16_t id = 1; id <= kRobots; ++id) {
      for (std::size_t i = 0; i < kRequests; ++i) {
        // The index travels in the payload, so the order of arrival can be checked.
        runs[id].push_back({CommandId::send_trajectory_data,
                            protocol::Payload().put_u32(static_cast<std::uint32_t>(i)).put_u32(0)});
      }
    }
    runner.run([&]() -> asio::awaitable<void> {
      co_await for_each_concurrently(kRobots, [&](std::size_t k) -> asio::awaitable<void> {
        const auto id = static_cast<std::uint16_t>(k + 1);
        auto r = co_await client.pipeline(id, runs[id], 8);
        failed += r.ok() ? 0 : 1;
      });
      co_await client.stop();
      fake.stop();
    });
    std::vector<std::uint32_t> next(kRobots + 1, 0);
    for (const auto& m : fake.requests()) {
      if (m.id.command != protocol::number(CommandId::send_trajectory_data)) continue;
      const std::uint32_t index = m.payload[0] | std::uint32_t{m.payload[1]} << 8 | std::uint32_t{m.payload[2]} << 16;
      if (index != next[m.id.positioner]) ++out_of_order;
      next[m.id.positioner] = index + 1;
      ++checked;
    }
  }
  EXPECT_EQ(failed, 0u);
  EXPECT_EQ(checked, 12u * kRobots * kRequests);
  EXPECT_EQ(out_of_order, 0u);
}

// The in-flight bound hands a freed slot to the oldest waiting request; that request resumes a
// little later. A request made meanwhile (here the next trajectory point of the same robot, right
// after another slot came free) must queue behind it instead of taking the free slot: otherwise
// the later point reaches the robot first and the robot refuses the earlier one.
TEST_F(CommandClientTest, AWokenRequestKeepsItsSlotAgainstNewcomers) {
  std::optional<protocol::Message> held;
  make(
      [&held](const protocol::Message& m) {
        std::vector<Outgoing> out;
        if (m.id.positioner == 5) {
          held = m;  // answered together with robot 6's request, in one burst
        } else if (m.id.positioner == 6) {
          if (held) out.push_back({reply_to(*held, 5)});
          out.push_back({reply_to(m, 6)});
        } else {
          out.push_back({reply_to(m, m.id.positioner)});
        }
        return out;
      },
      [] {
        ClientOptions o;
        o.max_in_flight = 2;
        return o;
      }());
  auto point = [](std::uint32_t i) { return protocol::Payload().put_u32(i).put_u32(0); };
  runner.run([&]() -> asio::awaitable<void> {
    std::size_t done = 0;
    auto other = [&](std::uint16_t id, bool then_next_point) -> asio::awaitable<void> {
      auto r = co_await client->request(id, CommandId::get_status);
      EXPECT_TRUE(r.has_value());
      if (then_next_point) {
        const auto p1 = point(1);
        auto n = co_await client->request(1, CommandId::send_trajectory_data, p1);
        EXPECT_TRUE(n.has_value());
      }
      ++done;
    };
    auto first_point = [&]() -> asio::awaitable<void> {
      const auto p0 = point(0);
      auto r = co_await client->request(1, CommandId::send_trajectory_data, p0);
      EXPECT_TRUE(r.has_value());
      ++done;
    };
    asio::co_spawn(runner.io, other(5, false), asio::detached);  // takes slot 1
    asio::co_spawn(runner.io, other(6, true), asio::detached);   // takes slot 2
    asio::co_spawn(runner.io, first_point(), asio::detached);    // waits for a slot
    while (done < 3) co_await core::sleep_for(1ms);
  });
  std::vector<std::uint32_t> order;
  for (const auto& m : fake->requests()) {
    if (m.id.command == protocol::number(CommandId::send_trajectory_data)) order.push_back(m.payload[0]);
  }
  EXPECT_EQ(order, (std::vector<std::uint32_t>{0, 1}));
}
