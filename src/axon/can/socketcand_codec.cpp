#include "axon/can/socketcand_codec.hpp"
#include "axon/core/text.hpp"

#include <fmt/format.h>

#include <array>
#include <charconv>
#include <vector>

namespace axon::can::socketcand {

namespace {

constexpr std::size_t kMaxFields = 16;  // the longest message (send, 8 bytes) has 11

bool is_space(char c) noexcept { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }
bool is_printable(char c) noexcept { return c >= 0x20 && c <= 0x7E; }

bool all_hex(std::string_view s) noexcept {
  for (char c : s)
    if (core::hex_value(c) < 0) return false;
  return !s.empty();
}

bool all_decimal(std::string_view s) noexcept {
  for (char c : s)
    if (c < '0' || c > '9') return false;
  return !s.empty();
}

// Text fit for a log line: at most `limit` characters, control bytes as \xNN.
std::string excerpt(std::string_view s, std::size_t limit = 60) {
  std::string out;
  for (std::size_t i = 0; i < s.size() && i < limit; ++i) {
    const char c = s[i];
    if (is_printable(c))
      out += c;
    else
      out += fmt::format("\\x{:02X}", static_cast<unsigned char>(c));
  }
  if (s.size() > limit) out += "...";
  return out;
}

template <class T>
bool parse_unsigned(std::string_view s, T& out, int base) noexcept {
  if (s.empty()) return false;
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), out, base);
  return ec == std::errc() && p == s.data() + s.size();
}

struct Fields {
  std::array<std::string_view, kMaxFields> v{};
  std::size_t n = 0;
  [[nodiscard]] std::size_t args() const noexcept { return n - 1; }  // fields after the keyword
};

void append_hex_byte(std::string& out, std::uint8_t b) {
  static constexpr char kDigits[] = "0123456789ABCDEF";
  out += kDigits[b >> 4];
  out += kDigits[b & 0xF];
}

}  // namespace

// ---------------------------------------------------------------------------------------- ids, time

Result<Id> parse_id(std::string_view hex) {
  if (hex.empty() || hex.size() > 8 || !all_hex(hex))
    return Error(CanErrc::parse_error, fmt::format("id '{}': expected 1 to 8 hex digits", excerpt(hex)));
  std::uint32_t v = 0;
  parse_unsigned(hex, v, 16);
  if (v > Frame::kMaxExtendedId)
    return Error(CanErrc::parse_error, fmt::format("id '{}' is wider than 29 bits", hex));
  const bool extended = hex.size() == 8 || v > Frame::kMaxStandardId;
  return Id{v, extended ? IdFormat::extended : IdFormat::standard};
}

void append_id(std::string& out, std::uint32_t id, IdFormat fmt) {
  if (fmt == IdFormat::extended)
    fmt::format_to(std::back_inserter(out), "{:08X}", id);
  else
    fmt::format_to(std::back_inserter(out), "{:03X}", id);
}

Result<core::WallTime> parse_timestamp(std::string_view text) {
  auto bad = [&](std::string_view why) {
    return Error(CanErrc::parse_error, fmt::format("timestamp '{}': {} (expected SECONDS.MICROSECONDS)", excerpt(text), why));
  };
  const auto dot = text.find('.');
  const std::string_view sec_text = text.substr(0, dot);
  const std::string_view frac = dot == std::string_view::npos ? std::string_view{} : text.substr(dot + 1);
  if (!all_decimal(sec_text)) return bad("seconds are not decimal digits");
  // Nanoseconds since 1970 in 64 bits reach the year 2262; accept up to 2255.
  constexpr std::int64_t kMaxSeconds = 9'000'000'000;
  if (sec_text.size() > 10) return bad("seconds out of range");
  if (dot != std::string_view::npos && (frac.empty() || frac.size() > 9 || !all_decimal(frac)))
    return bad("fraction must be 1 to 9 decimal digits");
  std::int64_t sec = 0;
  parse_unsigned(sec_text, sec, 10);
  if (sec > kMaxSeconds) return bad("seconds out of range");
  std::int64_t usec = 0;
  for (std::size_t i = 0; i < 6; ++i) usec = usec * 10 + (i < frac.size() ? frac[i] - '0' : 0);
  return core::WallTime(sec * 1'000'000'000LL + usec * 1'000LL);
}

