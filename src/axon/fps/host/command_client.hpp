// CommandClient: requests and replies with the positioners on one CAN bus.
//
// One client per bus. It runs one reader coroutine on the bus's executor that takes every frame
// off the bus and hands it to whoever waits for it:
//   - a unicast reply (uid 1..63) to the request with the same (positioner, command, uid);
//   - a reply with uid 0 to the broadcast of that command being collected, if any;
//   - everything else with uid 0 (collision reports, starts triggered by the sync line) to the
//     subscribers, as Unsolicited events;
//   - a reply nobody waits for is counted (late when its request had timed out, unmatched
//     otherwise) and dropped.
//
// Requests take a uid from the pool of their (positioner, command) pair (uid_pool.hpp); when all 63
// are in flight the request waits for one to come back rather than fail. The client also bounds the
// unicast requests in flight on its bus (ClientOptions::max_in_flight): a CAN@net gateway drops
// frames beyond its 100-frame transmit FIFO. Each request has a timeout; only reads (the command
// table's `read_only` commands) are retried after a timeout. A reply with a non-zero response code
// comes back as an Error whose code is the protocol's ResponseCode, so its message names the code
// and carries the interface document's advice.
//
// Safety: this client is where the collision lock is enforced (motion_lock.hpp). Every frame it
// sends, and every broadcast trigger (the sync line), first passes the lock it was given: while
// that lock is held, a command the table marks `moves` is refused with HostErrc::locked, nothing
// goes on the bus and ClientCounters::refused counts it. Reads, settings and stops always go out.
// An Array gives the clients of all its buses its one lock, so whoever holds one of them
// (Array::client(bus), a Positioner, a pipeline of trajectory points) cannot move a robot of a
// locked array. A client made without a lock refuses nothing. Frames written to the can::Bus
// directly bypass it.
//
// Threading: everything runs on the bus's executor (single-threaded). Lifetime: call `co_await
// stop()` before destroying the client, and keep the bus alive until the reader has stopped (stop()
// waits for it; destroying the io_context also ends it).
#pragma once

#include "axon/can/bus.hpp"
#include "axon/core/clock.hpp"
#include "axon/core/error.hpp"
#include "axon/fps/host/error.hpp"
#include "axon/fps/host/motion_lock.hpp"
#include "axon/fps/protocol/commands.hpp"
#include "axon/fps/protocol/message.hpp"
#include "axon/fps/protocol/payload.hpp"
#include "axon/fps/protocol/payloads.hpp"
#include "axon/fps/protocol/response.hpp"

#include <boost/asio/awaitable.hpp>

#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <vector>

namespace axon::fps::host {

namespace asio = boost::asio;
using namespace std::chrono_literals;

struct ClientOptions {
  // How long a unicast request waits for its reply (per attempt).
  core::Duration timeout = 1s;
  // Per-command overrides of `timeout`.
  std::map<protocol::CommandId, core::Duration> command_timeouts;
  // Extra attempts after a timeout, for reads only (the table's read_only commands).
  unsigned read_retries = 2;
  // How long a broadcast collects replies when it does not reach its expected count (hosts in
  // service wait a fixed 0.5 s).
  core::Duration broadcast_window = 500ms;
  // A uid whose request timed out stays unused this long, in case its reply still comes.
  core::Duration late_window = 2s;
  // Unicast requests in flight on this bus at most (a CAN@net gateway holds 100 frames per bus).
  std::size_t max_in_flight = 64;
  // How often the idle reader checks whether it should stop.
  core::Duration idle_poll = 50ms;

  [[nodiscard]] core::Duration timeout_for(protocol::CommandId c) const {
    auto it = command_timeouts.find(c);
    return it == command_timeouts.end() ? timeout : it->second;
  }
};

// A reply as it came off the bus.
struct Reply {
  std::uint16_t positioner = 0;
  std::uint8_t command = 0;
  std::uint8_t uid = 0;
  protocol::ResponseCode code = protocol::ResponseCode::accepted;
  protocol::Payload payload;
  core::WallTime timestamp{0};

