#include "axon/can/cannet_codec.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <iterator>
#include <vector>

namespace axon::can::cannet {
namespace {

constexpr std::array<std::uint32_t, 12> kStandardBitrates = {5'000,   10'000,  20'000,  50'000,  62'500,  83'300,
                                                             100'000, 125'000, 250'000, 500'000, 800'000, 1'000'000};

// The line as it can be shown in an error message: control and non-ASCII bytes escaped, long
// lines cut.
std::string quote(std::string_view line) {
  constexpr std::size_t kShown = 80;
  std::string out;
  for (std::size_t i = 0; i < line.size() && i < kShown; ++i) {
    const auto c = static_cast<unsigned char>(line[i]);
    if (c < 0x20 || c >= 0x7F)
      out += fmt::format("\\x{:02X}", c);
    else
      out += static_cast<char>(c);
  }
  if (line.size() > kShown) out += fmt::format("... ({} characters)", line.size());
  return out;
}

bool is_space(char c) noexcept { return c == ' ' || c == '\t'; }

struct Token {
  std::string_view text;
  std::size_t offset = 0;  // where it starts in the line
};

// The tokens of a line without allocating: the first kMaxTokens are kept, all are counted. No line
// the parser accepts has more than 12; the count alone is enough to reject longer ones.
struct Tokens {
  static constexpr std::size_t kMaxTokens = 16;
  std::array<Token, kMaxTokens> kept{};
  std::size_t count = 0;

  [[nodiscard]] std::size_t size() const noexcept { return count; }
  [[nodiscard]] bool empty() const noexcept { return count == 0; }
  // Tokens beyond the kept ones read as empty (only ever asked for to quote them in a message).
  const Token& operator[](std::size_t i) const noexcept {
    static const Token none{};
    return i < kMaxTokens ? kept[i] : none;
  }
};

Tokens split(std::string_view line) {
  Tokens tokens;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_space(line[i])) ++i;
    if (i == line.size()) break;
    const std::size_t start = i;
    while (i < line.size() && !is_space(line[i])) ++i;
    if (tokens.count < Tokens::kMaxTokens) tokens.kept[tokens.count] = Token{line.substr(start, i - start), start};
    ++tokens.count;
  }
  return tokens;
}

// The rest of the line from `offset`, without trailing blanks.
std::string_view rest_of_line(std::string_view line, std::size_t offset) {
  std::string_view r = line.substr(offset);
  while (!r.empty() && is_space(r.back())) r.remove_suffix(1);
  return r;
}

bool parse_hex(std::string_view s, std::size_t max_digits, std::uint32_t& out) {
  if (s.empty() || s.size() > max_digits) return false;
  if (!std::all_of(s.begin(), s.end(), [](char c) { return std::isxdigit(static_cast<unsigned char>(c)) != 0; }))
    return false;
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), out, 16);
  return ec == std::errc() && p == s.data() + s.size();
}

bool parse_dec(std::string_view s, std::size_t max_digits, std::uint32_t& out) {
  if (s.empty() || s.size() > max_digits) return false;
  if (!std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; })) return false;
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), out, 10);
  return ec == std::errc() && p == s.data() + s.size();
}

bool iequals(std::string_view a, std::string_view b) noexcept {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::toupper(static_cast<unsigned char>(x)) == std::toupper(static_cast<unsigned char>(y));
         });
}

class Parser {
 public:
  explicit Parser(std::string_view line) : line_(line) {}