void append_timestamp(std::string& out, core::WallTime t) {
  const std::int64_t us = t.count() < 0 ? 0 : t.count() / 1'000;
  fmt::format_to(std::back_inserter(out), "{}.{:06}", us / 1'000'000, us % 1'000'000);
}

// ------------------------------------------------------------------------------------------- parse

namespace {

// Errors carry only the reason; parse() adds the message itself.
Result<Message> parse_fields(const Fields& f) {
  const std::string_view kw = f.v[0];
  auto bad = [&](std::string_view why) { return Error(CanErrc::parse_error, std::string(why)); };
  auto no_args = [&](Message m) -> Result<Message> {
    if (f.args() != 0) return bad(fmt::format("'{}' takes no arguments", kw));
    return m;
  };
  auto id_field = [&](std::string_view s) -> Result<Id> {
    auto id = parse_id(s);
    if (!id) return id.error();
    return id.value();
  };
  auto time_field = [&](std::string_view s) -> Result<core::WallTime> {
    auto t = parse_timestamp(s);
    if (!t) return t.error();
    return t.value();
  };
  // A length/DLC field: one or two hex digits, value 0..8 (decimal and hex agree there).
  auto length_field = [&](std::string_view s) -> Result<std::uint8_t> {
    unsigned v = 0;
    if (s.size() > 2 || !all_hex(s) || !parse_unsigned(s, v, 16) || v > Frame::kMaxData)
      return bad(fmt::format("length '{}' must be 0..8", excerpt(s)));
    return static_cast<std::uint8_t>(v);
  };

  if (kw == "hi") return no_args(Hi{});
  if (kw == "ok") return no_args(Ok{});
  if (kw == "echo") return no_args(Echo{});
  if (kw == "rawmode") return no_args(Mode{Mode::Kind::raw});
  if (kw == "bcmmode") return no_args(Mode{Mode::Kind::bcm});
  if (kw == "controlmode") return no_args(Mode{Mode::Kind::control});
  if (kw == "isotpmode") return no_args(Mode{Mode::Kind::isotp});

  if (kw == "error") {
    if (f.args() == 2 && f.v[1].size() <= 8 && all_hex(f.v[1])) {
      if (auto t = parse_timestamp(f.v[2])) {
        std::uint32_t cls = 0;
        parse_unsigned(f.v[1], cls, 16);
        return ErrorFrame{cls, t.value()};
      }
    }
    ErrorText e;
    for (std::size_t i = 1; i < f.n; ++i) {
      if (i > 1) e.text += ' ';
      e.text += f.v[i];
    }
    return e;
  }

  if (kw == "open") {
    if (f.args() != 1) return bad("expected '< open CHANNEL >'");
    if (f.v[1].size() > kMaxChannelName) return bad(fmt::format("channel name longer than {} characters", kMaxChannelName));
    return Open{std::string(f.v[1])};
  }

  if (kw == "send") {
    if (f.args() < 2) return bad("expected '< send ID LEN B0 B1 ... >'");
    AXON_TRY(id, id_field(f.v[1]));
    AXON_TRY(len, length_field(f.v[2]));
    if (f.args() != 2u + len)
      return bad(fmt::format("length {} but {} data bytes", len, f.args() - 2));
    std::array<std::uint8_t, Frame::kMaxData> bytes{};
    for (std::size_t i = 0; i < len; ++i) {
      const std::string_view b = f.v[3 + i];
      unsigned v = 0;
      if (b.size() > 2 || !all_hex(b) || !parse_unsigned(b, v, 16))
        return bad(fmt::format("data byte '{}' is not one or two hex digits", excerpt(b)));
      bytes[i] = static_cast<std::uint8_t>(v);
    }
    auto frame = Frame::data(id.value, id.format, std::span<const std::uint8_t>(bytes.data(), len));
    if (!frame) return bad(frame.error().detail);
    return Send{frame.value()};
  }

  if (kw == "sendrtr") {
    if (f.args() != 2) return bad("expected '< sendrtr ID DLC >'");
    AXON_TRY(id, id_field(f.v[1]));
    AXON_TRY(dlc, length_field(f.v[2]));
    auto frame = Frame::remote(id.value, id.format, dlc);
    if (!frame) return bad(frame.error().detail);
    return Send{frame.value()};
  }

  if (kw == "frame") {
    if (f.args() < 2) return bad("expected '< frame ID SECONDS.MICROSECONDS HEXDATA >'");
    AXON_TRY(id, id_field(f.v[1]));
    AXON_TRY(ts, time_field(f.v[2]));
    // The daemon writes the data as one hex string; its documentation shows one field per byte.
    // Both are accepted: every field must hold whole bytes.
    std::array<std::uint8_t, Frame::kMaxData> bytes{};
    std::size_t n = 0;
    for (std::size_t i = 3; i < f.n; ++i) {
      const std::string_view d = f.v[i];
      if (!all_hex(d) || d.size() % 2 != 0) return bad(fmt::format("data '{}' is not whole hex bytes", excerpt(d)));
      for (std::size_t k = 0; k < d.size(); k += 2) {
        if (n == Frame::kMaxData) return bad("more than 8 data bytes");
        bytes[n++] = static_cast<std::uint8_t>(core::hex_value(d[k]) << 4 | core::hex_value(d[k + 1]));
      }
    }
    auto frame = Frame::data(id.value, id.format, std::span<const std::uint8_t>(bytes.data(), n));
    if (!frame) return bad(frame.error().detail);
    Frame out = frame.value();
    out.set_timestamp(ts);
    return FrameMessage{out};
  }

  if (kw == "rtr") {
    if (f.args() != 3) return bad("expected '< rtr ID SECONDS.MICROSECONDS DLC >'");
    AXON_TRY(id, id_field(f.v[1]));
    AXON_TRY(ts, time_field(f.v[2]));
    AXON_TRY(dlc, length_field(f.v[3]));
    auto frame = Frame::remote(id.value, id.format, dlc);
    if (!frame) return bad(frame.error().detail);
    Frame out = frame.value();
    out.set_timestamp(ts);
    return FrameMessage{out};
  }

  if (kw == "statistics") {
    std::uint32_t ms = 0;
    if (f.args() != 1 || !all_decimal(f.v[1]) || !parse_unsigned(f.v[1], ms, 10))
      return bad("expected '< statistics MILLISECONDS >'");
    return Statistics{ms};
  }

  if (kw == "stat") {
    Stat s;
    std::uint64_t* slots[] = {&s.rx_bytes, &s.rx_frames, &s.tx_bytes, &s.tx_frames};
    if (f.args() != 4) return bad("expected '< stat RBYTES RPACKETS TBYTES TPACKETS >'");
    for (std::size_t i = 0; i < 4; ++i)
      if (!all_decimal(f.v[1 + i]) || !parse_unsigned(f.v[1 + i], *slots[i], 10))
        return bad(fmt::format("statistic '{}' is not a decimal count", excerpt(f.v[1 + i])));
    return s;
  }

  if (kw == "fdframe" || kw == "fdsend") return bad("CAN FD frames are not supported");
  if (kw == "add" || kw == "update" || kw == "delete" || kw == "filter" || kw == "muxfilter" || kw == "subscribe" ||
      kw == "unsubscribe" || kw == "isotpconf" || kw == "sendpdu")
    return bad(fmt::format("'{}' (broadcast manager / ISO-TP) is not supported", kw));
  return bad(fmt::format("unknown command '{}'", excerpt(kw, 20)));
}

}  // namespace