  [[nodiscard]] bool accepted() const noexcept { return code == protocol::ResponseCode::accepted; }
  // The response code as an Error ("positioner 17 GO_TO_ABSOLUTE_POSITION uid 3: positioner:
  // ALREADY_IN_MOTION (...); advice"); only meaningful when !accepted().
  [[nodiscard]] Error error() const;
};

// A frame a positioner sent on its own (uid 0) that no broadcast was collecting: a collision
// report (command 18; code 8 alpha, 9 beta) or the acknowledgement of a start by the sync line.
struct Unsolicited {
  std::uint16_t positioner = 0;
  std::uint8_t command = 0;
  protocol::ResponseCode code = protocol::ResponseCode::accepted;
  protocol::Payload payload;
  core::WallTime timestamp{0};

  [[nodiscard]] bool is_collision() const noexcept {
    return command == protocol::number(protocol::CommandId::collision_detected);
  }
};

struct RequestOptions {
  std::optional<core::Duration> timeout;  // instead of the client's
  std::optional<unsigned> retries;        // instead of read_retries; ignored for non-reads
};

struct BroadcastOptions {
  // Stop collecting as soon as this many distinct positioners replied.
  std::optional<std::size_t> expected;
  // Or as soon as every one of these replied (replies from others are collected too, but do not
  // count: a robot nobody knows cannot stand in for a known one that stays silent).
  std::optional<std::set<std::uint16_t>> expected_ids;
  // Collect this long at most (default ClientOptions::broadcast_window).
  std::optional<core::Duration> window;
  // Called instead of sending the broadcast frame, once the collection is ready: for replies that
  // something else triggers (the sync line starts trajectories; its replies carry uid 0 too).
  std::function<asio::awaitable<Result<void>>()> trigger;
};

struct BroadcastResult {
  std::vector<Reply> replies;  // the first reply of each positioner, in arrival order
  std::size_t duplicates = 0;  // further replies from a positioner that already replied
  bool complete = false;       // the expected count was reached before the window closed

  [[nodiscard]] const Reply* from(std::uint16_t positioner) const noexcept;
  [[nodiscard]] std::vector<std::uint16_t> positioners() const;
};

// The outcome of a pipelined run of requests to one positioner (CommandClient::pipeline).
struct PipelineResult {
  std::size_t issued = 0;                   // requests sent
  std::size_t accepted = 0;                 // requests accepted in order before the first failure
  std::optional<std::size_t> failed_index;  // the first request (in order) that failed
  std::optional<Error> error;               // and why

  [[nodiscard]] bool ok() const noexcept { return !failed_index.has_value(); }
};

struct ClientCounters {
  std::uint64_t sent = 0;               // request frames handed to the bus (retries and broadcasts included)
  std::uint64_t send_errors = 0;        // frames the bus refused
  std::uint64_t replies = 0;            // replies matched to a request or a broadcast
  std::uint64_t timeouts = 0;           // attempts that got no reply in time
  std::uint64_t retries = 0;            // repeated attempts of reads
  std::uint64_t late = 0;               // replies that came after their request timed out
  std::uint64_t unmatched = 0;          // replies no request or broadcast waited for (duplicates, stray)
  std::uint64_t broadcasts = 0;         // broadcasts sent (or triggered)
  std::uint64_t broadcast_duplicates = 0;
  std::uint64_t unsolicited = 0;        // uid-0 frames handed to subscribers (collisions included)
  std::uint64_t collisions = 0;         // collision reports (command 18)
  std::uint64_t foreign = 0;            // frames that are not fps replies (standard/remote, addressed to 0)
  std::uint64_t bad_replies = 0;        // replies whose data did not decode for their command
  std::uint64_t uid_waits = 0;          // requests that had to wait for a free uid
  std::uint64_t slot_waits = 0;         // requests that had to wait for the bus in-flight bound
  std::uint64_t refused = 0;            // moves refused by the motion lock (nothing sent)
  std::array<std::uint64_t, 16> by_code{};  // matched replies by response code (0 = accepted)

