// The PC side of the open interface: a UDP server that answers every packet of the robot
// controller within the cycle, from the very first one.
//
// Threads: the cycle runs on a CycleThread (real-time when permitted). Per packet it decodes,
// builds the safe reply for the current modes, lets the user's Controller refine it, applies the
// Safety layer and sends. The user's Controller runs inline on the cycle thread: it must be quick
// and should not allocate; the Server catches its exceptions and times it (see docs/c4g-server.md
// for why inline rather than on a worker thread with a deadline).
//
// Session (session_peer.hpp): the server answers one controller. Its address is fixed by
// ServerOptions::controller or by the first well-formed packet; datagrams from anyone else are
// counted (ServerCounters::foreign) and otherwise ignored: no reply, no state change, no safety
// latch, no timing sample.
//
// Packets (from the session's controller):
//   - the initialization packet (1200 bytes): decoded, kept (init()), turned into an AxisMap and
//     the Safety thresholds/limits; answered with a cyclic packet of its axis count carrying its
//     protocol number and the start-up modes, data zero (the manual does not define this answer;
//     the controller only checks the number);
//   - cyclic packets (12 + 36 n bytes): answered with the same protocol number (the manual) or
//     NUM + 1 (field libraries, ServerOptions::numbering);
//   - anything else: counted as a protocol error; a cyclic-sized packet that fails to decode (NaN,
//     wrong axis count, NUM out of range) is still answered, with drive off, and latches a fault;
//     a datagram of no known size cannot be answered meaningfully and is not.
//
// Safe reply (used before the controller runs, when it throws, when it is faulted): every axis
// echoes its mode; data are zero except where zero would move the robot: mode 0' echoes targets
// (the manual's echo test), modes 1/1' and 4/4' hold the last commanded target (else the
// controller's own target D1, so that nothing jumps). Modes 1 and 2 (PC closes the loops) have no passive safe current: a fault there asks
// for drive off.
#pragma once

#include "axon/c4g/host/controller_watch.hpp"
#include "axon/c4g/host/cycle_thread.hpp"
#include "axon/c4g/host/pcap_recorder.hpp"
#include "axon/c4g/host/safety.hpp"
#include "axon/c4g/host/session_peer.hpp"
#include "axon/c4g/host/switch_tracker.hpp"
#include "axon/c4g/protocol/axis_map.hpp"
#include "axon/c4g/protocol/init_packet.hpp"
#include "axon/c4g/protocol/packet.hpp"
#include "axon/core/error.hpp"
#include "axon/net/endpoint.hpp"

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

namespace axon::c4g::host {

// The manual's addresses: the PC serves on 10.2.12.149, the controller sends from 10.2.12.150,
// port 1000 (field notes). A host given without a port gets kManualPort.
inline constexpr const char* kManualServerAddress = "10.2.12.149";
inline constexpr std::uint16_t kManualPort = 1000;
// Unless told otherwise the server listens on loopback, on a port an unprivileged user may bind
// (the manual's 1000 needs root); `axon sim c4g` sends there by default.
inline constexpr const char* kDefaultServerAddress = "127.0.0.1";
inline constexpr std::uint16_t kDefaultPort = 11000;

// What the Controller sees of one cycle.
struct CycleContext {
  const protocol::Packet& request;    // the controller's packet, decoded
  const protocol::InitPacket* init;   // nullptr until the initialization packet arrived
  const protocol::AxisMap* axes;      // nullptr until then (or if its axis lists were bad)
  std::uint64_t cycle;                // cyclic packets handled so far (0 for the first)
  std::int64_t arrival_wall_ns;       // kernel arrival stamp (or clock at receive)
  // Soft control switching per axis as inferred from the modes (interval, chi/eta/rho, the PC
  // reducer's factor pc_gain()); nullptr when the caller does not track it (hand-made contexts).
  const SwitchTracker* switching = nullptr;
  // Active freezing (500) is in force: the Server answers on its own (every axis 500, exit-from-open
  // when released) and discards this cycle's reply; the call is neither timed nor counted late, so
  // the controller may do long non-real-time work here (see Server::request_freeze).
  bool frozen = false;

