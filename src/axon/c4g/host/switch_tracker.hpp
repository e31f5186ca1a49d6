// Soft control switching as the PC sees it (manual, chapter 12). The controller does not send its
// switching clock: the packets only show the modes. The PC infers, per axis, where the switch stands
// from the mode and the number of packets since that mode first appeared:
//   - the first packet in mode 1 or 2 (coming from any other code) starts a switch drive -> PC;
//   - the first packet in 1' (11) or 2' (12) starts a switch PC -> drive;
//   - elapsed = packets since then x the controller's period (initialization packet), evaluated with
//     the linear model (protocol::linear_switch) for the configured T1, T2, T3, which must match the
//     controller's;
//   - any other mode: no switch (interval none).
// The reply to packet k drives the robot during period k on the controller side, and the simulator
// starts its switching clock at the first period that uses the new mode, so the two sides agree
// packet for packet.
//
// Pure and allocation-free: update() once per cyclic packet on the cycle thread (the Server does
// it before calling the user's Controller and hands the tracker over in CycleContext::switching).
#pragma once

#include "axon/c4g/protocol/packet.hpp"
#include "axon/c4g/protocol/soft_switch.hpp"

#include <array>
#include <cstddef>
#include <cstdint>

namespace axon::c4g::host {

class SwitchTracker {
 public:
  explicit SwitchTracker(protocol::SwitchTimes times = {}) noexcept : times_(times) {}

  void set_times(protocol::SwitchTimes times) noexcept { times_ = times; }
  [[nodiscard]] const protocol::SwitchTimes& times() const noexcept { return times_; }
  // Forgets every switch (a new initialization packet).
  void reset() noexcept;
  // One cyclic packet from the controller; period_s is the controller's period.
  void update(const protocol::Packet& request, double period_s) noexcept;

  [[nodiscard]] std::size_t count() const noexcept { return count_; }
  // Where axis `open_index`'s switch stands for the current packet.
  [[nodiscard]] const protocol::SwitchSample& axis(std::size_t open_index) const noexcept {
    return samples_[open_index < protocol::kMaxAxes ? open_index : 0];
  }
  // The PC regulator's reducer factor for the axis: eta entering modes 1/2, rho leaving them, 1 in
  // modes 1/2 once the switch is done, 0 in any other mode.
  [[nodiscard]] double pc_gain(std::size_t open_index) const noexcept { return axis(open_index).pc_gain(); }

 private:
  protocol::SwitchTimes times_;
  std::size_t count_ = 0;
  std::array<std::int32_t, protocol::kMaxAxes> prev_mode_{};
  std::array<std::uint64_t, protocol::kMaxAxes> packets_{};  // packets since the switch started
  std::array<bool, protocol::kMaxAxes> seen_{};
  std::array<protocol::SwitchSample, protocol::kMaxAxes> samples_{};
};

}  // namespace axon::c4g::host