  [[nodiscard]] std::uint64_t errors() const noexcept;  // matched replies with a non-zero code
};

class CommandClient {
 public:
  // Starts the reader on the bus's executor. `lock`: the lock whose holding refuses moves (an
  // Array's; none: nothing is refused).
  explicit CommandClient(can::Bus& bus, ClientOptions options = {}, std::shared_ptr<const MotionLock> lock = nullptr);
  CommandClient(const CommandClient&) = delete;
  CommandClient& operator=(const CommandClient&) = delete;
  ~CommandClient();

  [[nodiscard]] can::Bus& bus() const noexcept;
  [[nodiscard]] const ClientOptions& options() const noexcept;
  [[nodiscard]] const ClientCounters& counters() const noexcept;
  // The lock this client obeys (nullptr: none).
  [[nodiscard]] const MotionLock* motion_lock() const noexcept;
  // Unicast requests waiting for their reply right now.
  [[nodiscard]] std::size_t in_flight() const noexcept;
  [[nodiscard]] bool running() const noexcept;

  // Sends one request to positioner 1..2047 and waits for its reply. Errors: the command table's
  // (ProtocolErrc: broadcast-only addressing, wrong payload size, host cannot send it),
  // HostErrc::locked (a move while the lock is held: not sent), a ResponseCode when the positioner
  // refused, HostErrc::timeout, cancelled, closed, or the bus's send error.
  asio::awaitable<Result<Reply>> request(std::uint16_t positioner, protocol::CommandId command,
                                         protocol::Payload payload = {}, RequestOptions options = {});

  // The same with the command's typed request and reply (payloads.hpp); a reply that does not
  // decode is HostErrc::bad_reply (counted).
  template <protocol::CommandId C>
  asio::awaitable<Result<protocol::ReplyOf<C>>> call(std::uint16_t positioner, protocol::RequestOf<C> req = {},
                                                     RequestOptions options = {}) {
    auto r = co_await request(positioner, C, req.encode(), options);
    if (!r) co_return r.error();
    co_return decode_reply<protocol::ReplyOf<C>>(r.value());
  }

  // Decodes a reply's data as T; HostErrc::bad_reply (counted) when it does not fit.
  template <class T>
  Result<T> decode_reply(const Reply& reply) {
    auto v = T::decode(reply.payload);
    if (!v) return bad_reply(reply, v.error());
    return std::move(v).value();
  }

  // Sends `requests` to one positioner in order, at most `window` of them waiting for replies at
  // a time, and checks every reply. After the first failure no further request goes out (those
  // already in flight are awaited). `progress` is called with the number of requests accepted in
  // order each time that number grows. The requests must stay alive until this completes.
  asio::awaitable<PipelineResult> pipeline(std::uint16_t positioner, std::span<const protocol::Request> requests,
                                           std::size_t window, std::function<void(std::size_t)> progress = {},
                                           RequestOptions options = {});

  // Sends a broadcast (positioner 0, uid 0) and collects the replies until `expected` positioners
  // answered or the window closed. Replies with a non-zero code are collected too (check each).
  // Only one broadcast of a given command is collected at a time on a bus: a second one waits.
  // A move (START_TRAJECTORY) while the lock is held is HostErrc::locked: neither sent nor triggered.
  asio::awaitable<Result<BroadcastResult>> broadcast(protocol::CommandId command, protocol::Payload payload = {},
                                                     BroadcastOptions options = {});
  // Sends a broadcast at once and does not collect replies (they go to a running collection of
  // the same command, or to the subscribers): for emergency stops, which must never wait. A move
  // while the lock is held is HostErrc::locked.
  asio::awaitable<Result<void>> broadcast_now(protocol::CommandId command);

  // Subscribers see every Unsolicited frame, synchronously from the reader (keep handlers short;
  // co_spawn longer work). Returns an id for unsubscribe().
  using Handler = std::function<void(const Unsolicited&)>;
  std::uint64_t subscribe(Handler handler);
  void unsubscribe(std::uint64_t id) noexcept;

  // Fails every waiting request with HostErrc::cancelled, ends the reader and waits until it has
  // ended. Safe to call twice.
  asio::awaitable<void> stop();

  class Impl;

 private:
  Error bad_reply(const Reply& reply, const Error& why);
  std::shared_ptr<Impl> impl_;
};

}  // namespace axon::fps::host