  Result<Line> run() {
    // Line ending: "\n", "\r\n", or none.
    if (!line_.empty() && line_.back() == '\n') line_.remove_suffix(1);
    if (!line_.empty() && line_.back() == '\r') line_.remove_suffix(1);
    for (std::size_t i = 0; i < line_.size(); ++i) {
      const auto c = static_cast<unsigned char>(line_[i]);
      if ((c < 0x20 && c != '\t') || c >= 0x7F)
        return bad(fmt::format("byte 0x{:02X} at column {} is not printable ASCII", c, i + 1));
    }
    if (line_.size() > kMaxLineLength) return bad(fmt::format("longer than {} characters", kMaxLineLength));
    tokens_ = split(line_);
    if (tokens_.empty()) return bad("empty line");
    const std::string_view type = tokens_[0].text;
    if (type == "M") return frame();
    if (type == "CAN") return can_command();
    if (type == "DEV") return dev_command();
    if (type == "R") return reply();
    if (type == "E") return event();
    return bad(fmt::format("unknown line type '{}' (expected M, CAN, DEV, R or E)", quote(type)));
  }

 private:
  Error bad(std::string_view why) const {
    return Error(CanErrc::parse_error, fmt::format("CAN@net line '{}': {}", quote(line_), why));
  }

  // Fails unless the line has exactly n tokens.
  Result<void> expect_tokens(std::size_t n, std::string_view shape) const {
    if (tokens_.size() < n) return bad(fmt::format("too few fields (expected '{}')", shape));
    if (tokens_.size() > n)
      return bad(fmt::format("unexpected '{}' after the end (expected '{}')", quote(tokens_[n].text), shape));
    return ok();
  }

  Result<int> channel(std::size_t index) const {
    if (tokens_.size() <= index) return bad("missing channel number");
    const std::string_view t = tokens_[index].text;
    if (t.size() != 1 || t[0] < '0' + kMinChannel || t[0] > '0' + kMaxChannel)
      return bad(fmt::format("channel '{}' is not {}..{}", quote(t), kMinChannel, kMaxChannel));
    return t[0] - '0';
  }

  Result<std::uint32_t> id(std::string_view t, IdFormat idf, std::string_view what) const {
    const bool ext = idf == IdFormat::extended;
    std::uint32_t v = 0;
    if (!parse_hex(t, ext ? 8 : 3, v))
      return bad(fmt::format("{} '{}' is not 1..{} hex digits", what, quote(t), ext ? 8 : 3));
    const std::uint32_t max = ext ? Frame::kMaxExtendedId : Frame::kMaxStandardId;
    if (v > max)
      return bad(fmt::format("{} 0x{:X} does not fit {} bits (max 0x{:X})", what, v, ext ? 29 : 11, max));
    return v;
  }

  Result<Line> frame() const {
    AXON_TRY(ch, channel(1));
    if (tokens_.size() < 4) return bad("too few fields (expected 'M <channel> CED|CSD|CER|CSR <id> [bytes]')");
    const std::string_view f = tokens_[2].text;
    if (f.size() == 3 && f[0] == 'F') return bad("CAN FD frames are not supported");
    if (f.size() != 3 || f[0] != 'C' || (f[1] != 'E' && f[1] != 'S') || (f[2] != 'D' && f[2] != 'R'))
      return bad(fmt::format("frame format '{}' is not CED, CSD, CER or CSR", quote(f)));
    const IdFormat idf = f[1] == 'E' ? IdFormat::extended : IdFormat::standard;
    AXON_TRY(frame_id, id(tokens_[3].text, idf, "id"));
    if (f[2] == 'R') {
      std::uint32_t dlc = 0;
      if (tokens_.size() >= 5) {
        const std::string_view t = tokens_[4].text;
        if (t.substr(0, 4) != "dlc=") return bad(fmt::format("remote frame carries '{}' (only dlc=0..8)", quote(t)));
        if (!parse_dec(t.substr(4), 2, dlc) || dlc > Frame::kMaxData)
          return bad(fmt::format("remote frame length '{}' is not 0..8", quote(t.substr(4))));
      }
      AXON_TRY(expect_tokens(tokens_.size() >= 5 ? 5 : 4, "M <channel> CER|CSR <id> [dlc=<0..8>]"));
      AXON_TRY(fr, Frame::remote(frame_id, idf, static_cast<std::uint8_t>(dlc)));
      return Line{FrameMessage{ch, fr}};
    }
    const std::size_t nbytes = tokens_.size() - 4;
    if (nbytes > Frame::kMaxData) return bad(fmt::format("{} data bytes (classic CAN carries at most 8)", nbytes));
    std::array<std::uint8_t, Frame::kMaxData> bytes{};
    for (std::size_t i = 0; i < nbytes; ++i) {
      const std::string_view t = tokens_[4 + i].text;
      if (t.substr(0, 4) == "dlc=") return bad("dlc= belongs to remote frames only (a data frame's length is its byte count)");
      std::uint32_t v = 0;
      if (!parse_hex(t, 2, v)) return bad(fmt::format("data byte {} '{}' is not 1..2 hex digits", i + 1, quote(t)));
      bytes[i] = static_cast<std::uint8_t>(v);
    }
    AXON_TRY(fr, Frame::data(frame_id, idf, std::span<const std::uint8_t>(bytes.data(), nbytes)));
    return Line{FrameMessage{ch, fr}};
  }