  // The motion type the robot program set for an arm (1..4): its byte of CMD, $ARM_DATA[arm].
  // C4GOPEN_CMD[1] (manual chapters 8 and 18); 0 when none was set.
  [[nodiscard]] std::uint8_t motion_type(std::size_t arm) const noexcept { return protocol::arm_byte(request.cmd, arm); }
};

// Helps the controller fill the reply, which arrives pre-filled with the safe reply.
class ReplyBuilder {
 public:
  explicit ReplyBuilder(protocol::Packet& reply) noexcept : reply_(reply) {}
  [[nodiscard]] std::size_t axis_count() const noexcept { return reply_.count; }
  protocol::Axis& axis(std::size_t open_index) noexcept { return reply_.axes[open_index < protocol::kMaxAxes ? open_index : 0]; }
  void set_mode(std::size_t open_index, std::int32_t mode) noexcept { axis(open_index).mode = mode; }
  // Modes 1xx (101 accelerometer, 102 camera, 103 force/torque): the external sensor's measure for
  // an axis, in the sensor's own unit; it travels in D3, the only field those modes use.
  void set_measure(std::size_t open_index, float value) noexcept { axis(open_index).d3 = value; }
  // Asks the controller to leave the open mode for an arm (1..4): INFPAR byte = 1.
  void exit_from_open(std::size_t arm) noexcept { reply_.infpar = protocol::request_exit_from_open(reply_.infpar, arm); }
  void set_cmd(std::int32_t cmd) noexcept { reply_.cmd = cmd; }
  protocol::Packet& packet() noexcept { return reply_; }

 private:
  protocol::Packet& reply_;
};

// The user's control law. on_cycle runs on the cycle thread for every cyclic packet while no
// fault is latched; it may throw (the Server then latches a fault and drives off).
class Controller {
 public:
  virtual ~Controller() = default;
  virtual void on_init(const protocol::InitPacket& init, const protocol::AxisMap& axes) { (void)init, (void)axes; }
  virtual void on_cycle(const CycleContext& ctx, ReplyBuilder& reply) = 0;
  // No packet within the cycle timeout (the controller stopped or restarted). Cycle thread.
  virtual void on_silence() noexcept {}
};

struct ServerOptions {
  net::Endpoint listen{kDefaultServerAddress, kDefaultPort};
  // The controller's address: only it may start a session. Empty host: any host; port 0: any port
  // of that host. Either way the session then sticks to the first well-formed packet's exact
  // source (session_peer.hpp).
  net::Endpoint controller{"", 0};
  // The controller's period for the timing figures until its initialization packet tells (0:
  // unknown until then); the initialization packet's period wins.
  std::chrono::nanoseconds period{0};
  protocol::ReplyNumbering numbering = protocol::ReplyNumbering::same;
  net::UdpOptions udp{};
  CycleOptions cycle{};
  SafetyConfig safety{};
  std::string pcap_path{};  // empty: no recording
  PcapOptions pcap{};
  // Controller budget: a call longer than this counts as late; this many late calls in a row
  // latch a fault (0 disables).
  std::chrono::nanoseconds controller_budget = std::chrono::microseconds(400);
  int max_late_cycles = 3;
  // Checks every reply against the per-mode field table (protocol::check_reply_fields: a field the
  // mode does not use must be zero). Violations are always counted (ServerCounters::unused_fields);
  // with this set, one is a safety fault (drive off). Off in production by default; the tests turn
  // it on, so that no built-in reply sends data the controller does not expect.
  bool verify_reply_fields = false;
  // A session whose cyclic packets come without an initialization packet (this server was started
  // or restarted while the controller ran) is served, but without the axis map its Safety and the
  // applications need: after this many cyclic packets (past any sync phase) the server asks for the
  // packet with RESTART (506) on every axis, from mode 0 as the controller requires, and again every
  // as many packets until it comes. 0: never ask.
  int request_init_after = 50;
  // Soft control switching intervals T1, T2, T3 of the controller (the PC infers the switch's phase
  // from the modes and these; they must match the controller's configuration).
  protocol::SwitchTimes soft_switch{};
  // How the controller's errors are recognised from the packets (controller_watch.hpp).
  ControllerWatchOptions watch{};
};

enum class ServerState : std::uint8_t {
  waiting,   // no packet yet
  syncing,   // answering packets, no initialization packet yet
  running,   // initialization packet received, cyclic packets flowing
  silent,    // packets stopped arriving (cycle timeout)
  stopped,
};
std::string_view to_string(ServerState s) noexcept;

struct ServerCounters {
  std::atomic<std::uint64_t> packets{0};           // datagrams received from the session's controller
  std::atomic<std::uint64_t> foreign{0};           // datagrams from any other source: ignored
  std::atomic<std::uint64_t> last_foreign{SessionPeer::kNone};  // its source (SessionPeer::pack)
  std::atomic<std::uint64_t> sessions{0};          // sessions started (a peer fixed)
  std::atomic<std::uint64_t> init_packets{0};
  std::atomic<std::uint64_t> cyclic_packets{0};
  std::atomic<std::uint64_t> protocol_errors{0};   // datagrams that did not decode (before a session too)
  std::atomic<std::uint64_t> unanswered{0};        // datagrams with no answer (unknown size)
  std::atomic<std::uint64_t> controller_exceptions{0};
  std::atomic<std::uint64_t> controller_late{0};
  std::atomic<std::uint64_t> refused_mode_changes{0};  // controller asked for a change the rules forbid
  std::atomic<std::uint64_t> safe_replies{0};      // cycles answered without the controller's reply
  std::atomic<std::uint64_t> frozen_cycles{0};     // cycles answered under active freezing (500 .. back to 0)
  std::atomic<std::uint64_t> freezes{0};           // active freezings the controller entered
  std::atomic<std::uint64_t> unused_fields{0};     // replies with data in a field their mode does not use
  std::atomic<std::uint64_t> init_requests{0};     // RESTART (506) sent to get a missing initialization packet
  std::atomic<std::uint64_t> controller_restarts{0};  // the session's numbering started again (a restart within the cycle timeout)
};

// Active freezing (special mode 500), as the Server drives it.
enum class FreezeState : std::uint8_t {
  off,       // normal exchange
  pending,   // asked for; waits until every axis shows mode 0 (the manual's precondition)
  entering,  // 500 sent on every axis; the controller has not shown it yet
  frozen,    // the controller shows 500: it no longer checks the PC's replies
  leaving,   // released: exit-from-open sent on every arm until the controller shows mode 0
};
std::string_view to_string(FreezeState s) noexcept;

class Server : private CycleHandler {
 public:
  // Binds, opens the capture if asked, starts the cycle thread. The controller must outlive the
  // server.
  static Result<std::unique_ptr<Server>> start(Controller& controller, const ServerOptions& options = {});
  ~Server() override;  // stop()
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  void stop();

