// A host connection to an Ixxat CAN@net NT gateway (or to CanNetGatewayEmulator): one TCP
// connection, up to four CAN channels, each handed out as a can::Bus.
//
// connect() opens the connection and sets every requested channel up the way hosts in service do:
//   CAN b STOP, CAN b INIT STD <kbit/s>, CAN b FILTER CLEAR, CAN b FILTER ADD EXT 00000000 00000000,
//   CAN b START
// awaiting "R ok" after each. A refused command fails the connect with CanErrc::device_error and
// the gateway's text (a refused STOP is tolerated: a gateway may refuse to stop a stopped channel).
//
// One reader coroutine takes every line from the gateway: frames go to the channel's bus, events
// change the bus's state (bus_off, error_warning) or count dropped frames (tx_dropped), replies go to
// the command waiting for them. A line that does not parse, or that a gateway never sends, is
// counted in protocol_errors (the gateway's and every open bus's), logged once, and skipped; the
// connection stays up. When the connection drops, every bus closes: receive() returns the frames
// already queued, then CanErrc::closed; send() fails with CanErrc::io.
//
// Reconnection (CanNetOptions::reconnectable): a host that keeps its buses for the life of the
// program (fps::host::FocalPlaneArray) can have them survive a lost connection. They stay open
// while it is down (send() fails with CanErrc::io, receive() just waits) and carry on once
// reconnect() has opened a new connection and set every channel up again. Nothing queued before
// the loss is sent on the new connection: a command that was waiting for the wire when the link
// dropped is the caller's to repeat or not. The kind of loss (disconnect_kind()) tells a gateway
// that closed the connection in order (another client took it over: a CAN@net NT serves one at a
// time) from one that failed (reset, read or write error, keep-alive timeout: power cycled,
// cable pulled). TCP keep-alive (CanNetOptions::keepalive) finds a gateway that died silently
// while the host had nothing to send.
//
// The protocol has no request ids: replies are matched to commands by order, so commands are sent
// one at a time (concurrent callers queue). Frames need no reply and are never held back by a
// command in flight.
//
// Flow control: the gateway's transmit FIFO holds 100 frames per channel and silently drops frames
// beyond. send() cannot see that; keep what is in flight per channel bounded (replies from the
// devices pace a host naturally) or check status() for free buffers. The axon emulator reports
// drops with "E b TXOVERFLOW n", which lands in the bus's stats().tx_dropped.
//
// Threading: everything (gateway, buses, coroutines) lives on the executor given to connect().
#pragma once

#include "axon/can/bus.hpp"
#include "axon/can/cannet_codec.hpp"
#include "axon/net/endpoint.hpp"

