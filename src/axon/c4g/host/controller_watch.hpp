// What the controller did to the robot that the PC sees only as symptoms in its packets, named as
// the manual's error table (chapter 17) names it on the controller's screen.
//
// The controller never tells the PC which error it raised: the packets only show modes, the drives'
// byte and the positions. ControllerWatch reads those, cycle by cycle, and says which documented
// error (or controller-side check, chapter 14.17.1) each symptom corresponds to:
//
//   symptom in the packets                                         the controller's error
//   an open mode goes straight to 0, drives still on, no            ERR_C4GOPEN_SET_0_MODALITY (the state
//     exit-from-open asked by the PC                                  selector moved AUTO <-> PROG)
//   the PC asked 505 and the arm shows 505 / its drives go off      ERR_C4GOPEN_DRIVEOFF_SERVER
//   the PC asked 508 and the arm shows 508                          ERR_C4GOPEN_FOLLOW_ERROR
//   drives off in an open mode the PC did not ask for               the controller's own checks: following
//                                                                     error, offset limit of modes 7/8/9
//   the target D1 jumps in mode 0                                   pos_i not updated to pos_k after an
//                                                                     abnormal exit (mode 5/7 warning)
//   mode 5's increments applied at less than 100 %                  the general override scales them (14.8)
//   a start-up mode on an axis the open-axis lists leave out        ERR_C4GOPEN_CONFIGURATION_AX
//   packets stop (not after 504)                                    ERR_C4GOPEN_UDP (10 missed answers) or
//                                                                     a restart
//
// Threads: configure/observe/on_silence/reset on the server's cycle thread (no allocation); the
// counters and the last diagnosis are atomics any thread reads; summary() allocates (any thread).
#pragma once

#include "axon/c4g/protocol/axis_map.hpp"
#include "axon/c4g/protocol/init_packet.hpp"
#include "axon/c4g/protocol/packet.hpp"

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace axon::c4g::host {

enum class ControllerError : std::uint8_t {
  none,
  communication,      // ERR_C4GOPEN_UDP
  configuration_ax,   // ERR_C4GOPEN_CONFIGURATION_AX
  forced_mode0,       // ERR_C4GOPEN_SET_0_MODALITY
  drive_off_server,   // ERR_C4GOPEN_DRIVEOFF_SERVER
  follow_error,       // ERR_C4GOPEN_FOLLOW_ERROR
  controller_stop,    // not in the table: the controller's own following-error or offset check
  position_jump,      // not in the table: the warning of modes 5 and 7
  override_scaled,    // not in the table: mode 5's increments scaled by the general override
};
inline constexpr std::size_t kControllerErrorCount = 9;

// The manual's name (ERR_C4GOPEN_*) or, for what its table does not list, a descriptive one.
std::string_view manual_name(ControllerError e) noexcept;
// What it means, in words, with the manual's message where it has one.
std::string_view meaning(ControllerError e) noexcept;

struct ControllerWatchOptions {
  float jump_turns = 0.5f;        // a change of the target D1 in mode 0 larger than this in one cycle [motor turns]
  double override_tolerance = 0.02;  // mode 5: applied/sent below 1 - this is reported as scaled
};

class ControllerWatch {
 public:
  explicit ControllerWatch(ControllerWatchOptions options = {}) noexcept : options_(options) {}

  // A new initialization packet: checks its start-up modes against its open-axis lists.
  void configure(const protocol::InitPacket& init, const protocol::AxisMap& map) noexcept;
  // One cycle: the controller's packet and the reply this server sent to it.
  void observe(const protocol::Packet& request, const protocol::Packet& reply) noexcept;
  // The packets stopped (cycle timeout).
  void on_silence() noexcept;
  // Forget the previous packet (a new session); the counts stay.
  void reset() noexcept { have_prev_ = false; }

  [[nodiscard]] std::uint32_t count(ControllerError e) const noexcept {
    return counts_[static_cast<std::size_t>(e)].load(std::memory_order_relaxed);
  }
  [[nodiscard]] ControllerError last() const noexcept { return last_.load(std::memory_order_acquire); }
  [[nodiscard]] int last_arm() const noexcept { return last_arm_.load(std::memory_order_relaxed); }
  [[nodiscard]] int last_axis() const noexcept { return last_axis_.load(std::memory_order_relaxed); }  // logical, 0: none
  // Mode 5's increments as applied by the controller [% of those sent] (the last mode-5 run; 0: none).
  [[nodiscard]] double applied_percent() const noexcept { return applied_percent_.load(std::memory_order_relaxed); }
  // The largest target jump seen [motor turns].
  [[nodiscard]] double jump_turns() const noexcept { return jump_.load(std::memory_order_relaxed); }
  // "none", or one line per error seen: name, count, last arm/axis, meaning.
  [[nodiscard]] std::string summary() const;
  // "none", or "NAME xN, NAME xN" (any thread).
  [[nodiscard]] std::string names() const;

 private:
  void record(ControllerError e, std::size_t arm, std::size_t axis) noexcept;
  void watch_axis(std::size_t i, const protocol::Packet& req) noexcept;
  void watch_mode5(std::size_t i, const protocol::Packet& req) noexcept;

  ControllerWatchOptions options_;
  std::array<std::atomic<std::uint32_t>, kControllerErrorCount> counts_{};
  std::atomic<ControllerError> last_{ControllerError::none};
  std::atomic<int> last_arm_{0}, last_axis_{0};
  std::atomic<double> applied_percent_{0}, jump_{0};

  // Cycle thread.
  protocol::AxisMap map_{};
  bool have_map_ = false;
  protocol::Packet prev_{};
  protocol::Packet prev_reply_{};
  bool have_prev_ = false;
  std::array<bool, protocol::kMaxArms + 1> exit_asked_{};   // since the arm's open mode began
  std::array<std::int32_t, protocol::kMaxArms + 1> pc_asked_{};  // 505 or 508 asked by the PC
  std::array<bool, protocol::kMaxArms + 1> reported_{};     // this transition already named (per packet)
  double sent5_ = 0, applied5_ = 0;
};

}  // namespace axon::c4g::host
