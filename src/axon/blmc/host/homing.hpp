// Homing on the encoder index: each motor in the set moves slowly (a position target ramping at
// `speed` under a small PD with a low current limit) until the board reports the next index tick
// for it (message 0x060, enabled by SEND_ALL or SEND_ENC_INDEX), then holds at the index position.
// The index position is the motor's offset: joint zero = index position (+ a mechanical offset
// the user knows). A motor that travels `max_travel_rev` without an index fails.
//
// Runs as a Controller inside the ControlLoop, so homing gets the same real-time cycle and the
// same safety supervision as any other control.
#pragma once

#include "axon/blmc/host/control_loop.hpp"
#include "axon/blmc/host/homing_options.hpp"

#include <array>
#include <atomic>
#include <vector>

namespace axon::blmc::host {

class HomingController final : public Controller {
 public:
  // Throws axon::Exception (HostErrc::invalid_argument, in words) unless the speed is finite and
  // not 0, kp, the current limit and the travel are > 0 and kd is >= 0.
  HomingController(std::size_t boards, HomingOptions options);

  void start(const ControlInput& in) noexcept override;
  void update(const ControlInput& in, std::span<MotorPair> currents) noexcept override;

  // True once every motor found its index or failed (safe to read from any thread).
  [[nodiscard]] bool done() const noexcept { return done_.load(std::memory_order_acquire); }
  // Read after done() or after the loop stopped.
  [[nodiscard]] const MotorHoming& result(std::size_t board, int motor) const noexcept {
    return motors_[board * 2 + static_cast<std::size_t>(motor)];
  }
  [[nodiscard]] bool all_found() const noexcept;

 private:
  HomingOptions options_;
  core::TimePoint t0_{};
  std::vector<MotorHoming> motors_;
  std::vector<std::uint64_t> index_seen_;
  std::atomic<bool> done_{false};
};

}  // namespace axon::blmc::host