Result<Message> parse_terse(std::string_view text) {
  auto bad = [&](std::string_view why) { return Error(CanErrc::parse_error, std::string(why)); };
  if (text.size() < 2 || text.front() != '<' || text.back() != '>') return bad("not enclosed in '<' '>'");
  if (text.size() > kMaxMessageLength) return bad(fmt::format("longer than {} characters", kMaxMessageLength));
  const std::string_view inner = text.substr(1, text.size() - 2);
  Fields f;
  std::size_t i = 0;
  while (i < inner.size()) {
    const char c = inner[i];
    if (c == ' ' || c == '\t') {
      ++i;
      continue;
    }
    if (!is_printable(c) || c == '<' || c == '>')
      return bad(fmt::format("byte 0x{:02X} is not allowed inside a message", static_cast<unsigned char>(c)));
    const std::size_t start = i;
    while (i < inner.size() && is_printable(inner[i]) && inner[i] != ' ' && inner[i] != '<' && inner[i] != '>') ++i;
    if (f.n == kMaxFields) return bad(fmt::format("more than {} fields", kMaxFields));
    f.v[f.n++] = inner.substr(start, i - start);
  }
  if (f.n == 0) return bad("empty message");
  return parse_fields(f);
}

Result<Message> parse(std::string_view text) {
  auto r = parse_terse(text);
  if (!r) return Error(CanErrc::parse_error, fmt::format("socketcand message '{}': {}", excerpt(text), r.error().detail));
  return r;
}

