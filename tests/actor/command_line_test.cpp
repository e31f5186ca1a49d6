#include "axon/actor/command_line.hpp"
#include "axon/actor/message.hpp"

#include <gtest/gtest.h>

namespace axon::actor {
namespace {

TEST(ActorCommandLine, SplitsTheVerbFromItsArguments) {
  const auto line = split_command("  goto 12 90.5\t180 ").value();
  EXPECT_EQ(line.verb, "goto");
  EXPECT_EQ(line.args, (std::vector<std::string>{"12", "90.5", "180"}));
}

TEST(ActorCommandLine, QuotesKeepBlanksAndEscapes) {
  const auto line = split_command(R"(say "two words" "a \"q\"" "")").value();
  EXPECT_EQ(line.args, (std::vector<std::string>{"two words", "a \"q\"", ""}));
}

TEST(ActorCommandLine, RejectsAnEmptyCommandAndAnOpenQuote) {
  EXPECT_FALSE(split_command("   "));
  const auto open = split_command("say \"unterminated");
  ASSERT_FALSE(open);
  EXPECT_NE(open.error().message().find("quote"), std::string::npos);
}

TEST(ActorCommandLine, ReadsTheCommandStringOfABody) {
  EXPECT_EQ(command_string_of(command_body("status --full")).value(), "status --full");
  EXPECT_EQ(command_string_of(R"({"command_string": "ping", "other": 1})").value(), "ping");
}

TEST(ActorCommandLine, RejectsBodiesWithAReason) {
  EXPECT_NE(command_string_of("status").error().message().find("not JSON"), std::string::npos);
  EXPECT_NE(command_string_of("[1, 2]").error().message().find("not a JSON object"), std::string::npos);
  EXPECT_NE(command_string_of("{}").error().message().find("no command_string"), std::string::npos);
  EXPECT_NE(command_string_of(R"({"command_string": 3})").error().message().find("not a string"), std::string::npos);
}

TEST(ActorMessage, CodesRoundTripAndThreeAreFinal) {
  for (char c : std::string("> : f e ! i w d")) {
    if (c == ' ') continue;
    const auto code = parse_message_code(std::string(1, c));
    ASSERT_TRUE(code) << c;
    EXPECT_EQ(to_char(*code), c);
    EXPECT_EQ(is_final(*code), c == ':' || c == 'f' || c == '!') << c;
  }
  EXPECT_FALSE(parse_message_code("x"));
  EXPECT_FALSE(parse_message_code("::"));
}

TEST(ActorMessage, RoutingKeysFollowTheConvention) {
  EXPECT_EQ(command_binding("fps"), "command.fps.#");
  EXPECT_EQ(command_key("fps"), "command.fps");
  EXPECT_EQ(reply_key("tron.fps"), "reply.tron.fps");
}

TEST(ActorMessage, HeaderTextReadsStringsNumbersFlagsAndNull) {
  const Headers h{{"s", std::string("abc")}, {"n", std::int64_t{42}}, {"b", true}, {"v", std::monostate{}}};
  EXPECT_EQ(header_text(h, "s"), "abc");
  EXPECT_EQ(header_text(h, "n"), "42");
  EXPECT_EQ(header_text(h, "b"), "true");
  EXPECT_EQ(header_text(h, "v"), "");
  EXPECT_EQ(header_text(h, "absent"), "");
}

}  // namespace
}  // namespace axon::actor
