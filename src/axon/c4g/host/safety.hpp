// The PC-side safety layer: applied by the Server to every reply, whoever built it.
//
// The manual leaves these checks to the PC (chapters "PC-side safety controls" and "Following
// error from PC"): the controller cannot verify a trajectory the PC generates, so in every mode
// where the PC generates or changes the motion the PC must keep the robot inside its stroke ends
// and its references continuous. All checks are on by default. Per cycle:
//   - following error: |D1 - D3| of the controller's packet against the initialization packet's
//     threshold, in modes 1 and 2 (the PC closes the loops: mandatory) and 4 and 5 (the PC
//     generates the trajectory: the manual suggests it as a redundant check); over it -> the PC
//     asks for a following-error stop (508) on that axis;
//   - current saturation (modes 1, 2, 9 and their standbys): the reply's D5 clamped to the
//     initialization packet's current limit (clamping is the manual's remedy, not a fault);
//   - stroke ends: the position the reply commands (D1 in modes 1 and 4, the controller's target
//     D1 + the reply's increment D1 in modes 5 and 7), or the actual position D3 where the PC only
//     contributes (2, 8, 9), must stay within the joint's range at the link (SafetyConfig::joints,
//     degrees, converted through the arm's transmission ratios, influence coefficients and
//     calibration constants of the initialization packet; default +-180 deg) and within the
//     optional motor-turn ranges of SafetyConfig::axes; the initialization packet carries no
//     stroke ends, so the robot's own ranges must be set here;
//   - continuity: a commanded position may not move more than a step per cycle (default
//     max_motor_speed x the period): from the previous command, and on entering the mode from the
//     controller's own target D1 (a trajectory must start where the robot is);
//   - anything not finite in a reply.
// A stroke-end, continuity or non-finite violation latches a fault, as does the Server reporting a
// controller exception, a late controller or a malformed packet. While a fault is latched every
// reply asks for drive off (505, the manual's "DRIVE OFF request") on all axes, until the
// controller shows the drives off and all axes in mode 0; the fault stays latched (and the user's
// controller is no longer called) until reset(). A following-error fault answers 508 on the first
// offending axis instead.
//
// The following error |D1 - D3| of every open axis is also kept for readers on other threads (a
// page): the latest cycle's and the largest since the axis entered the mode it is in, in relaxed
// atomics the cycle writes, whatever the mode and whether or not the check is on.
//
// Allocation-free and noexcept. configure() and apply() belong to the cycle thread; trip(),
// reset() and the readers may be called from any thread.
#pragma once

#include "axon/c4g/protocol/axis_map.hpp"
#include "axon/c4g/protocol/init_packet.hpp"
#include "axon/c4g/protocol/packet.hpp"
#include "axon/core/error.hpp"

#include <array>
#include <atomic>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <string_view>