  Result<Line> can_command() const {
    AXON_TRY(ch, channel(1));
    if (tokens_.size() < 3) return bad("missing command after the channel (STOP, START, INIT, FILTER, STATUS)");
    const std::string_view cmd = tokens_[2].text;
    if (cmd == "STOP") {
      AXON_TRY(expect_tokens(3, "CAN <channel> STOP"));
      return Line{CanStop{ch}};
    }
    if (cmd == "START") {
      AXON_TRY(expect_tokens(3, "CAN <channel> START"));
      return Line{CanStart{ch}};
    }
    if (cmd == "STATUS") {
      AXON_TRY(expect_tokens(3, "CAN <channel> STATUS"));
      return Line{CanStatusRequest{ch}};
    }
    if (cmd == "INIT") return init(ch);
    if (cmd == "FILTER") return filter(ch);
    return bad(fmt::format("unknown CAN command '{}' (expected STOP, START, INIT, FILTER or STATUS)", quote(cmd)));
  }

  Result<Line> init(int ch) const {
    constexpr std::string_view shape = "CAN <channel> INIT STD <kbit/s>";
    AXON_TRY(expect_tokens(5, shape));
    if (tokens_[3].text != "STD")
      return bad(fmt::format("INIT mode '{}' is not supported (only STD with a standard bitrate)", quote(tokens_[3].text)));
    const std::string_view t = tokens_[4].text;
    const auto dot = t.find('.');
    std::uint32_t whole = 0, tenth = 0;
    const bool ok_whole = parse_dec(t.substr(0, dot), 5, whole);
    const bool ok_tenth = dot == std::string_view::npos || parse_dec(t.substr(dot + 1), 1, tenth);
    if (!ok_whole || !ok_tenth || whole * 1000 + tenth * 100 == 0)
      return bad(fmt::format("bitrate '{}' is not a positive kbit/s value like 1000 or 83.3", quote(t)));
    return Line{CanInit{ch, whole * 1000 + tenth * 100}};
  }

  Result<Line> filter(int ch) const {
    if (tokens_.size() < 4) return bad("missing FILTER command (CLEAR or ADD)");
    const std::string_view sub = tokens_[3].text;
    if (sub == "CLEAR") {
      AXON_TRY(expect_tokens(4, "CAN <channel> FILTER CLEAR"));
      return Line{CanFilterClear{ch}};
    }
    if (sub != "ADD") return bad(fmt::format("unknown FILTER command '{}' (expected CLEAR or ADD)", quote(sub)));
    constexpr std::string_view shape = "CAN <channel> FILTER ADD EXT|STD <id> <mask>";
    AXON_TRY(expect_tokens(7, shape));
    const std::string_view f = tokens_[4].text;
    if (f != "EXT" && f != "STD") return bad(fmt::format("filter format '{}' is not EXT or STD", quote(f)));
    const IdFormat idf = f == "EXT" ? IdFormat::extended : IdFormat::standard;
    AXON_TRY(fid, id(tokens_[5].text, idf, "filter id"));
    AXON_TRY(fmask, id(tokens_[6].text, idf, "filter mask"));
    return Line{CanFilterAdd{ch, idf, fid, fmask}};
  }