// ------------------------------------------------------------------------------------------ format

namespace {

struct Appender {
  std::string& out;

  void operator()(const Hi&) const { out += "< hi >"; }
  void operator()(const Ok&) const { out += "< ok >"; }
  void operator()(const Echo&) const { out += "< echo >"; }
  void operator()(const ErrorText& e) const {
    out += "< error ";
    // Keep the stream parseable whatever the text holds: no '<', '>' or control bytes.
    for (char c : e.text) out += (is_printable(c) && c != '<' && c != '>') ? c : '?';
    if (!e.text.empty()) out += ' ';
    out += '>';
  }
  void operator()(const ErrorFrame& e) const {
    fmt::format_to(std::back_inserter(out), "< error {:03X} ", e.error_class);
    append_timestamp(out, e.timestamp);
    out += " >";
  }
  void operator()(const Open& o) const {
    out += "< open ";
    out += o.channel;
    out += " >";
  }
  void operator()(const Mode& m) const {
    switch (m.kind) {
      case Mode::Kind::raw: out += "< rawmode >"; return;
      case Mode::Kind::bcm: out += "< bcmmode >"; return;
      case Mode::Kind::control: out += "< controlmode >"; return;
      case Mode::Kind::isotp: out += "< isotpmode >"; return;
    }
  }
  void operator()(const Send& s) const {
    const Frame& f = s.frame;
    out += f.is_remote() ? "< sendrtr " : "< send ";
    append_id(out, f.id(), f.format());
    out += ' ';
    out += static_cast<char>('0' + f.dlc());
    for (std::uint8_t b : f.payload()) {
      out += ' ';
      append_hex_byte(out, b);
    }
    out += " >";
  }
  void operator()(const FrameMessage& m) const {
    const Frame& f = m.frame;
    out += f.is_remote() ? "< rtr " : "< frame ";
    append_id(out, f.id(), f.format());
    out += ' ';
    append_timestamp(out, f.timestamp());
    out += ' ';
    if (f.is_remote()) {
      out += static_cast<char>('0' + f.dlc());
    } else {
      for (std::uint8_t b : f.payload()) append_hex_byte(out, b);
    }
    out += " >";
  }
  void operator()(const Statistics& s) const { fmt::format_to(std::back_inserter(out), "< statistics {} >", s.interval_ms); }
  void operator()(const Stat& s) const {
    fmt::format_to(std::back_inserter(out), "< stat {} {} {} {} >", s.rx_bytes, s.rx_frames, s.tx_bytes, s.tx_frames);
  }
};

struct Keyword {
  const char* operator()(const Hi&) const noexcept { return "hi"; }
  const char* operator()(const Ok&) const noexcept { return "ok"; }
  const char* operator()(const Echo&) const noexcept { return "echo"; }
  const char* operator()(const ErrorText&) const noexcept { return "error"; }
  const char* operator()(const ErrorFrame&) const noexcept { return "error"; }
  const char* operator()(const Open&) const noexcept { return "open"; }
  const char* operator()(const Mode& m) const noexcept {
    switch (m.kind) {
      case Mode::Kind::raw: return "rawmode";
      case Mode::Kind::bcm: return "bcmmode";
      case Mode::Kind::control: return "controlmode";
      case Mode::Kind::isotp: return "isotpmode";
    }
    return "mode";
  }
  const char* operator()(const Send& s) const noexcept { return s.frame.is_remote() ? "sendrtr" : "send"; }
  const char* operator()(const FrameMessage& m) const noexcept { return m.frame.is_remote() ? "rtr" : "frame"; }
  const char* operator()(const Statistics&) const noexcept { return "statistics"; }
  const char* operator()(const Stat&) const noexcept { return "stat"; }
};

}  // namespace

