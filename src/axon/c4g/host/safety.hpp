// The PC-side safety layer: applied by the Server to every reply, whoever built it.
//
// The manual leaves these checks to the PC (chapters "PC-side safety controls" and "Following
// error from PC"): the controller cannot verify a trajectory the PC generates. Per cycle:
//   - following error (modes 1 and 2, where the PC closes the loops): |D1 - D3| of the
//     controller's packet against the initialization packet's threshold; over it -> the PC asks
//     for a following-error stop (508) on that axis;
//   - current saturation (modes 1, 2, 9 and their standbys): the reply's D5 clamped to the
//     initialization packet's current limit (clamping is the manual's remedy, not a fault);
//   - stroke ends (optional per axis, motor turns): the position the reply would command (D1 in
//     modes 1 and 4, actual target + D1 in modes 5 and 7) must stay within [min, max];
//   - continuity (optional per axis): the commanded position may not move more than a set step
//     from one cycle to the next;
//   - anything not finite in a reply.
// A stroke-end, continuity or non-finite violation latches a fault, as does the Server reporting a
// controller exception, a late controller or a malformed packet. While a fault is latched every
// reply asks for drive off (505) on all axes, until the controller shows the drives off and all
// axes in mode 0; the fault stays latched (and the user's controller is no longer called) until
// reset(). A following-error fault answers 508 on the first offending axis instead.
//
// Allocation-free and noexcept. configure() and apply() belong to the cycle thread; trip(),
// reset() and the readers may be called from any thread.
#pragma once

#include "axon/c4g/protocol/axis_map.hpp"
#include "axon/c4g/protocol/init_packet.hpp"
#include "axon/c4g/protocol/packet.hpp"

#include <array>
#include <atomic>
#include <cstdint>
#include <limits>
#include <string_view>

namespace axon::c4g::host {

enum class FaultReason : std::uint8_t {
  none = 0,
  following_error,      // 508 on the axis
  stroke_end,           // commanded position outside the configured range
  discontinuity,        // commanded position jumped more than the allowed step
  not_finite,           // NaN or infinity in a reply
  controller_exception, // the user's controller threw
  controller_late,      // the user's controller overran its budget too many cycles in a row
  bad_packet,           // the controller sent a packet that does not decode
  user_request,         // Safety::trip() by the application
};
std::string_view to_string(FaultReason r) noexcept;

struct AxisLimits {
  float min_position = -std::numeric_limits<float>::infinity();  // stroke ends [motor turns]
  float max_position = std::numeric_limits<float>::infinity();
  float max_step = 0;  // max change of the commanded position per cycle [motor turns]; 0: unchecked
};

struct SafetyConfig {
  bool check_following_error = true;
  bool saturate_current = true;
  std::array<AxisLimits, protocol::kMaxAxes> axes{};  // in open order
  // Thresholds and limits from the initialization packet unless overridden here (> 0), in open order.
  std::array<float, protocol::kMaxAxes> following_error_override{};
  std::array<float, protocol::kMaxAxes> current_limit_override{};
};

struct SafetyCounters {
  std::atomic<std::uint64_t> currents_clamped{0};
  std::atomic<std::uint64_t> faults{0};
  std::atomic<std::uint64_t> drive_off_replies{0};
  std::atomic<std::uint64_t> following_error_replies{0};
};

class Safety {
 public:
  explicit Safety(const SafetyConfig& config = {});

  // From the initialization packet: thresholds and current limits in open order. Cycle thread.
  void configure(const protocol::InitPacket& init, const protocol::AxisMap& map) noexcept;

  // Applies a pending reset(); call before deciding whether the user's controller runs.
  void begin_cycle() noexcept;
  // Checks the reply against the controller's packet and fixes it in place (clamps currents, or
  // replaces it with a drive-off / following-error request when a fault is or becomes latched).
  // Returns the fault in force after this cycle (none when the reply went out as built).
  FaultReason apply(const protocol::Packet& request, protocol::Packet& reply) noexcept;

  // Latches a fault from outside the checks (controller exception, late, bad packet, user).
  void trip(FaultReason reason, int axis = -1) noexcept;
  // Clears a latched fault. Any thread; takes effect at the next cycle.
  void reset() noexcept { reset_requested_.store(true, std::memory_order_release); }

  [[nodiscard]] bool faulted() const noexcept { return reason() != FaultReason::none; }
  [[nodiscard]] FaultReason reason() const noexcept { return reason_.load(std::memory_order_acquire); }
  [[nodiscard]] int fault_axis() const noexcept { return fault_axis_.load(std::memory_order_relaxed); }
  [[nodiscard]] const SafetyCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] const std::array<float, protocol::kMaxAxes>& following_error_thresholds() const noexcept { return thresholds_; }
  [[nodiscard]] const std::array<float, protocol::kMaxAxes>& current_limits() const noexcept { return limits_; }

  // Writes the reply that asks for drive off on every axis (505).
  static void make_drive_off(const protocol::Packet& request, protocol::Packet& reply) noexcept;

 private:
  void latch(FaultReason r, int axis) noexcept;
  // The position the reply commands for axis i in its mode, if the mode commands one.
  static bool commanded_position(const protocol::Axis& req, const protocol::Axis& rep, float& out) noexcept;

  SafetyConfig config_;
  std::array<float, protocol::kMaxAxes> thresholds_{};
  std::array<float, protocol::kMaxAxes> limits_{};
  std::array<float, protocol::kMaxAxes> last_position_{};
  std::array<bool, protocol::kMaxAxes> have_last_{};
  std::atomic<FaultReason> reason_{FaultReason::none};
  std::atomic<int> fault_axis_{-1};
  std::atomic<bool> reset_requested_{false};
  bool drive_off_done_ = false;  // cycle thread
  SafetyCounters counters_;
};

}  // namespace axon::c4g::host
