// MotorSession and with_motors_enabled against the board simulator on the in-process virtual bus:
// whatever way the work with the motors ends, the simulated firmware ends with the system and both
// motors off and a zero current reference, and the caller gets the disable's result.
#include "axon/blmc/host/error.hpp"
#include "axon/blmc/host/motor_session.hpp"
#include "sim_rig.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

namespace axon::blmc::host {
namespace {

using namespace testing;

// What a user relies on after the session: nothing enabled, no current asked for, no error latched
// (a clean disable, not the board's receive timeout tripping).
void expect_board_off(const sim::Board& b) {
  EXPECT_FALSE(b.status().system_enabled);
  EXPECT_FALSE(b.motor_state(0).enabled);
  EXPECT_FALSE(b.motor_state(1).enabled);
  EXPECT_EQ(b.motor_state(0).iq_ref_a, 0.0);
  EXPECT_EQ(b.motor_state(1).iq_ref_a, 0.0);
  EXPECT_EQ(b.status().error, proto::ErrorCode::none);
}

// A controller that asks for a constant current.
struct ConstantCurrent final : Controller {
  MotorPair value{};
  void update(const ControlInput&, std::span<MotorPair> c) noexcept override { c[0] = value; }
};

// Starts cyclic mode and runs a loop asking for 0.3 A until the firmware follows it, then leaves
// the loop by `exit` (the loop object is destroyed on the way out, as in a real program).
asio::awaitable<int> drive_then(SimRig& rig, Board& board, const std::function<int()>& exit) {
  auto c = co_await board.start_cyclic();
  EXPECT_TRUE(c);
  ConstantCurrent ctl;
  ctl.value = {0.3, 0.0};
  ControlLoop loop({&board.port()}, ctl, {test_limits()}, loop_options());
  EXPECT_TRUE(loop.start());
  const bool driven = co_await eventually([&] { return rig.sim->motor_state(0).iq_ref_a > 0.29; });
  EXPECT_TRUE(driven);
  co_return exit();
}

TEST(BlmcMotorSession, DisablesAfterTheWorkEnds) {
  SimRig rig;
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host);
    const std::function<asio::awaitable<int>()> body = [&]() -> asio::awaitable<int> {
      const int rc = co_await drive_then(rig, board, [] { return 7; });
      co_return rc;
    };
    auto run = co_await with_motors_enabled<int>(board, body);
    EXPECT_TRUE(run.enable);
    EXPECT_EQ(run.value, 7);
    EXPECT_TRUE(run.disable) << (run.disable ? "" : run.disable.error().message());
    EXPECT_FALSE(board.cyclic());
    co_await eventually([&] { return !rig.sim->status().system_enabled; });
  });
  expect_board_off(*rig.sim);
}

// The root cause of `axon blmc --rate 0` leaving the board on: an exception after start_cyclic()
// (there: the loop refusing its period) met a disable() that refused to run in cyclic mode.
TEST(BlmcMotorSession, DisablesWhenTheWorkThrowsInCyclicMode) {
  SimRig rig;
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host);
    const std::function<asio::awaitable<int>()> body = [&]() -> asio::awaitable<int> {
      const int rc = co_await drive_then(rig, board, []() -> int { throw std::runtime_error("boom"); });
      co_return rc;
    };
    bool thrown = false;
    try {
      auto run = co_await with_motors_enabled<int>(board, body);
      (void)run;
    } catch (const std::runtime_error& e) {
      thrown = std::string(e.what()) == "boom";
    }
    EXPECT_TRUE(thrown) << "the body's exception is passed on after the disable";
    EXPECT_FALSE(board.cyclic());
    co_await eventually([&] { return !rig.sim->status().system_enabled; });
  });
  expect_board_off(*rig.sim);
}

TEST(BlmcMotorSession, FailedEnableLeavesTheBoardDisabled) {
  auto cfg = SimRig::config();
  cfg.alignment_time = 5s;  // longer than the ready timeout below
  SimRig rig(cfg);
  rig.run([&]() -> asio::awaitable<void> {
    BoardOptions bo;
    bo.ready_timeout = 300ms;
    Board board(*rig.host, bo);
    bool ran = false;
    const std::function<asio::awaitable<int>()> body = [&]() -> asio::awaitable<int> {
      ran = true;
      co_return 0;
    };
    auto run = co_await with_motors_enabled<int>(board, body);
    EXPECT_FALSE(run.enable);
    EXPECT_FALSE(ran);
    EXPECT_FALSE(run.value.has_value());
    EXPECT_TRUE(run.disable);
    co_await eventually([&] { return !rig.sim->status().system_enabled; });
  });
  expect_board_off(*rig.sim);
}

// A stop request (Ctrl-C) during the seconds of alignment ends the enable at once and disables.
TEST(BlmcMotorSession, InterruptDuringEnableDisables) {
  auto cfg = SimRig::config();
  cfg.alignment_time = 30s;
  SimRig rig(cfg);
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host);
    asio::co_spawn(
        rig.io,
        [&]() -> asio::awaitable<void> {
          co_await eventually([&] { return rig.sim->motor_state(0).aligning; });
          board.interrupt();
        },
        asio::detached);
    MotorSession session(board);
    auto e = co_await session.enable();
    CO_ASSERT(!e);
    EXPECT_EQ(e.error(), HostErrc::interrupted);
    EXPECT_FALSE(session.active());
    co_await eventually([&] { return !rig.sim->status().system_enabled; });
    // Later waits stay interrupted until cleared.
    auto st = co_await board.wait_status(2s);
    EXPECT_EQ(st.error(), HostErrc::interrupted);
  });
  expect_board_off(*rig.sim);
}

// A session destroyed while enabled (a coroutine abandoned by a stopped io_context, a forgotten
// end()) still has the disable sent, from its destructor.
TEST(BlmcMotorSession, AbandonedSessionQueuesTheDisable) {
  SimRig rig;
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host);
    {
      MotorSession session(board);
      auto e = co_await session.enable();
      CO_ASSERT(e);
      auto c = co_await board.send_currents({0.2, 0.0});
      EXPECT_TRUE(c);
      co_await eventually([&] { return rig.sim->motor_state(0).iq_ref_a > 0.19; });
      EXPECT_TRUE(session.active());
    }
    co_await eventually([&] { return !rig.sim->status().system_enabled; });
  });
  expect_board_off(*rig.sim);
}

// A board dropped with its motors on queues the disable on the bus's executor; when the owner
// then drops the bus too before the loop runs that work, the queued disable must end without
// touching the destroyed bus (before: heap-use-after-free under AddressSanitizer).
TEST(BlmcMotorSession, DisableQueuedByADroppedBoardOutlivesTheBus) {
  SimRig rig;
  rig.run([&]() -> asio::awaitable<void> {
    auto board = std::make_unique<Board>(*rig.host);
    auto e = co_await board->enable();
    CO_ASSERT(e);
    board.reset();      // queues the disable frames
    rig.host.reset();   // the bus goes before they are sent
  });
  rig.io.restart();
  rig.io.run_for(std::chrono::milliseconds(200));  // runs the queued disable
  SUCCEED();
}

}  // namespace
}  // namespace axon::blmc::host