  Result<Line> dev_command() const {
    if (tokens_.size() < 2) return bad("missing DEV command (IDENTIFY or VERSION)");
    const std::string_view cmd = tokens_[1].text;
    if (cmd == "IDENTIFY") {
      AXON_TRY(expect_tokens(2, "DEV IDENTIFY"));
      return Line{DevIdentify{}};
    }
    if (cmd == "VERSION") {
      AXON_TRY(expect_tokens(2, "DEV VERSION"));
      return Line{DevVersion{}};
    }
    return bad(fmt::format("unknown DEV command '{}' (expected IDENTIFY or VERSION)", quote(cmd)));
  }

  Result<Line> reply() const {
    if (tokens_.size() < 2) return bad("empty reply (expected 'R ok', 'R ERR <n> <text>' or 'R <text>')");
    const std::string_view first = tokens_[1].text;
    if (iequals(first, "ok")) {
      AXON_TRY(expect_tokens(2, "R ok"));
      return Line{ReplyOk{}};
    }
    if (first == "ERR") {
      if (tokens_.size() < 3) return bad("error reply without a number (expected 'R ERR <n> <text>')");
      std::uint32_t code = 0;
      if (!parse_dec(tokens_[2].text, 9, code))
        return bad(fmt::format("error number '{}' is not a decimal number", quote(tokens_[2].text)));
      std::string text = tokens_.size() > 3 ? std::string(rest_of_line(line_, tokens_[3].offset)) : std::string();
      return Line{ReplyError{static_cast<int>(code), std::move(text)}};
    }
    if (first == "CAN" && tokens_.size() >= 3 &&
        std::all_of(tokens_[2].text.begin(), tokens_[2].text.end(), [](char c) { return c >= '0' && c <= '9'; }))
      return status_reply();
    return Line{ReplyText{std::string(rest_of_line(line_, tokens_[1].offset))}};
  }

  Result<Line> status_reply() const {
    AXON_TRY(ch, channel(2));
    AXON_TRY(expect_tokens(5, "R CAN <channel> <BEOTI flags> <free tx buffers>"));
    const std::string_view f = tokens_[3].text;
    constexpr std::string_view letters = "BEOTI";
    if (f.size() != letters.size()) return bad(fmt::format("status flags '{}' are not 5 characters", quote(f)));
    std::array<bool, 5> set{};
    for (std::size_t i = 0; i < letters.size(); ++i) {
      if (f[i] != '-' && f[i] != letters[i])
        return bad(fmt::format("status flag {} is '{}' (expected '{}' or '-')", i + 1, quote(f.substr(i, 1)), letters[i]));
      set[i] = f[i] == letters[i];
    }
    std::uint32_t free_tx = 0;
    if (!parse_dec(tokens_[4].text, 3, free_tx) || free_tx > kTxFifoCapacity)
      return bad(fmt::format("free transmit buffers '{}' is not 0..{}", quote(tokens_[4].text), kTxFifoCapacity));
    return Line{ReplyStatus{ch, StatusFlags{set[0], set[1], set[2], set[3], set[4]}, free_tx}};
  }

