// The CAN@net NT ASCII protocol as typed values: every line a host sends to an Ixxat CAN@net NT
// gateway and every line the gateway sends back, parsed from text and formatted to text.
// Pure: no I/O, no clocks. docs/can-cannet.md describes the protocol in full.
//
// A line is tokens separated by spaces (runs of spaces or tabs are accepted), ended by '\n'; a '\r'
// before it is accepted and dropped. Other control characters and non-ASCII bytes are errors.
// Channels (the gateway calls them ports) are 1..4. Numbers are hexadecimal for ids, masks and
// data bytes, decimal elsewhere. Keywords are upper case, as the gateway writes them; the one
// exception is the positive reply, which the gateway writes "R ok" and which is accepted in any case.
//
//   host -> gateway                               gateway -> host
//   CAN b STOP | START                            R ok
//   CAN b INIT STD <kbit/s>   (e.g. 1000, 83.3)   R ERR <n> <text>
//   CAN b FILTER CLEAR                            R CAN b <BEOTI flags> <free tx buffers>
//   CAN b FILTER ADD EXT|STD <id> <mask>          R <text>   (DEV IDENTIFY / DEV VERSION answers)
//   CAN b STATUS                                  E b BUSOFF [SET]
//   DEV IDENTIFY | DEV VERSION                    E b ERRORWARNING SET|RESET
//                                                 E b TXOVERFLOW <n>   (axon emulator extension)
//   both ways: M b CED|CSD <id> [<byte> ...]   data frame, extended (8 hex digits) or standard (3)
//              M b CER|CSR <id> [dlc=<n>]       remote frame; its length travels as dlc=n (0..8)
#pragma once

#include "axon/can/frame.hpp"

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <variant>