namespace axon::c4g::host {

enum class FaultReason : std::uint8_t {
  none = 0,
  following_error,      // 508 on the axis
  stroke_end,           // commanded position outside the configured range
  discontinuity,        // commanded position jumped more than the allowed step
  not_finite,           // NaN or infinity in a reply
  unused_field,         // a reply field the mode does not use is not zero (ServerOptions::verify_reply_fields)
  controller_exception, // the user's controller threw
  controller_late,      // the user's controller overran its budget too many cycles in a row
  bad_packet,           // the controller sent a packet that does not decode
  user_request,         // Safety::trip() by the application
};
std::string_view to_string(FaultReason r) noexcept;


// Motor-side limits of one open axis (the controller's units), on top of the joint ranges.
struct AxisLimits {
  float min_position = -std::numeric_limits<float>::infinity();  // stroke ends [motor turns]; infinite: none
  float max_position = std::numeric_limits<float>::infinity();
  float max_step = 0;  // max change of the commanded position per cycle [motor turns]; 0: the default
};

// A joint's stroke ends at the link [deg], as a robot's data sheet gives them.
struct JointRange {
  double min_deg = -180.0;
  double max_deg = 180.0;
};

struct SafetyConfig {
  bool check_following_error = true;  // modes 1, 2, 4, 5
  bool saturate_current = true;
  bool check_stroke_ends = true;
  bool check_continuity = true;
  // Stroke ends per arm and logical axis, [arm-1][axis-1] (default +-180 deg for every joint).
  std::array<std::array<JointRange, protocol::kAxesPerArm>, protocol::kMaxArms> joints{};
  // The default continuity step: this speed times the controller's period [motor turns/s].
  double max_motor_speed = 100.0;
  std::array<AxisLimits, protocol::kMaxAxes> axes{};  // in open order
  // Thresholds and limits from the initialization packet unless overridden here (> 0), in open order.
  std::array<float, protocol::kMaxAxes> following_error_override{};
  std::array<float, protocol::kMaxAxes> current_limit_override{};
};

// "AXIS=MIN:MAX" or "ARM.AXIS=MIN:MAX" (degrees at the link; arm 1..4, axis 1..10; the arm
// defaults to default_arm), as `axon c4g serve --stroke-end` takes it; sets config.joints.
Result<void> parse_stroke_end(std::string_view text, std::size_t default_arm, SafetyConfig& config);

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
  // A latched fault has been obeyed: the controller shows the drives off and every axis in mode 0.
  [[nodiscard]] bool obeyed() const noexcept { return faulted() && drive_off_done_.load(std::memory_order_acquire); }
  [[nodiscard]] const SafetyCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] const std::array<float, protocol::kMaxAxes>& following_error_thresholds() const noexcept { return thresholds_; }
  [[nodiscard]] const std::array<float, protocol::kMaxAxes>& current_limits() const noexcept { return limits_; }

  // The continuity step in force per open axis [motor turns per cycle] (after configure()).
  [[nodiscard]] const std::array<float, protocol::kMaxAxes>& max_steps() const noexcept { return steps_; }

  // |D1 - D3| of open axis i in the latest packet [motor turns] (0 before any), and the largest since
  // the axis entered its present mode. Any thread; NaN when the packet carried one.
  [[nodiscard]] float following_error(std::size_t i) const noexcept {
    return i < protocol::kMaxAxes ? fe_now_[i].load(std::memory_order_relaxed) : 0.0f;
  }
  [[nodiscard]] float following_error_peak(std::size_t i) const noexcept {
    return i < protocol::kMaxAxes ? fe_peak_[i].load(std::memory_order_relaxed) : 0.0f;
  }
  // The modes whose following error is checked against the threshold (1, 2, 4, 5 and their standbys).
  static bool checks_following_error(std::int32_t mode) noexcept;

  // Writes the reply that asks for drive off on every axis (505).
  static void make_drive_off(const protocol::Packet& request, protocol::Packet& reply) noexcept;

 private:
  // One arm's conversion from motor turns to link radians, for the stroke ends (fixed size).
  struct ArmCheck {
    std::size_t axes = 0;                              // logical axes 1..axes in the transform
    std::array<int, protocol::kAxesPerArm> open{};     // open index of logical axis k+1, -1: not open
    std::array<double, protocol::kAxesPerArm> q0{};    // calibration [motor turns]
    std::array<std::array<double, protocol::kAxesPerArm>, protocol::kAxesPerArm> kr_inv{};
    std::array<double, protocol::kAxesPerArm> min_rad{}, max_rad{};
  };
  void latch(FaultReason r, int axis) noexcept;
  // The following errors of this packet into fe_now_ / fe_peak_.
  void track_following_errors(std::span<const protocol::Axis> request) noexcept;
  // The checks of one axis; false once a fault is latched.
  bool check_axis(std::size_t i, const protocol::Axis& q, protocol::Axis& r) noexcept;
  // The joint ranges of every arm with a checked axis; false once a fault is latched.
  bool check_joints(const protocol::Packet& request) noexcept;
  void configure_arms(const protocol::InitPacket& init, const protocol::AxisMap& map) noexcept;
  void set_steps(double period_s) noexcept;
  // The position the reply commands for axis i in its mode, if the mode commands one.
  static bool commanded_position(const protocol::Axis& req, const protocol::Axis& rep, float& out) noexcept;

  SafetyConfig config_;
  std::array<float, protocol::kMaxAxes> thresholds_{};
  std::array<float, protocol::kMaxAxes> limits_{};
  std::array<float, protocol::kMaxAxes> steps_{};
  std::array<float, protocol::kMaxAxes> last_position_{};
  std::array<bool, protocol::kMaxAxes> have_last_{};
  // This cycle: the position each axis is checked at (commanded or actual), and whether it is.
  std::array<float, protocol::kMaxAxes> position_{};
  std::array<bool, protocol::kMaxAxes> checked_{};
  std::array<ArmCheck, protocol::kMaxArms> arms_{};
  std::atomic<FaultReason> reason_{FaultReason::none};
  std::atomic<int> fault_axis_{-1};
  std::atomic<bool> reset_requested_{false};
  std::atomic<bool> drive_off_done_{false};  // written by the cycle thread
  SafetyCounters counters_;
  std::array<std::atomic<float>, protocol::kMaxAxes> fe_now_{}, fe_peak_{};
  std::array<std::int32_t, protocol::kMaxAxes> fe_mode_{};  // the mode each peak belongs to (cycle thread)
  std::array<float, protocol::kMaxAxes> fe_peak_local_{};
};

}  // namespace axon::c4g::host
