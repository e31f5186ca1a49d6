#include "axon/can/socketcand_codec.hpp"

#include <gtest/gtest.h>

#include <array>
#include <string>
#include <vector>

namespace axon::can::socketcand {
namespace {

using namespace std::chrono_literals;

Frame data_frame(std::uint32_t id, IdFormat fmt, std::vector<std::uint8_t> bytes, core::WallTime ts = core::WallTime{0}) {
  Frame f = Frame::data(id, fmt, bytes).value();
  f.set_timestamp(ts);
  return f;
}

Message parsed(std::string_view text) {
  auto r = parse(text);
  EXPECT_TRUE(r) << text << ": " << (r ? "" : r.error().message());
  return r ? r.value() : Message{};
}

void expect_parse_error(std::string_view text, std::string_view mentions = {}) {
  auto r = parse(text);
  ASSERT_FALSE(r) << "accepted: " << text;
  EXPECT_EQ(r.error(), CanErrc::parse_error);
  if (!mentions.empty()) {
    EXPECT_NE(r.error().detail.find(mentions), std::string::npos) << r.error().detail;
  }
}

// ---------------------------------------------------------------------------------------- ids

TEST(SocketcandId, DigitCountAndValueDecideTheFormat) {
  EXPECT_EQ(parse_id("123").value(), (Id{0x123, IdFormat::standard}));
  EXPECT_EQ(parse_id("7FF").value(), (Id{0x7FF, IdFormat::standard}));
  EXPECT_EQ(parse_id("0").value(), (Id{0, IdFormat::standard}));
  EXPECT_EQ(parse_id("7f").value(), (Id{0x7F, IdFormat::standard}));
  // Unpadded ids above the 11-bit range can only be extended (python-can writes them like this).
  EXPECT_EQ(parse_id("800").value(), (Id{0x800, IdFormat::extended}));
  EXPECT_EQ(parse_id("12345").value(), (Id{0x12345, IdFormat::extended}));
  EXPECT_EQ(parse_id("0800").value(), (Id{0x800, IdFormat::extended}));
  // Eight digits are extended whatever the value: the way to write an extended id <= 0x7FF.
  EXPECT_EQ(parse_id("00000123").value(), (Id{0x123, IdFormat::extended}));
  EXPECT_EQ(parse_id("1FFFFFFF").value(), (Id{0x1FFFFFFF, IdFormat::extended}));
}

TEST(SocketcandId, RejectsWhatIsNotAnId) {
  for (const char* bad : {"", "20000000", "FFFFFFFF", "123456789", "12G", "-1", "0x12", " 12"}) {
    auto r = parse_id(bad);
    EXPECT_FALSE(r) << bad;
    if (!r) {
      EXPECT_EQ(r.error(), CanErrc::parse_error);
    }
  }
}

TEST(SocketcandId, FormatsThreeOrEightDigits) {
  std::string s;
  append_id(s, 0x12, IdFormat::standard);
  s += ' ';
  append_id(s, 0x12, IdFormat::extended);
  s += ' ';
  append_id(s, 0x1ABCDEF0, IdFormat::extended);
  EXPECT_EQ(s, "012 00000012 1ABCDEF0");
}

// ----------------------------------------------------------------------------------- timestamps

TEST(SocketcandTimestamp, ParsesSecondsAndFraction) {
  EXPECT_EQ(parse_timestamp("23.424242").value(), core::WallTime(23'424'242'000));
  EXPECT_EQ(parse_timestamp("1700000000.000001").value(), core::WallTime(1'700'000'000'000'001'000));
  EXPECT_EQ(parse_timestamp("5").value(), core::WallTime(5'000'000'000));
  EXPECT_EQ(parse_timestamp("5.5").value(), core::WallTime(5'500'000'000));
  EXPECT_EQ(parse_timestamp("9000000000.999999").value(), core::WallTime(9'000'000'000'999'999'000));
  // Beyond microseconds the digits are dropped, so formatting and parsing again is stable.
  EXPECT_EQ(parse_timestamp("1.123456789").value(), core::WallTime(1'123'456'000));
  for (const char* bad : {"", ".5", "1.", "1.2.3", "a.000001", "1.00000x", "-1.000000", "1.1234567890", "1234567890123.0", "9000000001.0", "99999999999"})
    EXPECT_FALSE(parse_timestamp(bad)) << bad;
}

TEST(SocketcandTimestamp, FormatsSixFractionalDigits) {
  std::string s;
  append_timestamp(s, core::WallTime(1'700'000'000'000'001'999));
  EXPECT_EQ(s, "1700000000.000001");
  s.clear();
  append_timestamp(s, core::WallTime(0));
  EXPECT_EQ(s, "0.000000");
  s.clear();
  append_timestamp(s, core::WallTime(-5));
  EXPECT_EQ(s, "0.000000");
}

// ------------------------------------------------------------------------------ simple messages

TEST(SocketcandParse, KeywordOnlyMessages) {
  EXPECT_EQ(parsed("< hi >"), Message(Hi{}));
  EXPECT_EQ(parsed("< ok >"), Message(Ok{}));
  EXPECT_EQ(parsed("< echo >"), Message(Echo{}));
  EXPECT_EQ(parsed("< rawmode >"), Message(Mode{Mode::Kind::raw}));
  EXPECT_EQ(parsed("< bcmmode >"), Message(Mode{Mode::Kind::bcm}));
  EXPECT_EQ(parsed("< controlmode >"), Message(Mode{Mode::Kind::control}));
  EXPECT_EQ(parsed("< isotpmode >"), Message(Mode{Mode::Kind::isotp}));
  // Spacing is free: no space, several spaces, tabs.
  EXPECT_EQ(parsed("<hi>"), Message(Hi{}));
  EXPECT_EQ(parsed("<   rawmode\t>"), Message(Mode{Mode::Kind::raw}));
  expect_parse_error("< ok now >", "takes no arguments");
  expect_parse_error("< rawmode 1 >", "takes no arguments");
}

TEST(SocketcandParse, OpenNeedsOneChannelName) {
  EXPECT_EQ(parsed("< open can0 >"), Message(Open{"can0"}));
  EXPECT_EQ(parsed("< open vcan-fps.1 >"), Message(Open{"vcan-fps.1"}));
  expect_parse_error("< open >", "open CHANNEL");
  expect_parse_error("< open can0 can1 >", "open CHANNEL");
  expect_parse_error("< open " + std::string(kMaxChannelName + 1, 'c') + " >", "longer than");
}

TEST(SocketcandParse, ErrorTextOrErrorFrame) {
  EXPECT_EQ(parsed("< error could not open bus >"), Message(ErrorText{"could not open bus"}));
  EXPECT_EQ(parsed("< error   unknown    command >"), Message(ErrorText{"unknown command"}));
  EXPECT_EQ(parsed("< error >"), Message(ErrorText{""}));
  // What the daemon sends in raw mode for a bus error frame: class bits and a timestamp.
  EXPECT_EQ(parsed("< error 004 1700000000.250000 >"), Message(ErrorFrame{0x004, core::WallTime(1'700'000'000'250'000'000)}));
  EXPECT_EQ(parsed("< error 20000004 1.000000 >"), Message(ErrorFrame{0x20000004, core::WallTime(1'000'000'000)}));
  // Two words that are not class + time stay text.
  EXPECT_EQ(parsed("< error 004 later >"), Message(ErrorText{"004 later"}));
}

TEST(SocketcandParse, StatisticsAndStat) {
  EXPECT_EQ(parsed("< statistics 1000 >"), Message(Statistics{1000}));
  EXPECT_EQ(parsed("< statistics 0 >"), Message(Statistics{0}));
  EXPECT_EQ(parsed("< stat 10 2 24 3 >"), Message(Stat{10, 2, 24, 3}));
  expect_parse_error("< statistics >", "statistics MILLISECONDS");
  expect_parse_error("< statistics -1 >", "statistics MILLISECONDS");
  expect_parse_error("< statistics 99999999999 >", "statistics MILLISECONDS");
  expect_parse_error("< stat 1 2 3 >", "stat RBYTES");
  expect_parse_error("< stat 1 2 3 x >", "not a decimal count");
}

// ------------------------------------------------------------------------------------------ send

TEST(SocketcandParse, SendAsTheDaemonDocumentsIt) {
  EXPECT_EQ(parsed("< send 123 0 >"), Message(Send{data_frame(0x123, IdFormat::standard, {})}));
  EXPECT_EQ(parsed("< send 1AAAAAAA 2 1 F1 >"), Message(Send{data_frame(0x1AAAAAAA, IdFormat::extended, {0x01, 0xF1})}));
  EXPECT_EQ(parsed("< send 7FF 8 11 22 33 44 55 66 77 88 >"),
            Message(Send{data_frame(0x7FF, IdFormat::standard, {0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88})}));
}

TEST(SocketcandParse, SendAsPythonCan41WritesIt) {
  // python-can 4.1: "< send {id:X} {len:X} {bytes as {:x} joined by ' '} >": no padding anywhere,
  // lower-case data, and two spaces before '>' when there is no data.
  EXPECT_EQ(parsed("< send 123 0  >"), Message(Send{data_frame(0x123, IdFormat::standard, {})}));
  EXPECT_EQ(parsed("< send 5 3 1 f1 0 >"), Message(Send{data_frame(0x5, IdFormat::standard, {0x01, 0xF1, 0x00})}));
  EXPECT_EQ(parsed("< send 12345678 1 ab >"), Message(Send{data_frame(0x12345678, IdFormat::extended, {0xAB})}));
  EXPECT_EQ(parsed("< send 800 1 ab >"), Message(Send{data_frame(0x800, IdFormat::extended, {0xAB})}));
  // An extended id <= 0x7FF loses its format in python-can 4.1's text: it arrives as standard.
  EXPECT_EQ(parsed("< send 100 1 ab >"), Message(Send{data_frame(0x100, IdFormat::standard, {0xAB})}));
}

TEST(SocketcandParse, SendRejectsInconsistentFrames) {
  expect_parse_error("< send >", "send ID LEN");
  expect_parse_error("< send 123 >", "send ID LEN");
  expect_parse_error("< send 123 2 11 >", "length 2 but 1 data bytes");
  expect_parse_error("< send 123 1 11 22 >", "length 1 but 2 data bytes");
  expect_parse_error("< send 123 9 1 2 3 4 5 6 7 8 9 >", "must be 0..8");
  expect_parse_error("< send 123 x >", "must be 0..8");
  expect_parse_error("< send 123 1 100 >", "not one or two hex digits");
  expect_parse_error("< send 123 1 zz >", "not one or two hex digits");
  expect_parse_error("< send 123G 0 >", "hex digits");
  expect_parse_error("< send 3FFFFFFF 0 >", "wider than 29 bits");
}

TEST(SocketcandParse, SendRtr) {
  EXPECT_EQ(parsed("< sendrtr 123 0 >"), Message(Send{Frame::remote(0x123, IdFormat::standard, 0).value()}));
  EXPECT_EQ(parsed("< sendrtr 1AAAAAAA 2 >"), Message(Send{Frame::remote(0x1AAAAAAA, IdFormat::extended, 2).value()}));
  expect_parse_error("< sendrtr 123 >", "sendrtr ID DLC");
  expect_parse_error("< sendrtr 123 9 >", "must be 0..8");
}

// ----------------------------------------------------------------------------------------- frame

TEST(SocketcandParse, FrameAsTheDaemonWritesIt) {
  const auto ts = core::WallTime(1'700'000'123'000'042'000);
  EXPECT_EQ(parsed("< frame 123 1700000123.000042 11223344 >"),
            Message(FrameMessage{data_frame(0x123, IdFormat::standard, {0x11, 0x22, 0x33, 0x44}, ts)}));
  EXPECT_EQ(parsed("< frame 00000123 1700000123.000042 AABBCCDDEEFF0011 >"),
            Message(FrameMessage{data_frame(0x123, IdFormat::extended, {0xAA, 0xBB, 0xCC, 0xDD, 0xEE, 0xFF, 0x00, 0x11}, ts)}));
  // No data: the daemon writes two spaces.
  EXPECT_EQ(parsed("< frame 7FF 1700000123.000042  >"), Message(FrameMessage{data_frame(0x7FF, IdFormat::standard, {}, ts)}));
  EXPECT_EQ(parsed("< frame 7FF 1700000123.000042 >"), Message(FrameMessage{data_frame(0x7FF, IdFormat::standard, {}, ts)}));
}

TEST(SocketcandParse, FrameWithOneFieldPerByteAsTheDocumentationShowsIt) {
  EXPECT_EQ(parsed("< frame 123 23.424242 11 22 33 44 >"),
            Message(FrameMessage{data_frame(0x123, IdFormat::standard, {0x11, 0x22, 0x33, 0x44}, core::WallTime(23'424'242'000))}));
}

TEST(SocketcandParse, FrameTimestampIsKept) {
  auto m = parsed("< frame 123 12.000007 00 >");
  ASSERT_TRUE(std::holds_alternative<FrameMessage>(m));
  EXPECT_EQ(std::get<FrameMessage>(m).frame.timestamp(), core::WallTime(12'000'007'000));
}

TEST(SocketcandParse, FrameRejectsBadData) {
  expect_parse_error("< frame 123 >", "frame ID SECONDS");
  expect_parse_error("< frame 123 1.0 112 >", "whole hex bytes");
  expect_parse_error("< frame 123 1.0 1 2 >", "whole hex bytes");
  expect_parse_error("< frame 123 1.0 11zz >", "whole hex bytes");
  expect_parse_error("< frame 123 1.0 112233445566778899 >", "more than 8 data bytes");
  expect_parse_error("< frame 123 soon 11 >", "timestamp");
  expect_parse_error("< frame 1234567890 1.0 11 >", "hex digits");
}

TEST(SocketcandParse, RtrFrame) {
  auto expected = Frame::remote(0x123, IdFormat::standard, 4).value();
  expected.set_timestamp(core::WallTime(23'424'242'000));
  EXPECT_EQ(parsed("< rtr 123 23.424242 4 >"), Message(FrameMessage{expected}));
  expect_parse_error("< rtr 123 23.424242 >", "rtr ID");
  expect_parse_error("< rtr 123 23.424242 9 >", "must be 0..8");
}

// ----------------------------------------------------------------------------------- malformed

TEST(SocketcandParse, RejectsMalformedMessages) {
  expect_parse_error("", "not enclosed");
  expect_parse_error("hi", "not enclosed");
  expect_parse_error("< hi", "not enclosed");
  expect_parse_error("hi >", "not enclosed");
  expect_parse_error("<>", "empty message");
  expect_parse_error("<   >", "empty message");
  expect_parse_error("< hello >", "unknown command 'hello'");
  expect_parse_error("< HI >", "unknown command");
  expect_parse_error("< fdframe 123 00 1.0 11 >", "CAN FD");
  expect_parse_error("< fdsend 123 00 1 11 >", "CAN FD");
  expect_parse_error(std::string("< h\x01i >"), "0x01");
  expect_parse_error(std::string("< hi \xff>"), "0xFF");
  expect_parse_error("< hi < ok >", "not allowed");
  expect_parse_error("< error a b c d e f g h i j k l m n o p q >", "more than 16 fields");
  expect_parse_error("< error " + std::string(kMaxMessageLength, 'x') + " >", "longer than");
}

TEST(SocketcandParse, TerseErrorsGiveOnlyTheReason) {
  auto r = parse_terse("< send 123 2 11 >");
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error(), CanErrc::parse_error);
  EXPECT_EQ(r.error().detail, "length 2 but 1 data bytes");
  auto full = parse("< send 123 2 11 >");
  ASSERT_FALSE(full);
  EXPECT_NE(full.error().detail.find("< send 123 2 11 >"), std::string::npos) << full.error().detail;
  EXPECT_EQ(parse_terse("< subscribe 0 0 123 >").error().detail, "'subscribe' (broadcast manager / ISO-TP) is not supported");
}

TEST(SocketcandParse, ErrorMessagesQuoteTheInputReadably) {
  auto r = parse(std::string("< send \x02 >"));
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().detail.find("\\x02"), std::string::npos) << r.error().detail;
}

// ---------------------------------------------------------------------------------------- format

TEST(SocketcandFormat, ExactText) {
  const auto ts = core::WallTime(1'700'000'000'123'456'789);
  EXPECT_EQ(format(Hi{}), "< hi >");
  EXPECT_EQ(format(Ok{}), "< ok >");
  EXPECT_EQ(format(Echo{}), "< echo >");
  EXPECT_EQ(format(Open{"vcan0"}), "< open vcan0 >");
  EXPECT_EQ(format(Mode{Mode::Kind::raw}), "< rawmode >");
  EXPECT_EQ(format(Mode{Mode::Kind::bcm}), "< bcmmode >");
  EXPECT_EQ(format(Mode{Mode::Kind::control}), "< controlmode >");
  EXPECT_EQ(format(Mode{Mode::Kind::isotp}), "< isotpmode >");
  EXPECT_EQ(format(ErrorText{"could not open bus"}), "< error could not open bus >");
  EXPECT_EQ(format(ErrorText{""}), "< error >");
  EXPECT_EQ(format(ErrorFrame{0x4, core::WallTime(2'000'001'000)}), "< error 004 2.000001 >");
  EXPECT_EQ(format(Statistics{250}), "< statistics 250 >");
  EXPECT_EQ(format(Stat{1, 2, 3, 4}), "< stat 1 2 3 4 >");
  EXPECT_EQ(format(Send{data_frame(0x12, IdFormat::standard, {0x01, 0xAB})}), "< send 012 2 01 AB >");
  EXPECT_EQ(format(Send{data_frame(0x12, IdFormat::extended, {})}), "< send 00000012 0 >");
  EXPECT_EQ(format(Send{Frame::remote(0x1ABCDEF, IdFormat::extended, 3).value()}), "< sendrtr 01ABCDEF 3 >");
  EXPECT_EQ(format(FrameMessage{data_frame(0x123, IdFormat::standard, {0xDE, 0xAD, 0xBE, 0xEF}, ts)}),
            "< frame 123 1700000000.123456 DEADBEEF >");
  EXPECT_EQ(format(FrameMessage{data_frame(0x1FFFFFFF, IdFormat::extended, {0x00}, ts)}),
            "< frame 1FFFFFFF 1700000000.123456 00 >");
  // No data: two spaces, as the daemon writes it (python-can 4.1 needs the empty third field).
  EXPECT_EQ(format(FrameMessage{data_frame(0x7, IdFormat::standard, {}, ts)}), "< frame 007 1700000000.123456  >");
  auto rtr = Frame::remote(0x123, IdFormat::standard, 8).value();
  rtr.set_timestamp(ts);
  EXPECT_EQ(format(FrameMessage{rtr}), "< rtr 123 1700000000.123456 8 >");
}

TEST(SocketcandFormat, ErrorTextCannotBreakTheStream) {
  EXPECT_EQ(format(ErrorText{"a<b>c\nd"}), "< error a?b?c?d >");
}

TEST(SocketcandFormat, AppendAddsToTheBuffer) {
  std::string out = "x";
  append(out, Hi{});
  append(out, Ok{});
  EXPECT_EQ(out, "x< hi >< ok >");
}

TEST(SocketcandFormat, Keywords) {
  EXPECT_STREQ(keyword(Hi{}), "hi");
  EXPECT_STREQ(keyword(Send{Frame::remote(1, IdFormat::standard, 0).value()}), "sendrtr");
  EXPECT_STREQ(keyword(FrameMessage{Frame{}}), "frame");
  EXPECT_STREQ(keyword(Mode{Mode::Kind::control}), "controlmode");
}

TEST(SocketcandFormat, EveryMessageTypeRoundTrips) {
  const auto ts = core::WallTime(1'234'567'000);
  auto rtr = Frame::remote(0x1ABCDEF, IdFormat::extended, 5).value();
  rtr.set_timestamp(ts);
  const std::vector<Message> all = {
      Hi{}, Ok{}, Echo{}, ErrorText{"no such channel"}, ErrorText{""}, ErrorFrame{0x20, ts}, Open{"can1"},
      Mode{Mode::Kind::raw}, Mode{Mode::Kind::bcm}, Mode{Mode::Kind::control}, Mode{Mode::Kind::isotp},
      Send{data_frame(0x7FF, IdFormat::standard, {1, 2, 3, 4, 5, 6, 7, 8})},
      Send{data_frame(0x5, IdFormat::extended, {})}, Send{Frame::remote(0x10, IdFormat::standard, 1).value()},
      FrameMessage{data_frame(0x1FFFFFFF, IdFormat::extended, {0xFF}, ts)},
      FrameMessage{data_frame(0x0, IdFormat::standard, {}, ts)}, FrameMessage{rtr}, Statistics{1000},
      Stat{123456789012ULL, 1, 0, 99}};
  for (const auto& m : all) {
    const std::string text = format(m);
    auto back = parse(text);
    ASSERT_TRUE(back) << text << ": " << back.error().message();
    EXPECT_EQ(back.value(), m) << text;
    EXPECT_EQ(format(back.value()), text);
  }
}

// ------------------------------------------------------------------------------------- tokenizer

std::vector<std::string> drain(Tokenizer& t, std::vector<std::string>* errors = nullptr) {
  std::vector<std::string> out;
  while (auto r = t.next()) {
    if (*r)
      out.push_back(r->value());
    else if (errors)
      errors->push_back(r->error().detail);
  }
  return out;
}

TEST(SocketcandTokenizer, SplitsBackToBackMessages) {
  Tokenizer t;
  t.feed("< hi >< ok >< frame 123 1.000000 11 >");
  EXPECT_EQ(drain(t), (std::vector<std::string>{"< hi >", "< ok >", "< frame 123 1.000000 11 >"}));
  EXPECT_EQ(t.buffered(), 0u);
  EXPECT_EQ(t.stats().messages, 3u);
  EXPECT_EQ(t.stats().errors, 0u);
}

TEST(SocketcandTokenizer, WhitespaceBetweenMessagesIsNotAnError) {
  Tokenizer t;
  t.feed("  < hi >\n< ok >\r\n\t< echo > ");
  EXPECT_EQ(drain(t), (std::vector<std::string>{"< hi >", "< ok >", "< echo >"}));
  EXPECT_EQ(t.stats().errors, 0u);
}

TEST(SocketcandTokenizer, EverySplitPointGivesTheSameMessages) {
  const std::string stream = "< hi >< ok >\n< frame 123 1.000000 11 >< send 1 0  >< error oops >";
  const std::vector<std::string> expected = {"< hi >", "< ok >", "< frame 123 1.000000 11 >", "< send 1 0  >",
                                             "< error oops >"};
  for (std::size_t cut = 0; cut <= stream.size(); ++cut) {
    Tokenizer t;
    t.feed(stream.substr(0, cut));
    auto got = drain(t);
    t.feed(stream.substr(cut));
    auto rest = drain(t);
    got.insert(got.end(), rest.begin(), rest.end());
    EXPECT_EQ(got, expected) << "cut at " << cut;
    EXPECT_EQ(t.stats().errors, 0u);
  }
}

TEST(SocketcandTokenizer, OneByteAtATime) {
  const std::string stream = "< open vcan0 >< rawmode >< send 123 2 1 2 >";
  Tokenizer t;
  std::vector<std::string> got;
  for (char c : stream) {
    t.feed(std::string_view(&c, 1));
    auto part = drain(t);
    got.insert(got.end(), part.begin(), part.end());
  }
  EXPECT_EQ(got, (std::vector<std::string>{"< open vcan0 >", "< rawmode >", "< send 123 2 1 2 >"}));
}

TEST(SocketcandTokenizer, GarbageIsSkippedAndReportedOncePerRun) {
  Tokenizer t;
  std::vector<std::string> errors;
  t.feed("junk< hi > more junk \n< ok >");
  EXPECT_EQ(drain(t, &errors), (std::vector<std::string>{"< hi >", "< ok >"}));
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_NE(errors[0].find("4 garbage byte(s)"), std::string::npos) << errors[0];
  EXPECT_NE(errors[0].find("junk"), std::string::npos) << errors[0];
  EXPECT_NE(errors[1].find("8 garbage byte(s)"), std::string::npos) << errors[1];
  EXPECT_EQ(errors[1].find('<'), std::string::npos) << "errors must be fit to quote in '< error ... >'";
  EXPECT_EQ(t.stats().errors, 2u);
  EXPECT_EQ(t.stats().garbage_bytes, 12u);
}

TEST(SocketcandTokenizer, GarbageRunSplitAcrossReadsIsOneError) {
  Tokenizer t;
  std::vector<std::string> errors;
  t.feed("ab");
  EXPECT_TRUE(drain(t, &errors).empty());
  t.feed("cd< hi >");
  EXPECT_EQ(drain(t, &errors), (std::vector<std::string>{"< hi >"}));
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("4 garbage byte(s)"), std::string::npos) << errors[0];
}

TEST(SocketcandTokenizer, EndlessGarbageIsReportedWithoutWaitingForALessThan) {
  Tokenizer t(32);
  std::vector<std::string> errors;
  t.feed(std::string(100, 'x'));
  drain(t, &errors);
  EXPECT_EQ(errors.size(), 3u);  // one per 32 bytes
  EXPECT_EQ(t.buffered(), 0u);   // nothing kept
}

TEST(SocketcandTokenizer, OverlongMessageIsAnErrorAndSkippedToItsEnd) {
  Tokenizer t(16);
  std::vector<std::string> errors;
  t.feed("< error this is far too long for sixteen > < ok >");
  EXPECT_EQ(drain(t, &errors), (std::vector<std::string>{"< ok >"}));
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("longer than 16 bytes"), std::string::npos) << errors[0];
  EXPECT_EQ(t.stats().overlong, 1u);
}

TEST(SocketcandTokenizer, OverlongMessageWithoutEndStopsAtTheNextMessage) {
  Tokenizer t(16);
  std::vector<std::string> errors;
  t.feed("< aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa");
  EXPECT_TRUE(drain(t, &errors).empty());
  EXPECT_EQ(errors.size(), 1u);
  EXPECT_LT(t.buffered(), 64u);  // the long message is not accumulated
  t.feed("aaaa< hi >");
  EXPECT_EQ(drain(t, &errors), (std::vector<std::string>{"< hi >"}));
  EXPECT_EQ(errors.size(), 1u);
}

TEST(SocketcandTokenizer, ExactlyMaxLengthIsAccepted) {
  const std::string msg = "< error " + std::string(6, 'x') + " >";  // 16 bytes
  ASSERT_EQ(msg.size(), 16u);
  Tokenizer t(16);
  t.feed(msg);
  EXPECT_EQ(drain(t), (std::vector<std::string>{msg}));
  Tokenizer shorter(15);
  shorter.feed(msg);
  EXPECT_TRUE(drain(shorter).empty());
  EXPECT_EQ(shorter.stats().overlong, 1u);
}

TEST(SocketcandTokenizer, LessThanInsideAMessageStartsANewOne) {
  Tokenizer t;
  std::vector<std::string> errors;
  t.feed("< send 123 < hi >");
  EXPECT_EQ(drain(t, &errors), (std::vector<std::string>{"< hi >"}));
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("cut short"), std::string::npos) << errors[0];
  EXPECT_NE(errors[0].find("< send 123"), std::string::npos) << errors[0];
  EXPECT_EQ(t.stats().unterminated, 1u);
}

TEST(SocketcandTokenizer, StrayGreaterThanIsGarbage) {
  Tokenizer t;
  std::vector<std::string> errors;
  t.feed(">< ok >");
  EXPECT_EQ(drain(t, &errors), (std::vector<std::string>{"< ok >"}));
  EXPECT_EQ(errors.size(), 1u);
}

TEST(SocketcandTokenizer, LongStreamsDoNotGrowTheBuffer) {
  Tokenizer t;
  const std::string msg = "< frame 123 1.000000 1122334455667788 >";
  std::size_t n = 0;
  for (int i = 0; i < 10000; ++i) {
    t.feed(msg);
    t.feed(msg.substr(0, 7));  // leave a partial message behind each time
    n += drain(t).size();
    t.feed(msg.substr(7));
    n += drain(t).size();
    EXPECT_LT(t.buffered(), msg.size());
  }
  EXPECT_EQ(n, 20000u);
}

}  // namespace
}  // namespace axon::can::socketcand
