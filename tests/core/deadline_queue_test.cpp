// DeadlineQueue: one timer for the deadlines of many clients on one execution context.
#include "axon/core/deadline_queue.hpp"

#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>
#include <gtest/gtest.h>

#include <chrono>
#include <functional>
#include <memory>
#include <string>
#include <vector>

using namespace axon;
namespace asio = boost::asio;

namespace {

struct Recorder final : core::DeadlineClient {
  std::string name;
  std::vector<std::string>* log = nullptr;
  std::vector<core::TimePoint> called_at;
  std::function<void()> then;
  void on_deadline() override {
    called_at.push_back(std::chrono::steady_clock::now());
    log->push_back(name);
    if (then) then();
  }
};

}  // namespace

TEST(DeadlineQueue, OneQueuePerExecutionContext) {
  asio::io_context a, b;
  auto& qa = core::DeadlineQueue::of(a.get_executor());
  EXPECT_EQ(&qa, &core::DeadlineQueue::of(a.get_executor()));
  EXPECT_NE(&qa, &core::DeadlineQueue::of(b.get_executor()));
}

TEST(DeadlineQueue, CallsEachClientAtOrAfterItsTimeInTimeOrder) {
  asio::io_context io;
  auto& q = core::DeadlineQueue::of(io.get_executor());
  std::vector<std::string> log;
  Recorder x, y, z;
  x.name = "x", y.name = "y", z.name = "z";
  x.log = y.log = z.log = &log;
  const auto t0 = std::chrono::steady_clock::now();
  q.arm(x, t0 + std::chrono::milliseconds(6));
  q.arm(y, t0 + std::chrono::milliseconds(2));
  q.arm(z, t0 + std::chrono::milliseconds(4));
  EXPECT_EQ(y.armed(), t0 + std::chrono::milliseconds(2));
  io.run();
  EXPECT_EQ(log, (std::vector<std::string>{"y", "z", "x"}));
  ASSERT_EQ(x.called_at.size(), 1u);
  EXPECT_GE(x.called_at[0], t0 + std::chrono::milliseconds(6));
  EXPECT_GE(y.called_at[0], t0 + std::chrono::milliseconds(2));
  EXPECT_FALSE(x.armed().has_value());
}

TEST(DeadlineQueue, ArmingAgainReplacesAndDisarmRemoves) {
  asio::io_context io;
  auto& q = core::DeadlineQueue::of(io.get_executor());
  std::vector<std::string> log;
  Recorder x, y;
  x.name = "x", y.name = "y";
  x.log = y.log = &log;
  const auto t0 = std::chrono::steady_clock::now();
  q.arm(x, t0 + std::chrono::milliseconds(1));
  q.arm(x, t0 + std::chrono::milliseconds(3));  // replaces the first: called once, after 3 ms
  q.arm(y, t0 + std::chrono::milliseconds(2));
  q.disarm(y);
  io.run();
  EXPECT_EQ(log, (std::vector<std::string>{"x"}));
  ASSERT_EQ(x.called_at.size(), 1u);
  EXPECT_GE(x.called_at[0], t0 + std::chrono::milliseconds(3));
}

TEST(DeadlineQueue, DeadlinesAlreadyPastAreHandledInTheSameWakeUp) {
  asio::io_context io;
  auto& q = core::DeadlineQueue::of(io.get_executor());
  std::vector<std::string> log;
  Recorder x;
  x.name = "x";
  x.log = &log;
  const auto t0 = std::chrono::steady_clock::now();
  // Five deadlines in a row, each armed from the previous call for a time already past (what a
  // paced bus does when its thread woke up late): one timer wait serves them all.
  int left = 4;
  x.then = [&] {
    if (left-- > 0) q.arm(x, t0);
  };
  q.arm(x, t0 + std::chrono::milliseconds(1));
  const auto waits = q.timer_waits();
  io.run();
  EXPECT_EQ(log.size(), 5u);
  EXPECT_EQ(q.timer_waits(), waits);
}

TEST(DeadlineQueue, AClientDestroyedWhileArmedIsNeverCalled) {
  asio::io_context io;
  auto& q = core::DeadlineQueue::of(io.get_executor());
  std::vector<std::string> log;
  auto x = std::make_unique<Recorder>();
  Recorder y;
  x->name = "x", y.name = "y";
  x->log = y.log = &log;
  const auto t0 = std::chrono::steady_clock::now();
  q.arm(*x, t0 + std::chrono::milliseconds(1));
  q.arm(y, t0 + std::chrono::milliseconds(2));
  x.reset();
  EXPECT_EQ(q.size(), 1u);
  io.run();
  EXPECT_EQ(log, (std::vector<std::string>{"y"}));
}

TEST(DeadlineQueue, AClientMayDestroyAnotherFromItsCall) {
  asio::io_context io;
  auto& q = core::DeadlineQueue::of(io.get_executor());
  std::vector<std::string> log;
  auto victim = std::make_unique<Recorder>();
  Recorder killer;
  killer.name = "killer", victim->name = "victim";
  killer.log = victim->log = &log;
  killer.then = [&] { victim.reset(); };
  const auto t0 = std::chrono::steady_clock::now();
  q.arm(killer, t0);
  q.arm(*victim, t0);  // due in the same wake-up, after the killer
  io.run();
  EXPECT_EQ(log, (std::vector<std::string>{"killer"}));
}

TEST(DeadlineQueue, SlackLetsOneWakeUpServeCloseDeadlinesButNeverCallsEarly) {
  asio::io_context io;
  auto& q = core::DeadlineQueue::of(io.get_executor());
  q.set_slack(std::chrono::milliseconds(50));
  std::vector<std::string> log;
  Recorder x, y;
  x.name = "x", y.name = "y";
  x.log = y.log = &log;
  const auto t0 = std::chrono::steady_clock::now();
  q.arm(x, t0 + std::chrono::milliseconds(3));
  const auto waits = q.timer_waits();
  q.arm(y, t0 + std::chrono::milliseconds(4));  // x's wait ends within y's slack: no new wait
  EXPECT_EQ(q.timer_waits(), waits);
  io.run();
  EXPECT_EQ(log, (std::vector<std::string>{"x", "y"}));
  EXPECT_EQ(q.timer_waits(), waits);
  // Both in the one wake-up, which came no earlier than the first deadline plus the slack.
  EXPECT_GE(x.called_at.at(0), t0 + std::chrono::milliseconds(3) + std::chrono::milliseconds(50));
  EXPECT_GE(y.called_at.at(0), t0 + std::chrono::milliseconds(4));
}
