#include "axon/actor/actor_core.hpp"
#include "replies.hpp"

#include <gtest/gtest.h>

#include <future>
#include <stdexcept>

namespace axon::actor {
namespace {

using test::body_of;
using test::code_of;
using test::command;

TEST(ActorCore, RepliesCarryTheConventionsHeadersAndCorrelationId) {
  test::Replies out;
  ActorCore core("test", out.sink());
  core.handle(command("ping", "42", "tron.test"));
  const auto m = out.final_of("42");
  ASSERT_TRUE(m);
  EXPECT_EQ(m->routing_key, "reply.tron.test");
  EXPECT_EQ(code_of(*m), ':');
  EXPECT_EQ(header_text(m->headers, "commander_id"), "tron.test");
  EXPECT_EQ(header_text(m->headers, "sender"), "test");
  EXPECT_EQ(m->correlation_id, "42");
  EXPECT_EQ(body_of(*m)["text"], "Pong.");
}

TEST(ActorCore, ABodyThatIsNotJsonFailsWithAReasonAndIsCounted) {
  test::Replies out;
  ActorCore core("test", out.sink());
  auto m = command("ping", "7");
  m.body = "ping";
  core.handle(m);
  const auto r = out.final_of("7");
  ASSERT_TRUE(r);
  EXPECT_EQ(code_of(*r), 'f');
  EXPECT_NE(body_of(*r)["error"].get<std::string>().find("not JSON"), std::string::npos);
  EXPECT_EQ(core.counters().not_json, 1u);
  EXPECT_EQ(core.counters().failed, 1u);
}

TEST(ActorCore, UnknownAndMalformedCommandsFailWithAReasonAndAreCounted) {
  test::Replies out;
  ActorCore core("test", out.sink());
  core.handle(command("fly 3", "1"));
  core.handle(command("goto \"open", "2"));
  const auto unknown = out.final_of("1"), malformed = out.final_of("2");
  ASSERT_TRUE(unknown && malformed);
  EXPECT_EQ(code_of(*unknown), 'f');
  EXPECT_NE(body_of(*unknown)["error"].get<std::string>().find("unknown command \"fly\""), std::string::npos);
  EXPECT_EQ(code_of(*malformed), 'f');
  EXPECT_NE(body_of(*malformed)["error"].get<std::string>().find("quote"), std::string::npos);
  EXPECT_EQ(core.counters().unknown, 1u);
  EXPECT_EQ(core.counters().malformed, 1u);
}

// As clu's actors: an accepted command answers '>' (no keywords) first, then its keywords, then one
// final reply; get_schema gives the schema the actor was given, as a string, and fails without one.
TEST(ActorCore, ACommandAnswersRunningFirstAndGetSchemaGivesTheSchemaText) {
  test::Replies out;
  ActorCore core("test", out.sink());
  core.add({"work", "work", false, [](Command& c) {
              c.write(MessageCode::info, {{"text", "half way"}});
              c.finish({{"text", "done"}});
            }});
  core.handle(command("work", "w"));
  ASSERT_TRUE(out.final_of("w"));
  core.wait_idle();
  const auto replies = out.of("w");
  ASSERT_EQ(replies.size(), 3u);
  EXPECT_EQ(code_of(replies[0]), '>');
  EXPECT_EQ(replies[0].body, "{}");
  EXPECT_EQ(code_of(replies[1]), 'i');
  EXPECT_EQ(code_of(replies[2]), ':');
  core.handle(command("get_schema", "none"));
  const auto none = out.final_of("none");
  ASSERT_TRUE(none);
  EXPECT_EQ(code_of(*none), 'f');
  core.set_schema(R"({"type": "object"})");
  core.handle(command("get_schema", "s"));
  const auto schema = out.final_of("s");
  ASSERT_TRUE(schema);
  EXPECT_EQ(code_of(*schema), ':');
  EXPECT_EQ(body_of(*schema)["schema"], R"({"type": "object"})");
}

TEST(ActorCore, ASecondExclusiveCommandIsRefusedWhileTheFirstRunsNotQueued) {
  test::Replies out;
  ActorCore core("test", out.sink());
  std::promise<void> release;
  auto released = release.get_future().share();
  core.add({"move", "move", true, [released](Command& c) {
              c.write(MessageCode::running, {{"text", "moving"}});
              released.wait();
            }});
  core.handle(command("move", "first"));
  ASSERT_TRUE(out.wait_for([](const Message& m) { return header_text(m.headers, "command_id") == "first"; }));
  core.handle(command("move", "second"));
  const auto refused = out.final_of("second");
  ASSERT_TRUE(refused);
  EXPECT_EQ(code_of(*refused), 'f');
  EXPECT_NE(body_of(*refused)["error"].get<std::string>().find("\"move\" is running"), std::string::npos);
  EXPECT_EQ(core.busy_with(), "move");
  release.set_value();
  const auto first = out.final_of("first");
  ASSERT_TRUE(first);
  EXPECT_EQ(code_of(*first), ':');
  EXPECT_EQ(core.counters().refused, 1u);
}

TEST(ActorCore, TheExclusiveSlotIsFreeWhenTheFinalReplyLeaves) {
  test::Replies out;
  ActorCore* self = nullptr;
  bool sent_next = false;
  auto sink = out.sink();
  ActorCore core("test", [&](Message m) {
    const bool first_done = header_text(m.headers, "command_id") == "a" && code_of(m) == ':';
    sink(std::move(m));
    if (first_done && !sent_next) {  // the commander sends the next move on reading ':'
      sent_next = true;
      self->handle(command("move", "b"));
    }
  });
  self = &core;
  core.add({"move", "move", true, [](Command& c) { c.finish(); }});
  core.handle(command("move", "a"));
  const auto b = out.final_of("b");
  ASSERT_TRUE(b);
  EXPECT_EQ(code_of(*b), ':');
  core.wait_idle();
}

TEST(ActorCore, AHandlerThatThrowsEndsItsCommandWithTheReason) {
  test::Replies out;
  ActorCore core("test", out.sink());
  core.add({"boom", "boom", false, [](Command&) { throw std::runtime_error("device on fire"); }});
  core.handle(command("boom", "9"));
  const auto r = out.final_of("9");
  ASSERT_TRUE(r);
  EXPECT_EQ(code_of(*r), 'f');
  EXPECT_EQ(body_of(*r)["error"], "device on fire");
  core.handle(command("ping", "10"));  // and the actor goes on
  ASSERT_TRUE(out.final_of("10"));
}

TEST(ActorCore, NothingFollowsAFinalReply) {
  test::Replies out;
  ActorCore core("test", out.sink());
  core.add({"twice", "twice", false, [](Command& c) {
              c.finish();
              c.fail("too late");
              c.write(MessageCode::info, {{"text", "late"}});
            }});
  core.handle(command("twice", "3"));
  ASSERT_TRUE(out.final_of("3"));
  core.wait_idle();
  const auto replies = out.of("3");
  ASSERT_EQ(replies.size(), 2u);  // '>' as it starts, then the one final reply
  EXPECT_EQ(code_of(replies.back()), ':');
}

TEST(ActorCore, ACommandWithoutIdsGetsOneAndItsRepliesAreBroadcast) {
  test::Replies out;
  ActorCore core("test", out.sink());
  Message m;
  m.body = command_body("ping");
  core.handle(m);
  const auto r = out.wait_for([](const Message&) { return true; });
  ASSERT_TRUE(r);
  EXPECT_EQ(r->routing_key, kBroadcastKey);
  EXPECT_FALSE(header_text(r->headers, "command_id").empty());
  EXPECT_TRUE(std::holds_alternative<std::monostate>(r->headers.at("commander_id")));
}

TEST(ActorCore, AClosedCoreRefusesEveryCommand) {
  test::Replies out;
  ActorCore core("test", out.sink());
  core.close();
  core.handle(command("ping", "5"));
  const auto r = out.final_of("5");
  ASSERT_TRUE(r);
  EXPECT_EQ(code_of(*r), 'f');
  EXPECT_NE(body_of(*r)["error"].get<std::string>().find("shutting down"), std::string::npos);
}

TEST(ActorCore, HelpListsEveryVerb) {
  test::Replies out;
  ActorCore core("test", out.sink());
  core.add({"move", "move ID", true, [](Command& c) { c.finish(); }});
  core.handle(command("help", "h"));
  const auto r = out.final_of("h");
  ASSERT_TRUE(r);
  const auto help = body_of(*r)["help"];
  EXPECT_NE(std::find(help.begin(), help.end(), "move ID"), help.end());
  EXPECT_NE(std::find(help.begin(), help.end(), "ping"), help.end());
}

}  // namespace
}  // namespace axon::actor