  Result<Line> event() const {
    AXON_TRY(ch, channel(1));
    if (tokens_.size() < 3) return bad("missing event name (BUSOFF, ERRORWARNING or TXOVERFLOW)");
    const std::string_view name = tokens_[2].text;
    if (name == "BUSOFF") {
      // The gateway's manual shows "E b BUSOFF"; gateways in service were seen to add "SET".
      if (tokens_.size() >= 4 && tokens_[3].text != "SET")
        return bad(fmt::format("BUSOFF followed by '{}' (expected nothing or SET)", quote(tokens_[3].text)));
      AXON_TRY(expect_tokens(tokens_.size() >= 4 ? 4 : 3, "E <channel> BUSOFF [SET]"));
      return Line{Event{ch, EventKind::bus_off, true, 0}};
    }
    if (name == "ERRORWARNING") {
      AXON_TRY(expect_tokens(4, "E <channel> ERRORWARNING SET|RESET"));
      const std::string_view s = tokens_[3].text;
      if (s != "SET" && s != "RESET") return bad(fmt::format("ERRORWARNING '{}' is not SET or RESET", quote(s)));
      return Line{Event{ch, EventKind::error_warning, s == "SET", 0}};
    }
    if (name == "TXOVERFLOW") {
      AXON_TRY(expect_tokens(4, "E <channel> TXOVERFLOW <frames dropped>"));
      std::uint32_t n = 0;
      if (!parse_dec(tokens_[3].text, 9, n) || n == 0)
        return bad(fmt::format("TXOVERFLOW count '{}' is not a positive number", quote(tokens_[3].text)));
      return Line{Event{ch, EventKind::tx_overflow, true, n}};
    }
    return bad(fmt::format("unknown event '{}' (expected BUSOFF, ERRORWARNING or TXOVERFLOW)", quote(name)));
  }

  std::string_view line_;
  Tokens tokens_;
};

template <class... F>
struct Overloaded : F... {
  using F::operator()...;
};
template <class... F>
Overloaded(F...) -> Overloaded<F...>;

}  // namespace

bool is_host_command(const Line& line) noexcept {
  return std::holds_alternative<CanStop>(line) || std::holds_alternative<CanStart>(line) ||
         std::holds_alternative<CanInit>(line) || std::holds_alternative<CanFilterClear>(line) ||
         std::holds_alternative<CanFilterAdd>(line) || std::holds_alternative<CanStatusRequest>(line) ||
         std::holds_alternative<DevIdentify>(line) || std::holds_alternative<DevVersion>(line);
}

bool is_reply(const Line& line) noexcept {
  return std::holds_alternative<ReplyOk>(line) || std::holds_alternative<ReplyError>(line) ||
         std::holds_alternative<ReplyStatus>(line) || std::holds_alternative<ReplyText>(line);
}

Result<Line> parse_line(std::string_view text) { return Parser(text).run(); }

std::string format_kbit(std::uint32_t bitrate) {
  const std::uint32_t hundreds = bitrate / 100;
  if (hundreds % 10 == 0) return fmt::format("{}", hundreds / 10);
  return fmt::format("{}.{}", hundreds / 10, hundreds % 10);
}

bool is_standard_bitrate(std::uint32_t bitrate) noexcept {
  return std::find(kStandardBitrates.begin(), kStandardBitrates.end(), bitrate) != kStandardBitrates.end();
}

Result<void> check_channel(int channel) {
  if (channel < kMinChannel || channel > kMaxChannel)
    return Error(CanErrc::parse_error, fmt::format("CAN@net channel {} is not {}..{}", channel, kMinChannel, kMaxChannel));
  return ok();
}

std::string_view format_frame_to(FrameLineBuffer& out, int channel, const Frame& frame) noexcept {
  constexpr char kHex[] = "0123456789ABCDEF";
  char* p = out.data();
  *p++ = 'M';
  *p++ = ' ';
  p = std::to_chars(p, p + 12, channel).ptr;  // 12 characters hold any int
  const bool ext = frame.is_extended();
  *p++ = ' ';
  *p++ = 'C';
  *p++ = ext ? 'E' : 'S';
  *p++ = frame.is_remote() ? 'R' : 'D';
  *p++ = ' ';
  for (int shift = ext ? 28 : 8; shift >= 0; shift -= 4) *p++ = kHex[(frame.id() >> shift) & 0xF];
  if (frame.is_remote()) {
    for (const char c : std::string_view(" dlc=")) *p++ = c;
    p = std::to_chars(p, p + 3, unsigned{frame.dlc()}).ptr;
  } else {
    for (const std::uint8_t b : frame.payload()) {
      *p++ = ' ';
      *p++ = kHex[b >> 4];
      *p++ = kHex[b & 0xF];
    }
  }
  return std::string_view(out.data(), static_cast<std::size_t>(p - out.data()));
}