void append(std::string& out, const Message& m) { std::visit(Appender{out}, m); }

std::string format(const Message& m) {
  std::string out;
  append(out, m);
  return out;
}

const char* keyword(const Message& m) noexcept { return std::visit(Keyword{}, m); }

// --------------------------------------------------------------------------------------- tokenizer

Tokenizer::Tokenizer(std::size_t max_length) : max_length_(max_length < 2 ? 2 : max_length) {}

void Tokenizer::feed(std::string_view bytes) {
  compact();
  buf_.append(bytes);
}

void Tokenizer::compact() {
  if (pos_ == 0) return;
  if (pos_ < 4096 && pos_ * 2 < buf_.size()) return;
  buf_.erase(0, pos_);
  scan_ = scan_ > pos_ ? scan_ - pos_ : 0;
  pos_ = 0;
}

Error Tokenizer::framing_error(std::string_view what, std::string_view sample) {
  ++stats_.errors;
  return Error(CanErrc::parse_error, fmt::format("socketcand stream: {}: {}", what, excerpt(sample)));
}

Error Tokenizer::garbage_error(std::string_view what) {
  Error e = framing_error(what, garbage_sample_);
  garbage_ = 0;
  garbage_sample_.clear();
  return e;
}

std::optional<Result<std::string>> Tokenizer::next() {
  for (;;) {
    switch (state_) {
      case State::between: {
        // Skip separators; collect a garbage run until the next '<'.
        while (pos_ < buf_.size() && buf_[pos_] != '<') {
          const char c = buf_[pos_++];
          if (is_space(c)) continue;
          ++garbage_;
          ++stats_.garbage_bytes;
          if (garbage_sample_.size() < 40) garbage_sample_ += c;
          if (garbage_ >= max_length_) return garbage_error("garbage between messages");
        }
        if (pos_ == buf_.size()) return std::nullopt;
        if (garbage_ > 0) return garbage_error(fmt::format("{} garbage byte(s) between messages", garbage_));
        state_ = State::inside;
        scan_ = pos_ + 1;
        break;
      }
      case State::inside: {
        const std::size_t limit = pos_ + max_length_;  // index of the last byte a message may use, plus one
        while (scan_ < buf_.size() && scan_ < limit) {
          const char c = buf_[scan_];
          if (c == '>') {
            std::string msg = buf_.substr(pos_, scan_ + 1 - pos_);
            pos_ = scan_ + 1;
            state_ = State::between;
            ++stats_.messages;
            return Result<std::string>(std::move(msg));
          }
          if (c == '<') {
            ++stats_.unterminated;
            const std::size_t from = pos_;
            pos_ = scan_;
            scan_ = pos_ + 1;
            return framing_error("message cut short by the start of another",
                                 std::string_view(buf_).substr(from, pos_ - from));
          }
          ++scan_;
        }
        if (scan_ >= limit) {
          ++stats_.overlong;
          const std::size_t from = pos_;
          pos_ = scan_;
          state_ = State::skipping;
          return framing_error(fmt::format("message longer than {} bytes", max_length_),
                               std::string_view(buf_).substr(from, pos_ - from));
        }
        return std::nullopt;
      }
      case State::skipping: {
        while (pos_ < buf_.size() && buf_[pos_] != '>' && buf_[pos_] != '<') ++pos_;
        if (pos_ == buf_.size()) return std::nullopt;
        if (buf_[pos_] == '>') ++pos_;
        state_ = State::between;
        break;
      }
    }
  }
}

}  // namespace axon::can::socketcand
