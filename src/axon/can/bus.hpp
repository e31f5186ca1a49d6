// The Bus interface every CAN transport implements, with receive filtering, a bounded receive
// queue and per-bus statistics shared by all of them.
//
// Threading: a Bus lives on one executor (usually one io_context thread). All its member
// functions must be called from that executor; coroutines co_await send() and receive().
// Other threads hand frames over with asio::post / co_spawn onto the bus's executor.
#pragma once

#include "axon/can/frame.hpp"
#include "axon/can/wire.hpp"
#include "axon/core/clock.hpp"

#include <boost/asio/any_io_executor.hpp>
#include <boost/asio/awaitable.hpp>
#include <boost/asio/steady_timer.hpp>

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace axon::can {

namespace asio = boost::asio;

// Accepts a frame when (frame.id & mask) == (id & mask) and the id format matches.
struct Filter {
  enum class Format : std::uint8_t { any, standard, extended };
  std::uint32_t id = 0;
  std::uint32_t mask = 0;
  Format format = Format::any;

  [[nodiscard]] bool matches(const Frame& f) const noexcept {
    if (format == Format::standard && f.is_extended()) return false;
    if (format == Format::extended && !f.is_extended()) return false;
    return (f.id() & mask) == (id & mask);
  }
  // candump's notation "ID:MASK" (hex); 8 hex digits in ID make it extended-only.
  static Result<Filter> parse(std::string_view text);
};

enum class BusState : std::uint8_t { active, error_warning, error_passive, bus_off, closed };
const char* to_string(BusState s) noexcept;

struct BusStats {
  std::uint64_t frames_in = 0;        // frames received that passed the filters
  std::uint64_t frames_out = 0;       // frames sent
  std::uint64_t bits_in = 0;          // their exact wire bits (stuffing included)
  std::uint64_t bits_out = 0;
  std::uint64_t rx_filtered = 0;      // frames received but rejected by the filters
  std::uint64_t rx_dropped = 0;       // frames lost because the receive queue was full
  std::uint64_t tx_dropped = 0;       // frames the transport could not take (FIFO full)
  std::uint64_t protocol_errors = 0;  // malformed or unexpected input from the peer
  std::uint64_t error_frames = 0;     // CAN error frames / error reports from the controller
  std::uint64_t bus_off_events = 0;
  std::uint64_t error_warning_events = 0;
  core::TimePoint opened{};

  // Fraction of the bus time this node saw used by frames (in and out) since it was opened.
  [[nodiscard]] double load(core::TimePoint now, std::uint32_t bitrate) const noexcept;
};

struct BusOptions {
  std::size_t rx_capacity = 65536;          // frames queued for receive() before drops start
  std::uint32_t bitrate = kDefaultBitrate;  // for the load figure and wire timing
  std::size_t tx_capacity = 1024;           // frames a transport holds waiting for the wire
};

class Bus {
 public:
  using executor_type = asio::any_io_executor;

  Bus(executor_type ex, std::string name, BusOptions options = {});
  Bus(const Bus&) = delete;
  Bus& operator=(const Bus&) = delete;
  virtual ~Bus();

  [[nodiscard]] const std::string& name() const noexcept { return name_; }
  [[nodiscard]] executor_type get_executor() const noexcept { return executor_; }
  [[nodiscard]] const BusOptions& options() const noexcept { return options_; }

  // Hands the frame to the transport. Completes once the transport has taken it (queued for the
  // wire or written to the socket); errors: closed, tx_overflow, bus_off, io.
  virtual asio::awaitable<Result<void>> send(const Frame& frame) = 0;

  // The next received frame that passes the filters. Errors: closed; timeout for the timed form.
  asio::awaitable<Result<Frame>> receive();
  asio::awaitable<Result<Frame>> receive(core::Duration timeout);
  // A frame already queued, without waiting.
  std::optional<Frame> try_receive();
  [[nodiscard]] std::size_t pending() const noexcept { return rx_.size(); }
  // Frames sent but not yet on the wire (transports that queue; 0 for the others).
  [[nodiscard]] virtual std::size_t tx_pending() const noexcept { return 0; }
  // Waits until every frame sent so far has left (tx_pending() == 0): call before close() when
  // the last frames matter. Errors: timeout (with the count still waiting), closed.
  asio::awaitable<Result<void>> flush(core::Duration timeout);

  // Receive filters: a frame passes if any filter matches; no filters pass everything.
  // Transports that can also filter below user space (SocketCAN) override this and call it.
  virtual void set_filters(std::vector<Filter> filters);
  [[nodiscard]] const std::vector<Filter>& filters() const noexcept { return filters_; }

  [[nodiscard]] const BusStats& stats() const noexcept { return stats_; }
  [[nodiscard]] BusState state() const noexcept { return state_; }
  [[nodiscard]] bool is_open() const noexcept { return state_ != BusState::closed; }

  // Closes the transport; pending and future receive() calls complete with CanErrc::closed
  // once the queued frames are read. Safe to call twice.
  //
  // Lifetime: a bus may be destroyed while receive() or flush() calls are still in progress or
  // already woken and queued on the executor (a reader parked in receive() whose owner drops the
  // bus right after close()). They then complete with CanErrc::closed without touching the
  // destroyed bus. A send() still waiting for room on SocketCAN must end before the bus goes.
  virtual void close();

  // True once the bus is destroyed; shared with whoever holds it. For work queued on the bus's
  // executor that may run after the owner dropped the bus (frames a destructor sends on its way
  // out): check it before touching the bus.
  [[nodiscard]] std::shared_ptr<const bool> destroyed_flag() const noexcept {
    return {waiters_, &waiters_->bus_gone};
  }

 protected:
  // For transports: a frame came in from the wire (filters, statistics, queue; drops counted).
  void deliver(Frame frame) { deliver(frame, frame_bits(frame).total); }
  // The same, for transports that already know the frame's wire bits (one computation per frame
  // however many receivers).
  void deliver(Frame frame, std::uint32_t wire_bits);
  // For transports: a frame went out.
  void count_sent(const Frame& frame) noexcept { count_sent(frame, frame_bits(frame).total); }
  void count_sent(const Frame& frame, std::uint32_t wire_bits) noexcept;
  void set_state(BusState s) noexcept;
  BusStats& mutable_stats() noexcept { return stats_; }

  // The timers of receive() and flush() calls in progress, and whether the bus is gone; shared with
  // those calls, which outlive the bus in two ways: resumed after it was destroyed (woken by close()
  // or by the destructor, they see `bus_gone` and end without touching it), or destroyed unresumed
  // after it (an io_context torn down with work pending: they unregister from this, not the bus).
  struct Waiters {
    std::vector<asio::steady_timer*> timers;
    bool bus_gone = false;
  };
  // Registers a timer of a call in progress for the time it lives.
  struct WaiterRegistration {
    WaiterRegistration(std::shared_ptr<Waiters> w, asio::steady_timer& t);
    ~WaiterRegistration();
    WaiterRegistration(const WaiterRegistration&) = delete;
    WaiterRegistration& operator=(const WaiterRegistration&) = delete;
    std::shared_ptr<Waiters> waiters;
    asio::steady_timer* timer;
  };
  // For a transport's coroutine that suspends inside a member (a send waiting for room): hold this
  // before the suspension and check `bus_gone` after it before touching the bus.
  [[nodiscard]] std::shared_ptr<const Waiters> waiters() const noexcept { return waiters_; }

 private:
  asio::awaitable<Result<Frame>> receive_until(std::optional<core::TimePoint> deadline);
  void wake_receivers() noexcept;

  executor_type executor_;
  std::string name_;
  BusOptions options_;
  std::vector<Filter> filters_;
  std::deque<Frame> rx_;
  std::shared_ptr<Waiters> waiters_ = std::make_shared<Waiters>();
  BusStats stats_;
  BusState state_ = BusState::active;
};

}  // namespace axon::can
