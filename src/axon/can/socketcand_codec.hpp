// The socketcand text protocol (linux-can/socketcand), pure: no I/O.
//
// Every message is ASCII text between '<' and '>' with space-separated fields, and nothing marks
// the end of a message but its '>'. The daemon greets with `< hi >`; the client opens a channel
// (`< open can0 >`, answer `< ok >` or `< error ... >`), switches to raw mode (`< rawmode >`,
// `< ok >`), and from then on the server reports every bus frame as `< frame ID SEC.USEC HEX >`
// while the client transmits with `< send ID LEN B0 B1 ... >`.
//
// Identifiers: the daemon writes 3 hex digits for a standard id and 8 for an extended one. Some
// clients (python-can 4.1) write ids without padding, so when parsing an id of fewer than 8 digits
// the value decides: up to 0x7FF is standard, above is extended. Exactly 8 digits is always
// extended (that is how an extended id <= 0x7FF is written).
//
// Tokenizer turns a byte stream (TCP reads cut anywhere) into complete messages; parse() turns
// one message into a typed Message; format()/append() produce the exact text of a Message.
#pragma once

#include "axon/can/frame.hpp"
#include "axon/core/clock.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <variant>

namespace axon::can::socketcand {

// Longest message accepted, '<' and '>' included. The longest regular message (an 8-byte frame)
// is under 60 characters; error texts and channel names stay far below this.
inline constexpr std::size_t kMaxMessageLength = 512;
// Longest channel name in `< open NAME >`.
inline constexpr std::size_t kMaxChannelName = 64;

// `< hi >`: the server's greeting.
struct Hi {
  friend bool operator==(const Hi&, const Hi&) = default;
};
// `< ok >`: a command succeeded.
struct Ok {
  friend bool operator==(const Ok&, const Ok&) = default;
};
// `< error TEXT >`: the server refused a command (text normalised: single spaces, printable).
struct ErrorText {
  std::string text;
  friend bool operator==(const ErrorText&, const ErrorText&) = default;
};
// `< error CLASS SEC.USEC >`: an error frame seen on the bus in raw mode (CLASS in hex, the
// SocketCAN error class bits).
struct ErrorFrame {
  std::uint32_t error_class = 0;
  core::WallTime timestamp{0};  // microsecond resolution
  friend bool operator==(const ErrorFrame&, const ErrorFrame&) = default;
};
// `< open NAME >`: select the bus to work on.
struct Open {
  std::string channel;
  friend bool operator==(const Open&, const Open&) = default;
};
// `< rawmode >`, `< bcmmode >`, `< controlmode >`, `< isotpmode >`: switch mode.
struct Mode {
  enum class Kind : std::uint8_t { raw, bcm, control, isotp };
  Kind kind = Kind::raw;
  friend bool operator==(const Mode&, const Mode&) = default;
};
// `< echo >`: answered with the same message (liveness check).
struct Echo {
  friend bool operator==(const Echo&, const Echo&) = default;
};
// `< send ID LEN B0 ... >` or, for a remote frame, `< sendrtr ID DLC >`: client transmits a frame.
struct Send {
  Frame frame;
  friend bool operator==(const Send& a, const Send& b) noexcept { return a.frame == b.frame; }
};
// `< frame ID SEC.USEC HEX >` or, for a remote frame, `< rtr ID SEC.USEC DLC >`: a frame seen on
// the bus; the timestamp (microsecond resolution) is the frame's timestamp.
struct FrameMessage {
  Frame frame;
  friend bool operator==(const FrameMessage& a, const FrameMessage& b) noexcept {
    return a.frame == b.frame && a.frame.timestamp() == b.frame.timestamp();
  }
};
// `< statistics MS >`: report statistics every MS milliseconds (0 stops them).
struct Statistics {
  std::uint32_t interval_ms = 0;
  friend bool operator==(const Statistics&, const Statistics&) = default;
};
// `< stat RBYTES RPACKETS TBYTES TPACKETS >`: statistics report (payload bytes and frames).
struct Stat {
  std::uint64_t rx_bytes = 0, rx_frames = 0, tx_bytes = 0, tx_frames = 0;
  friend bool operator==(const Stat&, const Stat&) = default;
};

using Message =
    std::variant<Hi, Ok, ErrorText, ErrorFrame, Open, Mode, Echo, Send, FrameMessage, Statistics, Stat>;

// Parses one complete message, '<' and '>' included (what Tokenizer::next() yields).
// Errors: CanErrc::parse_error with the message text and what is wrong with it.
Result<Message> parse(std::string_view text);
// The same, but the error detail is only the reason ("length 2 but 1 data bytes"), without the
// message quoted: what a server puts in its `< error ... >` answer.
Result<Message> parse_terse(std::string_view text);

// The exact text of a message. Empty frame data is written as two spaces ("< frame 123 1.000000  >"),
// as the daemon does and as python-can's parser needs.
std::string format(const Message& m);
// Appends the text to `out` (no allocation beyond out's growth).
void append(std::string& out, const Message& m);

// The message's keyword ("frame", "send", "error", ...), for logs.
const char* keyword(const Message& m) noexcept;

// Ids as the protocol writes them (see the header comment for the digit-count rule).
struct Id {
  std::uint32_t value = 0;
  IdFormat format = IdFormat::standard;
  friend bool operator==(const Id&, const Id&) = default;
};
Result<Id> parse_id(std::string_view hex);
void append_id(std::string& out, std::uint32_t id, IdFormat fmt);

// "SEC.USEC" with 0..9 fractional digits (truncated to microseconds) -> wall time.
Result<core::WallTime> parse_timestamp(std::string_view text);
// Wall time -> "SEC.USEC" with exactly six fractional digits (negative times as 0.000000).
void append_timestamp(std::string& out, core::WallTime t);

// Cuts a byte stream into messages. Feed it whatever the socket returned; then call next() until it
// returns nullopt. Whitespace between messages is allowed and skipped. Anything else between
// messages is garbage: it is skipped and reported as one error per run. A message that reaches
// `max_length` without '>' is an error and is skipped up to its '>' (or the next '<'); a '<' inside
// a message ends the unterminated message with an error and starts a new one.
class Tokenizer {
 public:
  struct Stats {
    std::uint64_t messages = 0;       // complete messages returned
    std::uint64_t errors = 0;         // errors returned (all kinds below)
    std::uint64_t garbage_bytes = 0;  // non-whitespace bytes outside messages
    std::uint64_t overlong = 0;       // messages longer than max_length
    std::uint64_t unterminated = 0;   // messages cut by a '<' before their '>'
  };

  explicit Tokenizer(std::size_t max_length = kMaxMessageLength);

  void feed(std::string_view bytes);
  // The next complete message ("< ... >"), a framing error (CanErrc::parse_error), or nullopt when
  // more bytes are needed.
  std::optional<Result<std::string>> next();

  // Bytes held that are not yet part of a returned message or error.
  [[nodiscard]] std::size_t buffered() const noexcept { return buf_.size() - pos_; }
  [[nodiscard]] const Stats& stats() const noexcept { return stats_; }
  [[nodiscard]] std::size_t max_length() const noexcept { return max_length_; }

 private:
  enum class State : std::uint8_t { between, inside, skipping };
  Error framing_error(std::string_view what, std::string_view sample);
  Error garbage_error(std::string_view what);
  void compact();

  std::string buf_;
  std::size_t pos_ = 0;    // first byte not yet consumed (the '<' while inside a message)
  std::size_t scan_ = 0;   // where the search for '>' resumes while inside a message
  std::size_t garbage_ = 0;      // garbage bytes in the current run, not yet reported
  std::string garbage_sample_;   // the run's first bytes, for the error message
  std::size_t max_length_;
  State state_ = State::between;
  Stats stats_;
};

}  // namespace axon::can::socketcand
