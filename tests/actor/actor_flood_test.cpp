// A commander that floods an actor: slow commands beyond the limit, bodies too large to be a
// command, garbage by the thousand. The actor stays bounded (threads, memory, log lines), answers
// every message with one final reply and counts each kind.
#include "axon/actor/actor_core.hpp"
#include "replies.hpp"
#include "support/hostile_peer.hpp"

#include <gtest/gtest.h>

#include <future>
#include <string>

namespace axon::actor::flood_test {
namespace {

using test::body_of;
using test::code_of;
using test::command;

std::string error_of(const Message& m) { return body_of(m).value("error", std::string()); }

TEST(ActorFlood, AFloodOfASlowVerbRunsAtMostTheLimitAndAnswersTheRestBusyAtOnce) {
  test::Replies out;
  ActorCore core("test", out.sink());  // the default limits
  std::promise<void> release;
  auto released = release.get_future().share();
  core.add({"wait", "wait", false, [released](Command&) { released.wait(); }});
  const int sent = 200;
  for (int i = 0; i < sent; ++i) core.handle(command("wait", std::to_string(i)));
  const auto max_running = static_cast<int>(ActorLimits{}.max_running);
  for (int i = max_running; i < sent; ++i) {
    const auto r = out.final_of(std::to_string(i));
    ASSERT_TRUE(r) << i;
    EXPECT_EQ(code_of(*r), 'f');
    EXPECT_NE(error_of(*r).find("busy: 32 commands are running"), std::string::npos) << error_of(*r);
  }
  EXPECT_EQ(core.counters().accepted, static_cast<std::uint64_t>(max_running));
  EXPECT_EQ(core.counters().busy, static_cast<std::uint64_t>(sent - max_running));
  release.set_value();
  for (int i = 0; i < max_running; ++i) {
    const auto r = out.final_of(std::to_string(i));
    ASSERT_TRUE(r) << i;
    EXPECT_EQ(code_of(*r), ':');
  }
  core.wait_idle();
  core.handle(command("ping", "after"));  // the slots are free again
  const auto after = out.final_of("after");
  ASSERT_TRUE(after);
  EXPECT_EQ(code_of(*after), ':');
}

TEST(ActorFlood, TheLimitIsTheCallersToChoose) {
  test::Replies out;
  ActorCore core("test", out.sink(), ActorLimits{.max_running = 2});
  std::promise<void> release;
  auto released = release.get_future().share();
  core.add({"wait", "wait", false, [released](Command&) { released.wait(); }});
  for (const char* id : {"a", "b", "c"}) core.handle(command("wait", id));
  const auto c = out.final_of("c");
  ASSERT_TRUE(c);
  EXPECT_NE(error_of(*c).find("busy: 2 commands"), std::string::npos) << error_of(*c);
  release.set_value();
  core.wait_idle();
  EXPECT_EQ(core.counters().busy, 1u);
}

TEST(ActorFlood, ABodyLargerThanACommandIsRefusedUnparsedAndCounted) {
  test::Replies out;
  ActorCore core("test", out.sink());
  auto big = command("ping", "big");
  big.body = "{" + std::string(1 << 20, ' ') + "\"command_string\": \"ping\"}";
  core.handle(big);
  const auto r = out.final_of("big");
  ASSERT_TRUE(r);
  EXPECT_EQ(code_of(*r), 'f');
  EXPECT_NE(error_of(*r).find("more than the 65536 a command may have"), std::string::npos) << error_of(*r);
  EXPECT_EQ(core.counters().oversized, 1u);
  EXPECT_EQ(core.counters().not_json, 0u);

  auto padded = command("ping", "padded");  // just under the limit: an ordinary command
  padded.body = "{" + std::string(60000, ' ') + "\"command_string\": \"ping\"}";
  core.handle(padded);
  const auto p = out.final_of("padded");
  ASSERT_TRUE(p);
  EXPECT_EQ(code_of(*p), ':');
}

TEST(ActorFlood, EveryRefusalIsCountedButOnlyTheFirstAndEveryHundredthIsAWarning) {
  hostile::WarningLog log;
  test::Replies out;
  ActorCore core("test", out.sink());
  const int sent = 1000;
  for (int i = 0; i < sent; ++i) {
    auto m = command("ping", std::to_string(i));
    m.body = i % 2 ? "garbage" : "{\"command_string\": \"fly\"}";
    core.handle(m);
  }
  ASSERT_TRUE(out.final_of(std::to_string(sent - 1)));
  EXPECT_EQ(out.messages.size(), static_cast<std::size_t>(sent));  // one 'f' each
  EXPECT_EQ(core.counters().not_json + core.counters().unknown, static_cast<std::uint64_t>(sent));
  EXPECT_EQ(core.counters().failed, static_cast<std::uint64_t>(sent));
  EXPECT_EQ(log.count("command refused"), 10u);
  EXPECT_EQ(log.count("(1000 refused so far"), 0u);
  EXPECT_EQ(log.count("(901 refused so far"), 1u);
}

}  // namespace
}  // namespace axon::actor::flood_test
