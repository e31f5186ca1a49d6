// Board: one motor driver board (two motors) on its own can::Bus.
//
// Two ways to use it, never at the same time:
//
//  * Coroutine API on the bus's executor, for set-up and sequences: enable() (zero currents, then
//    ENABLE_SYS, SEND_ALL, ENABLE_MTRx, then wait until the status shows the motors aligned and
//    ready), wait_status(), send_currents(), command(), recover(), disable(). While in this mode a
//    reader coroutine decodes every frame into latest().
//
//  * Cyclic API for a real-time thread: co_await start_cyclic() zeroes the currents, sets the
//    board's receive timeout (options().recv_timeout_ms) and hands the state to port(). From then
//    on exactly one real-time thread calls port().poll(now) and port().send_currents(...) every
//    cycle; frames cross between the threads through the port's RtLink (see rt_link.hpp for why).
//    After that thread stopped, co_await stop_cyclic() sends the frames still queued and takes
//    the state back. Coroutine calls made in between fail with HostErrc::cyclic_active.
//
// Shutdown: disable() zeroes the currents and disables the motors and the system, from any mode
// (in cyclic mode it ends cyclic mode first) and trying every frame even when one fails. A Board
// destroyed while it had the motors enabled queues the same frames on the bus's executor (best
// effort: the bus must outlive that, as it must outlive the Board); the board's own receive
// timeout is the backstop when the host disappears. MotorSession (motor_session.hpp) makes the
// disable happen on every way out of a program's work with the motors.
//
// Stop requests: interrupt() (from a signal handler's callback on the bus's executor) makes the
// wait in progress and every later one return HostErrc::interrupted, so that an enable() waiting
// seconds for the alignment ends at once and the caller can disable. clear_interrupt() undoes it.
//
// Only one coroutine may wait on a board at a time (wait_* and the sequences that use them).
#pragma once

#include "axon/blmc/host/measurements.hpp"
#include "axon/blmc/host/onboard.hpp"
#include "axon/blmc/host/rt_link.hpp"
#include "axon/blmc/protocol/command.hpp"
#include "axon/blmc/protocol/frames.hpp"
#include "axon/can/bus.hpp"
#include "axon/core/clock.hpp"
#include "axon/core/error.hpp"
#include "axon/core/wakeup.hpp"

#include <boost/asio/awaitable.hpp>

#include <array>
#include <chrono>
#include <functional>
#include <memory>
#include <string>

namespace axon::blmc::host {

namespace asio = boost::asio;
using namespace std::chrono_literals;

struct BoardOptions {
  std::string name = "blmc";
  std::array<bool, 2> motors{true, true};  // motors to enable and supervise
  core::Duration ready_timeout = 10s;      // alignment on the first enable takes a few seconds
  core::Duration status_timeout = 2500ms;  // waiting for a status frame (the board sends one per second)
  std::uint32_t recv_timeout_ms = 50;      // SET_CAN_RECV_TIMEOUT at start_cyclic(); 0 leaves it off
  bool send_all = true;                    // SEND_ALL=1 on enable (data frames and encoder index)
  std::size_t link_capacity = 256;         // frames per direction between the RT and the bus thread
};

// The real-time thread's view of a board (only valid between start_cyclic and stop_cyclic).
// Nothing here blocks, locks, allocates or throws on the normal path.
class CyclicPort {
 public:
  explicit CyclicPort(std::size_t capacity);

  // Decodes every frame that arrived since the last call into latest(), stamped with `now`.
  // Returns how many frames were taken.
  std::size_t poll(core::TimePoint now) noexcept;
  [[nodiscard]] const Measurements& latest() const noexcept { return state_; }

  // Queues one IqRef frame. Non-finite values become 0 and values beyond the Q24 range are
  // limited to it (the safety clamp normally keeps them far inside). False when the queue is full.
  bool send_currents(MotorPair amperes) noexcept;
  // Queues IqRef = 0 and ENABLE_MTR1=0, ENABLE_MTR2=0 (what a safety fault sends).
  bool send_disable() noexcept;
  // Queues any frame.
  bool send(const can::Frame& f) noexcept { return link_.send(f); }

  [[nodiscard]] RtLink& link() noexcept { return link_; }
  [[nodiscard]] std::uint64_t frames_sent() const noexcept { return sent_; }

 private:
  friend class Board;
  RtLink link_;
  Measurements state_;
  std::array<can::Frame, 3> disable_frames_;
  std::uint64_t sent_ = 0;
};

class Board {
 public:
  // Sees every frame the board receives or sends (outgoing = true), on the bus's thread.
  using FrameTap = std::function<void(const can::Frame&, bool outgoing)>;

  Board(can::Bus& bus, BoardOptions options = {}, const core::Clock& clock = core::SteadyClock::instance());
  ~Board();
  Board(const Board&) = delete;
  Board& operator=(const Board&) = delete;

  [[nodiscard]] can::Bus& bus() const noexcept { return *bus_; }
  [[nodiscard]] const BoardOptions& options() const noexcept { return options_; }
  [[nodiscard]] const core::Clock& clock() const noexcept { return *clock_; }
  void set_tap(FrameTap tap) { tap_ = std::move(tap); }

