// The built-in applications of `axon c4g serve`: what they share.
//
// Each application is a host::Controller (it runs inline on the server's cycle thread) plus what
// the command line needs around it:
//   - events (mode changes per axis, drives on/off per arm, initialization packets, the app's own
//     milestones) queued without allocation for the CLI thread to print;
//   - a status line and a summary, read from any thread;
//   - a stop request: the app then leaves the open modes it is in (exit from open for the modes the
//     PC ends, holding replies meanwhile), and `quiescent()` tells when every axis is back in mode 0;
//   - `finished()` when the app has done its job (a trajectory played and the open mode left), and
//     an error text when it refuses to go on (bad configuration, start point far from the robot).
//
// Applications see the cycle through `step()`; the base class keeps the bookkeeping (modes per axis,
// drives per arm, last packet summary) and calls it. Nothing here allocates in the cycle.
#pragma once

#include "axon/c4g/host/server.hpp"
#include "axon/c4g/protocol/axis_map.hpp"
#include "axon/c4g/protocol/init_packet.hpp"
#include "axon/c4g/protocol/packet.hpp"
#include "axon/c4g/protocol/transform.hpp"

#include <boost/lockfree/spsc_queue.hpp>

#include <array>
#include <atomic>
#include <cstdarg>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace axon::c4g::apps {

enum class EventKind : std::uint8_t {
  init,          // initialization packet: value = open axes, aux = period [ms]
  mode_change,   // axis's SM changed: value = from, aux = to
  drives,        // arm's drives on (value 1) / off (value 0)
  exit_sent,     // the app asked the arm to leave the open mode
  note,          // the app's own milestone: value = app-defined code (see App::note_text)
  silence,       // packets stopped
};

// One cycle as the app saw it: the controller's packet and the reply the app built (before the
// server's Safety layer, which changes it only when a fault is latched or a current is clamped).
struct Sample {
  std::uint64_t cycle = 0;
  std::int64_t wall_ns = 0;  // arrival of the controller's packet
  protocol::Packet request;
  protocol::Packet reply;
};

struct Event {
  EventKind kind{};
  std::uint64_t cycle = 0;
  std::int64_t wall_ns = 0;
  int axis = -1;  // open index (mode_change) or arm (drives, exit_sent)
  std::int32_t value = 0;
  std::int32_t aux = 0;
};

// One arm's open axes and the conversions between link and motor side.
struct ArmView {
  std::size_t arm = 1;
  std::size_t first = 0;   // open index of logical axis 1
  std::size_t count = 0;   // axes of the transform (logical 1..count, all open and consecutive)
  double period_s = 0.001;
  protocol::ArmTransform transform;
};
// Builds the view of an arm whose logical axes 1..n (n from the transmission ratios) are all open,
// consecutive and in order; invalid_argument saying what is missing otherwise.
Result<ArmView> make_arm_view(const protocol::InitPacket& init, const protocol::AxisMap& map, std::size_t arm);

class App : public host::Controller {
 public:
  App();
  ~App() override = default;

  [[nodiscard]] virtual std::string_view name() const noexcept = 0;
  // One line for the live status (any thread).
  [[nodiscard]] virtual std::string status() const;
  // Lines printed at exit (any thread).
  [[nodiscard]] virtual std::string summary() const;
  // The app has done its job and the axes are back in mode 0 (any thread).
  [[nodiscard]] virtual bool finished() const noexcept { return false; }
  // When the app reports an error while the robot depends on it (the PC closes the loops), the
  // server should drive off at once rather than wait for the open mode to end.
  [[nodiscard]] virtual bool drive_off_on_error() const noexcept { return false; }

  // Asks the app to leave the open modes (any thread; takes effect at the next cycle).
  void request_stop() noexcept { stop_requested_.store(true, std::memory_order_release); }
  [[nodiscard]] bool stop_requested() const noexcept { return stop_requested_.load(std::memory_order_acquire); }
  // Every axis of the last packet is in mode 0 (or nothing has arrived, or packets stopped).
  [[nodiscard]] bool quiescent() const noexcept { return quiescent_.load(std::memory_order_acquire); }
  // The controller announced the end of the exchange (504).
  [[nodiscard]] bool controller_exited() const noexcept { return exit_open_seen_.load(std::memory_order_acquire); }

  // Why the app stopped doing its job; empty when it did not (any thread).
  [[nodiscard]] std::string error() const;
  [[nodiscard]] bool has_error() const noexcept { return error_set_.load(std::memory_order_acquire); }

