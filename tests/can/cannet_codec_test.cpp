// The CAN@net ASCII line codec: every line type parsed and formatted, and malformed lines rejected
// with a message that says what is wrong.
#include "axon/can/cannet_codec.hpp"

#include <gtest/gtest.h>

#include <array>
#include <string>
#include <vector>

namespace axon::can::cannet {
namespace {

Frame ext(std::uint32_t id, std::vector<std::uint8_t> bytes) { return Frame::extended(id, bytes).value(); }
Frame std_(std::uint32_t id, std::vector<std::uint8_t> bytes) { return Frame::standard(id, bytes).value(); }

// The line parses to `expected` and `expected` formats back to exactly `text`.
void expect_both_ways(const std::string& text, const Line& expected) {
  auto parsed = parse_line(text);
  ASSERT_TRUE(parsed) << text << ": " << parsed.error().message();
  EXPECT_EQ(parsed.value(), expected) << text;
  EXPECT_EQ(format_line(expected), text);
}

// The line is rejected as a parse error whose message contains `why`.
void expect_rejected(const std::string& text, const std::string& why) {
  auto parsed = parse_line(text);
  ASSERT_FALSE(parsed) << "accepted: '" << text << "' as " << format_line(parsed.value());
  EXPECT_EQ(parsed.error(), CanErrc::parse_error);
  EXPECT_NE(parsed.error().detail.find(why), std::string::npos)
      << "message '" << parsed.error().detail << "' does not mention '" << why << "'";
}

TEST(CanNetCodec, HostCommandsBothWays) {
  expect_both_ways("CAN 1 STOP", CanStop{1});
  expect_both_ways("CAN 4 START", CanStart{4});
  expect_both_ways("CAN 2 INIT STD 1000", CanInit{2, 1'000'000});
  expect_both_ways("CAN 3 INIT STD 125", CanInit{3, 125'000});
  expect_both_ways("CAN 1 INIT STD 83.3", CanInit{1, 83'300});
  expect_both_ways("CAN 1 INIT STD 62.5", CanInit{1, 62'500});
  expect_both_ways("CAN 1 FILTER CLEAR", CanFilterClear{1});
  expect_both_ways("CAN 1 FILTER ADD EXT 00000000 00000000", CanFilterAdd{1, IdFormat::extended, 0, 0});
  expect_both_ways("CAN 2 FILTER ADD EXT 1FFFFFFF 00FF0000", CanFilterAdd{2, IdFormat::extended, 0x1FFFFFFF, 0xFF0000});
  expect_both_ways("CAN 3 FILTER ADD STD 123 7FF", CanFilterAdd{3, IdFormat::standard, 0x123, 0x7FF});
  expect_both_ways("CAN 4 STATUS", CanStatusRequest{4});
  expect_both_ways("DEV IDENTIFY", DevIdentify{});
  expect_both_ways("DEV VERSION", DevVersion{});
}

TEST(CanNetCodec, FramesBothWays) {
  expect_both_ways("M 1 CED 0123ABCD 01 02 03 04 05 06 07 08",
                   FrameMessage{1, ext(0x0123ABCD, {1, 2, 3, 4, 5, 6, 7, 8})});
  expect_both_ways("M 2 CED 00000000", FrameMessage{2, ext(0, {})});
  expect_both_ways("M 3 CSD 7FF DE AD", FrameMessage{3, std_(0x7FF, {0xDE, 0xAD})});
  expect_both_ways("M 4 CSD 000", FrameMessage{4, std_(0, {})});
  expect_both_ways("M 1 CER 1FFFFFFF dlc=8", FrameMessage{1, Frame::remote(0x1FFFFFFF, IdFormat::extended, 8).value()});
  expect_both_ways("M 1 CSR 101 dlc=5", FrameMessage{1, Frame::remote(0x101, IdFormat::standard, 5).value()});
  expect_both_ways("M 1 CSR 101 dlc=0", FrameMessage{1, Frame::remote(0x101, IdFormat::standard, 0).value()});
}

TEST(CanNetCodec, FramesAcceptShortFieldsAndLowerCaseHex) {
  // What a peer may write besides the canonical form; all mean the same frame.
  auto a = parse_line("M 1 CSD 7f 1 a0");
  ASSERT_TRUE(a) << a.error().message();
  EXPECT_EQ(a.value(), Line(FrameMessage{1, std_(0x7F, {0x01, 0xA0})}));
  auto b = parse_line("M 1 CED 5 ff");
  ASSERT_TRUE(b);
  EXPECT_EQ(b.value(), Line(FrameMessage{1, ext(5, {0xFF})}));
  // A remote frame without dlc= has length 0; the device's own example writes dlc=05.
  auto c = parse_line("M 2 CER 00000123");
  ASSERT_TRUE(c);
  EXPECT_EQ(c.value(), Line(FrameMessage{2, Frame::remote(0x123, IdFormat::extended, 0).value()}));
  auto d = parse_line("M 2 CSR 101 dlc=05");
  ASSERT_TRUE(d);
  EXPECT_EQ(std::get<FrameMessage>(d.value()).frame.dlc(), 5);
}

TEST(CanNetCodec, RepliesBothWays) {
  expect_both_ways("R ok", ReplyOk{});
  expect_both_ways("R ERR 1 invalid baudrate", ReplyError{1, "invalid baudrate"});
  expect_both_ways("R ERR 17", ReplyError{17, ""});
  expect_both_ways("R CAN 1 ----- 100", ReplyStatus{1, StatusFlags{}, 100});
  expect_both_ways("R CAN 2 -E-T- 24", ReplyStatus{2, StatusFlags{false, true, false, true, false}, 24});
  expect_both_ways("R CAN 3 BEOTI 0", ReplyStatus{3, StatusFlags{true, true, true, true, true}, 0});
  expect_both_ways("R CAN 4 ----I 100", ReplyStatus{4, StatusFlags{false, false, false, false, true}, 100});
  expect_both_ways("R CAN@net NT 420", ReplyText{"CAN@net NT 420"});
  expect_both_ways("R V1.5.0", ReplyText{"V1.5.0"});
  // A text answer that starts with CAN but is not a status reply.
  expect_both_ways("R CAN CAN", ReplyText{"CAN CAN"});
}

TEST(CanNetCodec, PositiveReplyInAnyCase) {
  auto r = parse_line("R OK");
  ASSERT_TRUE(r);
  EXPECT_EQ(r.value(), Line(ReplyOk{}));
}

TEST(CanNetCodec, EventsBothWays) {
  expect_both_ways("E 1 BUSOFF SET", Event{1, EventKind::bus_off, true, 0});
  expect_both_ways("E 2 ERRORWARNING SET", Event{2, EventKind::error_warning, true, 0});
  expect_both_ways("E 3 ERRORWARNING RESET", Event{3, EventKind::error_warning, false, 0});
  expect_both_ways("E 4 TXOVERFLOW 12", Event{4, EventKind::tx_overflow, true, 12});
  // The device manual's form without SET.
  auto bare = parse_line("E 2 BUSOFF");
  ASSERT_TRUE(bare);
  EXPECT_EQ(bare.value(), Line(Event{2, EventKind::bus_off, true, 0}));
}

TEST(CanNetCodec, LineEndingsAndBlanks) {
  for (const char* text : {"CAN 1 START\n", "CAN 1 START\r\n", "CAN 1 START\r", "  CAN  1\tSTART  "}) {
    auto r = parse_line(text);
    ASSERT_TRUE(r) << r.error().message();
    EXPECT_EQ(r.value(), Line(CanStart{1}));
  }
  auto text = parse_line("R CAN@net NT 420 \r\n");
  ASSERT_TRUE(text);
  EXPECT_EQ(text.value(), Line(ReplyText{"CAN@net NT 420"}));
  auto err = parse_line("R ERR 2 wrong  state\r\n");
  ASSERT_TRUE(err);
  EXPECT_EQ(err.value(), Line(ReplyError{2, "wrong  state"}));
}

TEST(CanNetCodec, ClassifiesDirections) {
  EXPECT_TRUE(is_host_command(CanStop{1}));
  EXPECT_TRUE(is_host_command(DevVersion{}));
  EXPECT_FALSE(is_host_command(FrameMessage{}));
  EXPECT_FALSE(is_host_command(Event{}));
  EXPECT_TRUE(is_reply(ReplyText{"x"}));
  EXPECT_TRUE(is_reply(ReplyStatus{}));
  EXPECT_FALSE(is_reply(Event{}));
  EXPECT_FALSE(is_reply(FrameMessage{}));
}

TEST(CanNetCodec, RejectsEmptyAndUnknown) {
  expect_rejected("", "empty line");
  expect_rejected("\n", "empty line");
  expect_rejected("   \r\n", "empty line");
  expect_rejected("X 1 STOP", "unknown line type 'X'");
  expect_rejected("m 1 CSD 123", "unknown line type 'm'");
  expect_rejected("CAN 1 HALT", "unknown CAN command 'HALT'");
  expect_rejected("CAN 1", "missing command");
  expect_rejected("CAN 1 FILTER", "missing FILTER command");
  expect_rejected("CAN 1 FILTER DROP", "unknown FILTER command 'DROP'");
  expect_rejected("DEV RESET", "unknown DEV command 'RESET'");
  expect_rejected("DEV", "missing DEV command");
  expect_rejected("E 1 OVERHEAT", "unknown event 'OVERHEAT'");
  expect_rejected("R", "empty reply");
}

TEST(CanNetCodec, RejectsBadChannels) {
  expect_rejected("CAN 0 STOP", "channel '0' is not 1..4");
  expect_rejected("CAN 5 STOP", "channel '5' is not 1..4");
  expect_rejected("CAN 12 STOP", "channel '12'");
  expect_rejected("CAN a STOP", "channel 'a'");
  expect_rejected("M 9 CSD 123", "channel '9'");
  expect_rejected("E 0 BUSOFF", "channel '0'");
  expect_rejected("R CAN 5 ----- 100", "channel '5'");
  expect_rejected("M", "missing channel");
}

TEST(CanNetCodec, RejectsBadFrames) {
  expect_rejected("M 1 CED 0123ABCG 01", "id '0123ABCG' is not 1..8 hex digits");
  expect_rejected("M 1 CED 123456789", "not 1..8 hex digits");
  expect_rejected("M 1 CED 20000000", "does not fit 29 bits");
  expect_rejected("M 1 CSD 800", "does not fit 11 bits");
  expect_rejected("M 1 CSD 0123", "not 1..3 hex digits");
  expect_rejected("M 1 CSD 123 1 2 3 4 5 6 7 8 9", "9 data bytes");
  expect_rejected("M 1 CSD 123 0G", "data byte 1 '0G'");
  expect_rejected("M 1 CSD 123 01 100", "data byte 2 '100'");
  expect_rejected("M 1 CSD 123 -1", "data byte 1");
  expect_rejected("M 1 CXD 123", "frame format 'CXD'");
  expect_rejected("M 1 CS 123", "frame format 'CS'");
  expect_rejected("M 1 FED 18FE0201 01", "CAN FD");
  expect_rejected("M 1 CSD", "too few fields");
  expect_rejected("M 1 CSR 123 dlc=9", "remote frame length '9'");
  expect_rejected("M 1 CSR 123 dlc=", "remote frame length");
  expect_rejected("M 1 CSR 123 01", "remote frame carries '01'");
  expect_rejected("M 1 CSR 123 dlc=1 02", "unexpected '02'");
  expect_rejected("M 1 CSD 123 dlc=1", "dlc= belongs to remote frames");
}

TEST(CanNetCodec, RejectsBadCommands) {
  expect_rejected("CAN 1 STOP now", "unexpected 'now' after the end");
  expect_rejected("CAN 1 START 1", "unexpected '1'");
  expect_rejected("CAN 1 STATUS x", "unexpected 'x'");
  expect_rejected("DEV IDENTIFY me", "unexpected 'me'");
  expect_rejected("CAN 1 INIT STD", "too few fields");
  expect_rejected("CAN 1 INIT USER 1000", "INIT mode 'USER'");
  expect_rejected("CAN 1 INIT STD fast", "bitrate 'fast'");
  expect_rejected("CAN 1 INIT STD 0", "bitrate '0'");
  expect_rejected("CAN 1 INIT STD 83.33", "bitrate '83.33'");
  expect_rejected("CAN 1 INIT STD 1000.", "bitrate");
  expect_rejected("CAN 1 INIT STD 1000 extra", "unexpected 'extra'");
  expect_rejected("CAN 1 FILTER ADD EXT 00000000", "too few fields");
  expect_rejected("CAN 1 FILTER ADD ANY 0 0", "filter format 'ANY'");
  expect_rejected("CAN 1 FILTER ADD STD 800 7FF", "filter id 0x800 does not fit 11 bits");
  expect_rejected("CAN 1 FILTER ADD EXT 0 3FFFFFFF", "filter mask 0x3FFFFFFF does not fit 29 bits");
  expect_rejected("CAN 1 FILTER CLEAR all", "unexpected 'all'");
}

TEST(CanNetCodec, RejectsBadRepliesAndEvents) {
  expect_rejected("R ok then", "unexpected 'then'");
  expect_rejected("R ERR", "without a number");
  expect_rejected("R ERR x broken", "error number 'x'");
  expect_rejected("R CAN 1 ---- 100", "not 5 characters");
  expect_rejected("R CAN 1 E---- 100", "status flag 1 is 'E'");
  expect_rejected("R CAN 1 -----", "too few fields");
  expect_rejected("R CAN 1 ----- 101", "free transmit buffers '101'");
  expect_rejected("R CAN 1 ----- x", "free transmit buffers 'x'");
  expect_rejected("R CAN 1 ----- 100 more", "unexpected 'more'");
  expect_rejected("E 1 BUSOFF RESET", "BUSOFF followed by 'RESET'");
  expect_rejected("E 1 BUSOFF SET now", "unexpected 'now'");
  expect_rejected("E 1 ERRORWARNING", "too few fields");
  expect_rejected("E 1 ERRORWARNING MAYBE", "ERRORWARNING 'MAYBE'");
  expect_rejected("E 1 TXOVERFLOW 0", "TXOVERFLOW count '0'");
  expect_rejected("E 1", "missing event name");
}

TEST(CanNetCodec, RejectsControlCharactersAndOverlongLines) {
  expect_rejected(std::string("CAN 1 ST\0P", 10), "byte 0x00 at column 9");
  expect_rejected("R ok\n\n", "byte 0x0A");
  expect_rejected("R V1\r5", "byte 0x0D");
  expect_rejected("R caf\xC3\xA9", "byte 0xC3");
  expect_rejected("R " + std::string(kMaxLineLength, 'x'), "longer than");
}

TEST(CanNetCodec, ErrorMessageQuotesTheLine) {
  auto r = parse_line("M 1 CSD 123 ZZ");
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().detail.find("'M 1 CSD 123 ZZ'"), std::string::npos) << r.error().detail;
}

TEST(CanNetCodec, Bitrates) {
  EXPECT_EQ(format_kbit(1'000'000), "1000");
  EXPECT_EQ(format_kbit(83'300), "83.3");
  EXPECT_EQ(format_kbit(5'000), "5");
  EXPECT_TRUE(is_standard_bitrate(1'000'000));
  EXPECT_TRUE(is_standard_bitrate(62'500));
  EXPECT_FALSE(is_standard_bitrate(333'000));
  EXPECT_TRUE(check_channel(1));
  EXPECT_TRUE(check_channel(4));
  EXPECT_FALSE(check_channel(0));
  EXPECT_FALSE(check_channel(5));
}

TEST(CanNetCodec, FormatFrameMatchesFormatLine) {
  const Frame f = ext(0x18FE0201, {1, 2, 3});
  EXPECT_EQ(format_frame(2, f), "M 2 CED 18FE0201 01 02 03");
  EXPECT_EQ(format_frame(2, f), format_line(FrameMessage{2, f}));
}

// The allocation-free formatter writes exactly what the string one does, for every shape.
TEST(CanNetCodec, FormatFrameToMatchesFormatFrame) {
  const std::vector<Frame> frames = {
      Frame::parse("000#").value(),          Frame::parse("7FF#FFFFFFFFFFFFFFFF").value(),
      Frame::parse("1FFFFFFF#00").value(),    Frame::parse("00000001#0102030405060708").value(),
      Frame::parse("123#R").value(),          Frame::parse("1ABCDEF0#R8").value(),
      Frame::parse("0AB#DEADBEEF").value(),
  };
  const std::vector<std::string> expected = {
      "M 1 CSD 000",          "M 1 CSD 7FF FF FF FF FF FF FF FF FF", "M 1 CED 1FFFFFFF 00",
      "M 1 CED 00000001 01 02 03 04 05 06 07 08", "M 1 CSR 123 dlc=0", "M 1 CER 1ABCDEF0 dlc=8",
      "M 1 CSD 0AB DE AD BE EF",
  };
  FrameLineBuffer buf;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    EXPECT_EQ(format_frame_to(buf, 1, frames[i]), expected[i]);
    for (int ch = 1; ch <= 4; ++ch) EXPECT_EQ(format_frame_to(buf, ch, frames[i]), format_line(FrameMessage{ch, frames[i]}));
    auto back = parse_line(format_frame_to(buf, 3, frames[i]));
    ASSERT_TRUE(back.has_value());
    EXPECT_EQ(back.value(), (Line{FrameMessage{3, frames[i]}}));
  }
}

}  // namespace
}  // namespace axon::can::cannet

namespace axon::can::cannet {
namespace {

// A piece's text points into the splitter, valid until its next call: kept as copies here.
struct Kept {
  std::string text;
  bool overlong = false;
};

std::vector<Kept> feed(LineSplitter& s, std::string_view bytes) {
  s.append(bytes);
  std::vector<Kept> out;
  while (auto p = s.next()) out.push_back(Kept{std::string(p->text), p->overlong});
  return out;
}

TEST(CanNetLineSplitter, CutsAtNewlinesAcrossChunks) {
  LineSplitter s;
  auto a = feed(s, "R ok\nM 1 CSD 1");
  ASSERT_EQ(a.size(), 1u);
  EXPECT_EQ(a[0].text, "R ok");
  EXPECT_EQ(s.buffered(), 9u);  // the partial line waits
  auto b = feed(s, "23 01\r\n\nE 1 BUSOFF\n");
  ASSERT_EQ(b.size(), 3u);
  EXPECT_EQ(b[0].text, "M 1 CSD 123 01\r");  // '\r' is left for parse_line
  EXPECT_EQ(b[1].text, "");
  EXPECT_EQ(b[2].text, "E 1 BUSOFF");
  EXPECT_FALSE(b[2].overlong);
  EXPECT_EQ(s.buffered(), 0u);
}

TEST(CanNetLineSplitter, ReportsAnOverlongLineOnceAndResumesAfterIt) {
  LineSplitter s(8);
  auto a = feed(s, "0123456789");  // already too long, no newline yet
  ASSERT_EQ(a.size(), 1u);
  EXPECT_TRUE(a[0].overlong);
  auto b = feed(s, "more of it\nR ok\n");
  ASSERT_EQ(b.size(), 1u);
  EXPECT_EQ(b[0].text, "R ok");
  auto c = feed(s, "123456789\nR ok\n");  // too long but complete in one chunk
  ASSERT_EQ(c.size(), 2u);
  EXPECT_TRUE(c[0].overlong);
  EXPECT_EQ(c[1].text, "R ok");
  auto d = feed(s, "12345678\n");  // exactly the limit is fine
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].text, "12345678");
}

}  // namespace
}  // namespace axon::can::cannet