std::string format_frame(int channel, const Frame& frame) {
  FrameLineBuffer buf;
  return std::string(format_frame_to(buf, channel, frame));
}

std::string format_line(const Line& line) {
  return std::visit(
      Overloaded{
          [](const CanStop& c) { return fmt::format("CAN {} STOP", c.channel); },
          [](const CanStart& c) { return fmt::format("CAN {} START", c.channel); },
          [](const CanInit& c) { return fmt::format("CAN {} INIT STD {}", c.channel, format_kbit(c.bitrate)); },
          [](const CanFilterClear& c) { return fmt::format("CAN {} FILTER CLEAR", c.channel); },
          [](const CanFilterAdd& c) {
            return c.format == IdFormat::extended
                       ? fmt::format("CAN {} FILTER ADD EXT {:08X} {:08X}", c.channel, c.id, c.mask)
                       : fmt::format("CAN {} FILTER ADD STD {:03X} {:03X}", c.channel, c.id, c.mask);
          },
          [](const CanStatusRequest& c) { return fmt::format("CAN {} STATUS", c.channel); },
          [](const DevIdentify&) { return std::string("DEV IDENTIFY"); },
          [](const DevVersion&) { return std::string("DEV VERSION"); },
          [](const FrameMessage& m) { return format_frame(m.channel, m.frame); },
          [](const ReplyOk&) { return std::string("R ok"); },
          [](const ReplyError& r) {
            return r.text.empty() ? fmt::format("R ERR {}", r.code) : fmt::format("R ERR {} {}", r.code, r.text);
          },
          [](const ReplyStatus& r) {
            const StatusFlags& f = r.flags;
            return fmt::format("R CAN {} {}{}{}{}{} {}", r.channel, f.bus_off ? 'B' : '-', f.error_warning ? 'E' : '-',
                               f.data_overrun ? 'O' : '-', f.tx_pending ? 'T' : '-', f.stopped ? 'I' : '-', r.free_tx);
          },
          [](const ReplyText& r) { return fmt::format("R {}", r.text); },
          [](const Event& e) {
            switch (e.kind) {
              case EventKind::bus_off: return fmt::format("E {} BUSOFF SET", e.channel);
              case EventKind::error_warning:
                return fmt::format("E {} ERRORWARNING {}", e.channel, e.set ? "SET" : "RESET");
              case EventKind::tx_overflow: return fmt::format("E {} TXOVERFLOW {}", e.channel, e.count);
            }
            return std::string();
          },
      },
      line);
}

std::optional<LineSplitter::Piece> LineSplitter::next() {
  for (;;) {
    const auto nl = buf_.find('\n', head_);
    if (skipping_) {
      if (nl == std::string::npos) {
        buf_.clear();
        head_ = 0;
        return std::nullopt;
      }
      head_ = nl + 1;
      skipping_ = false;
      continue;
    }
    if (nl == std::string::npos) {
      if (head_ > 0) {  // keep the partial line at the front
        buf_.erase(0, head_);
        head_ = 0;
      }
      if (buf_.size() > max_) {
        buf_.clear();
        skipping_ = true;
        return Piece{{}, true};
      }
      return std::nullopt;
    }
    const std::size_t len = nl - head_;
    const std::size_t start = head_;
    head_ = nl + 1;
    if (len > max_) return Piece{{}, true};
    return Piece{std::string_view(buf_).substr(start, len), false};
  }
}

}  // namespace axon::can::cannet