  // ---- coroutine API (the bus's executor; HostErrc::cyclic_active in cyclic mode)
  asio::awaitable<Result<void>> send_frame(const can::Frame& f);
  asio::awaitable<Result<void>> command(const protocol::Command& cmd);
  asio::awaitable<Result<void>> send_currents(MotorPair amperes);
  // Zero currents, ENABLE_SYS=1, SEND_ALL=1 (option), ENABLE_MTRx=1 for the motors in use, then
  // wait_ready(ready_timeout).
  asio::awaitable<Result<void>> enable();
  // Waits for a status frame newer than the call showing the system and the used motors enabled
  // and ready. board_error (naming the code, or the undocumented code 6) when it carries an
  // error, not_ready after the timeout (timeout when no status came at all).
  asio::awaitable<Result<void>> wait_ready(core::Duration timeout);
  // The next status frame; board_error when it carries the undocumented error code 6 (which a
  // protocol::Status cannot hold).
  asio::awaitable<Result<protocol::Status>> wait_status(core::Duration timeout);
  // Waits until `n` more measurement frames (current, position, velocity, ADC) arrived.
  asio::awaitable<Result<void>> wait_data(core::Duration timeout, std::uint64_t n = 1);
  asio::awaitable<Result<void>> set_recv_timeout(std::uint32_t ms);
  // The documented recovery after an error: ENABLE_SYS=1, IqRef=0, ENABLE_MTRx=1, wait_ready.
  asio::awaitable<Result<void>> recover();
  // IqRef=0, ENABLE_MTR1=0, ENABLE_MTR2=0, ENABLE_SYS=0. In cyclic mode it first ends it
  // (stop_cyclic: the real-time thread must have stopped using port()). Every frame is tried even
  // when one fails; the first failure is returned.
  asio::awaitable<Result<void>> disable();
  // The same frames queued on the bus's executor without waiting (destructors, abandoned work).
  void queue_disable();
  // The program hands the board on enabled on purpose (`axon blmc enable`): the destructor does
  // not disable it.
  void leave_enabled() noexcept { motors_on_ = false; }
  // See "Stop requests" above.
  void interrupt() noexcept;
  void clear_interrupt() noexcept { interrupted_ = false; }
  [[nodiscard]] bool interrupted() const noexcept { return interrupted_; }
  // ---- the board's own controller and switches (onboard.hpp), coroutine mode. Each checks its
  // values first (HostErrc::invalid_argument in words; nothing is sent then) and sends its frames
  // in order. Once one of them went out, disable() and the destructor's queued disable also send
  // onboard_reset_frames() (controller limits 0, springs off) after the usual frames.
  asio::awaitable<Result<void>> set_onboard_gains(OnboardGains gains);
  // Position references in the host's positions (latest().position), see onboard.hpp.
  asio::awaitable<Result<void>> set_onboard_references(OnboardReferences refs);
  asio::awaitable<Result<void>> set_onboard_current_limits(OnboardCurrentLimits limits);
  asio::awaitable<Result<void>> set_rollover_error(bool on);
  asio::awaitable<Result<void>> set_virtual_springs(std::array<bool, 2> on);

  // The state decoded so far (coroutine mode; in cyclic mode port().latest() is current).
  [[nodiscard]] const Measurements& latest() const noexcept { return state_; }

  // ---- cyclic mode
  asio::awaitable<Result<void>> start_cyclic();
  // Call after the real-time thread stopped using port().
  asio::awaitable<Result<void>> stop_cyclic();
  [[nodiscard]] bool cyclic() const noexcept { return cyclic_; }
  [[nodiscard]] CyclicPort& port() noexcept { return *port_; }

  [[nodiscard]] bool closed() const noexcept { return closed_; }

  struct Shared;  // state shared with the board's coroutines (outlives the Board if they do)
  // Internal: called by the board's reader coroutine.
  void frame_hook(const can::Frame& f);
  void closed_hook();

 private:
  asio::awaitable<Result<void>> wait_until(core::TimePoint deadline, const std::function<bool()>& done);
  asio::awaitable<Result<void>> send_onboard(Result<std::vector<can::Frame>> frames);
  [[nodiscard]] std::vector<can::Frame> shutdown_frames() const;
  // board_error naming the latest status frame's error code (documented or not).
  [[nodiscard]] Error status_error() const;
  asio::awaitable<void> tx_pump(std::shared_ptr<Shared> shared);

  can::Bus* bus_;
  BoardOptions options_;
  const core::Clock* clock_;
  Measurements state_;
  std::unique_ptr<CyclicPort> port_;
  std::shared_ptr<Shared> shared_;
  core::Wakeup wake_;
  core::Wakeup pump_done_;
  FrameTap tap_;
  bool cyclic_ = false;
  bool pump_running_ = false;
  bool closed_ = false;
  bool motors_on_ = false;  // we enabled motors and did not disable them yet
  bool interrupted_ = false;
  bool onboard_used_ = false;  // a set_onboard_* / set_virtual_springs call sent its frames
};

}  // namespace axon::blmc::host