  // The error text without allocation (empty when none; any thread once has_error()).
  [[nodiscard]] const char* error_text() const noexcept { return has_error() ? error_.data() : ""; }

  // Events since the last call (CLI thread; single consumer). Composite apps add their parts'.
  virtual std::vector<Event> drain_events();
  // An event in words, e.g. "axis 1 (arm 1 axis 1): mode 0 -> 4 (mode4)".
  [[nodiscard]] std::string describe(const Event& e) const;

  // Keeps every cycle's packets for drain_samples() (call before the server starts; capacity in
  // cycles; a full queue drops samples and counts them).
  void record_samples(std::size_t capacity);
  // Hands the samples recorded since the last call to f, oldest first (one consumer thread).
  std::size_t drain_samples(const std::function<void(const Sample&)>& f);
  [[nodiscard]] std::uint64_t samples_dropped() const noexcept { return samples_dropped_.load(std::memory_order_relaxed); }

  [[nodiscard]] std::uint64_t cycles() const noexcept { return cycles_.load(std::memory_order_relaxed); }
  [[nodiscard]] std::uint64_t events_dropped() const noexcept { return events_dropped_.load(std::memory_order_relaxed); }

  // host::Controller
  void on_init(const protocol::InitPacket& init, const protocol::AxisMap& axes) final;
  void on_cycle(const host::CycleContext& ctx, host::ReplyBuilder& reply) final;
  void on_silence() noexcept final;

 protected:
  // The app's part of on_init (may allocate; a thrown exception becomes a server fault; prefer fail()).
  virtual void setup(const protocol::InitPacket& init, const protocol::AxisMap& axes) { (void)init, (void)axes; }
  // The app's part of on_cycle: the reply arrives as the server's safe reply.
  virtual void step(const host::CycleContext& ctx, host::ReplyBuilder& reply) = 0;
  virtual void silence() noexcept {}
  // Text of a note event's code.
  [[nodiscard]] virtual std::string note_text(std::int32_t code) const { return fmt_code(code); }

  // Cycle thread helpers.
  void fail(const char* format, ...) noexcept __attribute__((format(printf, 2, 3)));
  void fail_v(const char* format, va_list args) noexcept __attribute__((format(printf, 2, 0)));
  void note(std::int32_t code, int axis = -1, std::int32_t aux = 0) noexcept;
  // Sets exit from open for the arm (once per cycle; logs the first request of a series).
  void exit_from_open(host::ReplyBuilder& reply, std::size_t arm) noexcept;
  [[nodiscard]] const protocol::InitPacket* init() const noexcept { return have_init_ ? &init_ : nullptr; }
  [[nodiscard]] const protocol::AxisMap* axis_map() const noexcept { return have_init_ ? &map_ : nullptr; }
  [[nodiscard]] std::uint64_t cycle_now() const noexcept { return cycle_; }
  // Whether the previous packet had this axis in this mode (false at the first packet).
  [[nodiscard]] std::int32_t previous_mode(std::size_t open_index) const noexcept { return prev_modes_[open_index]; }

 private:
  static std::string fmt_code(std::int32_t code);
  void push(const Event& e) noexcept;

  boost::lockfree::spsc_queue<Event> events_;
  std::unique_ptr<boost::lockfree::spsc_queue<Sample>> samples_;
  std::atomic<std::uint64_t> samples_dropped_{0};
  std::atomic<std::uint64_t> events_dropped_{0};
  std::atomic<bool> stop_requested_{false};
  std::atomic<bool> quiescent_{true};
  std::atomic<bool> exit_open_seen_{false};
  std::atomic<std::uint64_t> cycles_{0};
  std::atomic<bool> error_set_{false};
  std::array<char, 512> error_{};

  // Cycle thread.
  protocol::InitPacket init_{};
  protocol::AxisMap map_{};
  bool have_init_ = false;
  bool have_packet_ = false;
  std::uint64_t cycle_ = 0;
  std::int64_t wall_ns_ = 0;
  std::array<std::int32_t, protocol::kMaxAxes> prev_modes_{};
  std::array<bool, protocol::kMaxArms> drives_{};
  std::array<bool, protocol::kMaxArms> exit_logged_{};

 protected:
  // Last packet seen, for status lines (relaxed atomics: a torn view across axes is fine there).
  std::array<std::atomic<std::int32_t>, protocol::kMaxAxes> shown_mode_{};
  std::array<std::atomic<float>, protocol::kMaxAxes> shown_position_{};  // D3 [motor turns]
  std::atomic<std::size_t> shown_count_{0};
};

}  // namespace axon::c4g::apps