  [[nodiscard]] net::SocketAddress local_address() const noexcept { return cycle_->local_address(); }
  [[nodiscard]] ServerState state() const noexcept { return state_.load(std::memory_order_acquire); }
  // The session's controller (any thread): nullopt until the first well-formed packet.
  [[nodiscard]] std::optional<net::SocketAddress> peer() const noexcept { return peer_.current(); }
  [[nodiscard]] const SessionPeer& session_peer() const noexcept { return peer_; }
  // The controller's period the timing figures use (any thread); 0 while unknown.
  [[nodiscard]] std::int64_t period_ns() const noexcept { return cycle_->timing().nominal_period_ns(); }
  // The last initialization packet received (copy; any thread).
  [[nodiscard]] std::optional<protocol::InitPacket> init() const;
  [[nodiscard]] const protocol::Packet& last_request_unsafe() const noexcept { return request_; }  // cycle thread only
  [[nodiscard]] const ServerCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] Safety& safety() noexcept { return safety_; }
  [[nodiscard]] const Safety& safety() const noexcept { return safety_; }
  // The controller's errors as the packets show them, named as the manual names them (any thread).
  [[nodiscard]] const ControllerWatch& controller_errors() const noexcept { return watch_; }
  [[nodiscard]] const SwitchTracker& switch_tracker_unsafe() const noexcept { return switch_; }  // cycle thread only
  [[nodiscard]] const CycleThread& cycle() const noexcept { return *cycle_; }
  [[nodiscard]] const core::RealtimeReport& realtime_report() const noexcept { return cycle_->realtime_report(); }
  [[nodiscard]] const PcapRecorder* recorder() const noexcept { return recorder_.get(); }
  [[nodiscard]] std::string summary() const;
  // " (last from HOST:PORT)" when foreign datagrams came, else empty.
  [[nodiscard]] std::string foreign_source_text() const;

  // ---- active freezing (500) ----
  // request_freeze(): from the next packet in which every axis is in mode 0 (drives on or off, not
  // while driving on), the Server answers 500 on every axis; once the controller shows 500 it stops
  // checking replies, so this process may stall (file I/O, allocation, a debugger) without a
  // communication error. release_freeze(): the Server sends exit-from-open on every arm until the
  // controller shows mode 0 again, then the normal exchange resumes. Any thread; atomics only.
  // While in force the Controller is still called with ctx.frozen = true (its reply is discarded,
  // the call is not timed); a latched safety fault overrides the freeze (drive off goes out).
  void request_freeze() noexcept { freeze_wanted_.store(true, std::memory_order_release); }
  void release_freeze() noexcept { freeze_wanted_.store(false, std::memory_order_release); }
  [[nodiscard]] bool freeze_requested() const noexcept { return freeze_wanted_.load(std::memory_order_acquire); }
  [[nodiscard]] FreezeState freeze_state() const noexcept { return freeze_state_.load(std::memory_order_acquire); }
  // The controller no longer checks replies (state frozen).
  [[nodiscard]] bool frozen() const noexcept { return freeze_state() == FreezeState::frozen; }