namespace axon::can::cannet {

inline constexpr std::uint16_t kDefaultPort = 19228;
inline constexpr int kMinChannel = 1;
inline constexpr int kMaxChannel = 4;
// Frames the gateway's transmit FIFO holds per channel; frames beyond are dropped.
inline constexpr std::uint32_t kTxFifoCapacity = 100;
// Longest line either side needs (a full extended data frame is 38 characters); longer input is
// a protocol error.
inline constexpr std::size_t kMaxLineLength = 256;

// ---- host -> gateway -------------------------------------------------------------------------

struct CanStop {
  int channel = 1;
  bool operator==(const CanStop&) const = default;
};
struct CanStart {
  int channel = 1;
  bool operator==(const CanStart&) const = default;
};
// CAN b INIT STD <kbit/s>. The rate travels in kbit/s with at most one decimal ("83.3", "62.5"),
// so `bitrate` (bit/s) is a multiple of 100. Whether the gateway supports the rate is its call
// (it answers R ERR otherwise); see is_standard_bitrate().
struct CanInit {
  int channel = 1;
  std::uint32_t bitrate = 1'000'000;
  bool operator==(const CanInit&) const = default;
};
struct CanFilterClear {
  int channel = 1;
  bool operator==(const CanFilterClear&) const = default;
};
// CAN b FILTER ADD EXT|STD <id> <mask>: frames of that format pass when (id ^ frame id) & mask == 0.
struct CanFilterAdd {
  int channel = 1;
  IdFormat format = IdFormat::extended;
  std::uint32_t id = 0;
  std::uint32_t mask = 0;
  bool operator==(const CanFilterAdd&) const = default;
};
struct CanStatusRequest {
  int channel = 1;
  bool operator==(const CanStatusRequest&) const = default;
};
struct DevIdentify {
  bool operator==(const DevIdentify&) const = default;
};
struct DevVersion {
  bool operator==(const DevVersion&) const = default;
};

// ---- both directions -------------------------------------------------------------------------

// M b <format> <id> ...: a frame the host wants sent, or one the gateway received.
struct FrameMessage {
  int channel = 1;
  Frame frame;
  bool operator==(const FrameMessage&) const = default;
};

// ---- gateway -> host -------------------------------------------------------------------------

struct ReplyOk {
  bool operator==(const ReplyOk&) const = default;
};
// R ERR <n> <text>: the command before it failed.
struct ReplyError {
  int code = 0;
  std::string text;
  bool operator==(const ReplyError&) const = default;
};
// The five characters of a status reply, in order B E O T I; a set flag shows its letter, a clear
// one '-'.
struct StatusFlags {
  bool bus_off = false;        // B
  bool error_warning = false;  // E
  bool data_overrun = false;   // O: the gateway lost received frames
  bool tx_pending = false;     // T: frames wait in the transmit FIFO
  bool stopped = false;        // I: the controller is in init (stopped) state, else running
  bool operator==(const StatusFlags&) const = default;
};
// R CAN b <flags> <free>: answer to CAN b STATUS.
struct ReplyStatus {
  int channel = 1;
  StatusFlags flags;
  std::uint32_t free_tx = kTxFifoCapacity;  // free transmit FIFO entries, 0..kTxFifoCapacity
  bool operator==(const ReplyStatus&) const = default;
};
// R <text>: any other answer, e.g. "CAN@net NT 420" to DEV IDENTIFY or "V1.5.0" to DEV VERSION.
// The text never reads like one of the replies above (parse_line would have taken it as that).
struct ReplyText {
  std::string text;
  bool operator==(const ReplyText&) const = default;
};

enum class EventKind : std::uint8_t {
  bus_off,        // E b BUSOFF [SET]; always "set" (the controller leaves bus-off only by restart)
  error_warning,  // E b ERRORWARNING SET|RESET
  tx_overflow,    // E b TXOVERFLOW <n>: n frames dropped because the transmit FIFO was full.
                  // Not sent by a real gateway (which drops silently); the axon emulator's report.
};
struct Event {
  int channel = 1;
  EventKind kind = EventKind::bus_off;
  bool set = true;          // error_warning: SET (true) or RESET (false); true for the others
  std::uint32_t count = 0;  // tx_overflow: frames dropped (>= 1); 0 for the others
  bool operator==(const Event&) const = default;
};

using Line = std::variant<CanStop, CanStart, CanInit, CanFilterClear, CanFilterAdd, CanStatusRequest, DevIdentify,
                          DevVersion, FrameMessage, ReplyOk, ReplyError, ReplyStatus, ReplyText, Event>;

// True for the lines a host sends (commands); frames go both ways and count as neither.
bool is_host_command(const Line& line) noexcept;
// True for the R ... lines.
bool is_reply(const Line& line) noexcept;

// Parses one line, with or without its '\n' / "\r\n" ending. Errors: CanErrc::parse_error with a
// message that quotes the line and names the field that is wrong.
Result<Line> parse_line(std::string_view text);

// The exact text of the line, without the '\n' (the caller adds it). Data bytes and ids are upper
// case hex, extended ids 8 digits, standard ids 3, data bytes 2. The values are assumed valid
// (channel 1..4, bitrate a multiple of 100, ...); parse_line() only ever produces valid ones.
std::string format_line(const Line& line);

// format_line(FrameMessage{channel, frame}) without building the variant.
std::string format_frame(int channel, const Frame& frame);
// The same text written into a caller's buffer, without allocating (the per-frame path of the
// client and the emulator); the view points into `out`. Any int channel fits.
using FrameLineBuffer = std::array<char, 64>;
std::string_view format_frame_to(FrameLineBuffer& out, int channel, const Frame& frame) noexcept;

// "1000", "83.3" for 1'000'000 and 83'300 bit/s.
std::string format_kbit(std::uint32_t bitrate);
// The rates the CAN@net NT offers for INIT STD, in bit/s: 5, 10, 20, 50, 62.5, 83.3, 100, 125,
// 250, 500, 800 and 1000 kbit/s.
bool is_standard_bitrate(std::uint32_t bitrate) noexcept;

// Checks 1..4; CanErrc::parse_error otherwise.
Result<void> check_channel(int channel);

// Cuts a byte stream into lines at '\n'. A line longer than max_length is not kept: it comes out
// once as an overlong piece (its text empty) and the rest of it up to the next '\n' is skipped.
class LineSplitter {
 public:
  struct Piece {
    // Without the '\n' (a '\r' before it is left for parse_line). Points into the splitter's
    // buffer: valid until the next call to next() or append().
    std::string_view text;
    bool overlong = false;
  };
  explicit LineSplitter(std::size_t max_length = kMaxLineLength + 1) : max_(max_length) {}
  void append(std::string_view bytes) { buf_.append(bytes); }
  // The next complete line, or nothing until more bytes arrive.
  std::optional<Piece> next();
  // Bytes held that do not yet form a line.
  [[nodiscard]] std::size_t buffered() const noexcept { return buf_.size() - head_; }

 private:
  std::string buf_;
  std::size_t head_ = 0;  // start of the unread part of buf_
  bool skipping_ = false;  // inside an overlong line
  std::size_t max_;
};

}  // namespace axon::can::cannet