#include <boost/asio/any_io_executor.hpp>
#include <boost/asio/awaitable.hpp>

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace axon::can {

struct CanNetOptions {
  std::uint32_t bitrate_kbit = 1000;                                           // CAN b INIT STD <kbit/s>
  core::Duration connect_timeout = std::chrono::seconds(5);                   // TCP connect (and name lookup)
  core::Duration reply_timeout = std::chrono::seconds(2);                     // per command
  BusOptions bus_options{};  // for each bus handed out; its bitrate is set from bitrate_kbit
  bool reconnectable = false;  // buses survive a lost connection until reconnect() (see above)
  // TCP keep-alive: first probe after this much silence, then one a second, 3 unanswered probes
  // end the connection (a gateway that lost power is found in about keepalive + 3 s). 0: off.
  core::Duration keepalive = std::chrono::seconds(2);
};

// How a connection ended.
enum class DisconnectKind : std::uint8_t {
  connected,          // it has not
  by_host,            // close() (or a failed set-up)
  by_gateway,         // an orderly close from the gateway: another client took it over, or it restarted
  failed,             // reset, read or write error, keep-alive timeout
};
const char* to_string(DisconnectKind k) noexcept;

// Answer to CAN b STATUS.
struct CanNetStatus {
  cannet::StatusFlags flags;
  std::uint32_t free_tx = 0;  // free transmit FIFO entries (the FIFO holds 100)
};

struct CanNetGatewayStats {
  std::uint64_t lines_in = 0;
  std::uint64_t lines_out = 0;
  std::uint64_t protocol_errors = 0;     // malformed or unexpected lines from the gateway
  std::uint64_t unrouted_frames = 0;     // frames for a channel with no open bus
  std::uint64_t commands = 0;            // commands answered (any reply)
  std::uint64_t device_errors = 0;       // R ERR replies
  std::uint64_t reconnections = 0;       // successful reconnect() calls
  std::uint64_t stale_lines_dropped = 0; // lines queued when the connection dropped, never sent
};

class CanNetGateway : public std::enable_shared_from_this<CanNetGateway> {
 public:
  // Connects to the gateway at `endpoint` (port 19228 for a real one) and sets up `channels`
  // (each 1..4, no repeats). Errors: bad_spec (channels), connect_failed, device_error (a set-up
  // command refused), timeout (no reply), protocol_error (a reply that is not "R ok"), io.
  // gcc 12 note: pass a named net::Endpoint; a braced temporary written inside the co_await
  // expression (connect(ex, net::Endpoint{"h", 1}, ...)) reaches the coroutine corrupted.
  static asio::awaitable<Result<std::shared_ptr<CanNetGateway>>> connect(asio::any_io_executor executor,
                                                                         net::Endpoint endpoint,
                                                                         std::vector<int> channels,
                                                                         CanNetOptions options = {});
  ~CanNetGateway();
  CanNetGateway(const CanNetGateway&) = delete;
  CanNetGateway& operator=(const CanNetGateway&) = delete;

  // The bus of a channel that connect() set up. One open bus per channel at a time (closing or
  // destroying it frees the channel). The bus keeps the gateway alive.
  Result<std::unique_ptr<Bus>> bus(int channel);

  // CAN b STATUS: the controller flags and free transmit buffers.
  asio::awaitable<Result<CanNetStatus>> status(int channel);
  // DEV IDENTIFY / DEV VERSION: the gateway's answer text (e.g. "CAN@net NT 420", "V1.5.0").
  asio::awaitable<Result<std::string>> identify();
  asio::awaitable<Result<std::string>> version();
  // Restarts a channel after bus-off: CAN b STOP, CAN b START; the bus is active again afterwards.
  asio::awaitable<Result<void>> restart(int channel);
  // Sends any host command and returns the gateway's reply as it came (R ERR included, as a
  // value). Errors: only transport ones (timeout, io, closed) and bad arguments.
  asio::awaitable<Result<cannet::Line>> command(const cannet::Line& line);

  // Opens a new connection to the same endpoint and sets every channel up again (with
  // CanNetOptions::reconnectable the buses already handed out carry on). `timeout` (when given)
  // replaces connect_timeout and reply_timeout for this attempt. Already connected: nothing to do.
  // Errors: closed (after close(), or a reconnect() already under way), and those of connect().
  asio::awaitable<Result<void>> reconnect(std::optional<core::Duration> timeout = std::nullopt);

  // Closes the connection; every bus closes too. Safe to call twice.
  void close();
  [[nodiscard]] bool is_connected() const noexcept;
  [[nodiscard]] DisconnectKind disconnect_kind() const noexcept;
  // Why the connection is down (meaningful once is_connected() is false): closed by the host, the
  // gateway's close (another client took the gateway over, or it restarted), a read or write error.
  [[nodiscard]] const Error& disconnect_reason() const noexcept;
  [[nodiscard]] const std::vector<int>& channels() const noexcept;
  [[nodiscard]] const net::Endpoint& endpoint() const noexcept;
  [[nodiscard]] const CanNetGatewayStats& stats() const noexcept;

  struct Impl;

 private:
  explicit CanNetGateway(std::shared_ptr<Impl> impl);
  std::shared_ptr<Impl> impl_;
};

}  // namespace axon::can