  // Scoped freeze: requests on construction, releases on destruction. It does not wait: poll
  // frozen() (or wait_frozen) before starting the long work.
  class FreezeGuard {
   public:
    explicit FreezeGuard(Server& s) noexcept : s_(&s) { s.request_freeze(); }
    ~FreezeGuard() { if (s_ != nullptr) s_->release_freeze(); }
    FreezeGuard(FreezeGuard&& o) noexcept : s_(o.s_) { o.s_ = nullptr; }
    FreezeGuard(const FreezeGuard&) = delete;
    FreezeGuard& operator=(const FreezeGuard&) = delete;
    FreezeGuard& operator=(FreezeGuard&&) = delete;

   private:
    Server* s_;
  };
  [[nodiscard]] FreezeGuard freeze() noexcept { return FreezeGuard(*this); }
  // Polls (1 ms sleeps; not for the cycle thread) until the controller shows 500 or the timeout
  // passes; true when frozen.
  bool wait_frozen(std::chrono::nanoseconds timeout) const;

 private:
  Server(Controller& controller, const ServerOptions& options, net::SocketAddress allowed);
  bool accepts(std::span<const std::byte> request, const net::Datagram& info) noexcept override;
  std::size_t on_packet(std::span<const std::byte> request, const net::Datagram& info,
                        std::span<std::byte> reply) noexcept override;
  void on_timeout(bool before_first) noexcept override;
  [[nodiscard]] double period_s() const noexcept;

  std::size_t answer_init(std::span<const std::byte> in, std::span<std::byte> out) noexcept;
  std::size_t answer_cyclic(std::span<const std::byte> in, const net::Datagram& info, std::span<std::byte> out) noexcept;
  std::size_t answer_bad_cyclic(std::span<const std::byte> in, std::span<std::byte> out) noexcept;
  void build_safe_reply(const protocol::Packet& request, protocol::Packet& reply) noexcept;
  void enforce_mode_rules(const protocol::Packet& request, protocol::Packet& reply) noexcept;
  bool arm_trajectory_moving(const protocol::Packet& request, std::size_t arm) const noexcept;
  // Advances the freeze state for this request; true when the freeze owns this cycle's reply.
  bool update_freeze(const protocol::Packet& request) noexcept;
  void build_freeze_reply(const protocol::Packet& request, protocol::Packet& reply) noexcept;
  // ServerOptions::request_init_after: RESTART (506) on every axis when the packet is missing.
  void request_missing_init(const protocol::Packet& request, protocol::Packet& reply) noexcept;
  // A controller that restarts faster than the cycle timeout comes back from the same address,
  // numbering from the start again: detected here, its session is started over.
  [[nodiscard]] bool numbering_restarted(std::int32_t num) const noexcept;
  void start_session_over() noexcept;
  std::size_t encode(const protocol::Packet& request, protocol::Packet& reply, std::span<std::byte> out) noexcept;

  Controller& controller_;
  ServerOptions options_;
  std::unique_ptr<PcapRecorder> recorder_;
  std::unique_ptr<CycleThread> cycle_;
  Safety safety_;
  SessionPeer peer_;
  ServerCounters counters_;
  std::atomic<ServerState> state_{ServerState::waiting};
  std::atomic<bool> freeze_wanted_{false};
  std::atomic<FreezeState> freeze_state_{FreezeState::off};

  mutable std::mutex init_mutex_;  // init_copy_ only; the cycle thread takes it once per init packet
  std::optional<protocol::InitPacket> init_copy_;

  // Cycle thread only.
  protocol::InitPacket init_{};
  bool have_init_ = false;
  protocol::AxisMap axes_{};
  bool have_axes_ = false;
  protocol::Packet request_{};
  protocol::Packet reply_{};
  protocol::Packet safe_{};
  std::uint64_t cyclic_count_ = 0;
  std::uint64_t init_requested_at_ = 0;  // cyclic_count_ when 506 was last sent (0: not yet)
  std::int32_t last_num_ = -1;           // the session's latest protocol number (-1: none yet)
  int late_in_row_ = 0;
  SwitchTracker switch_;
  ControllerWatch watch_;
  std::array<float, protocol::kMaxAxes> last_target_{};
  std::array<bool, protocol::kMaxAxes> have_target_{};
  std::array<bool, protocol::kMaxAxes> exit_sent_{};
};

}  // namespace axon::c4g::host
