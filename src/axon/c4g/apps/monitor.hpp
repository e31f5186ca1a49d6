// `monitor` (mode 0): the PC only answers; the app reports what the controller does. Replies are the
// server's safe reply (every axis echoes its mode, data zero). The status shows each axis's mode and
// actual position (motor turns, and link degrees for arms whose axes convert), events log mode
// changes and drives on/off; with `axon c4g serve --moni` every cycle goes to a CSV view (moni.hpp).
#pragma once

#include "axon/c4g/apps/app.hpp"

#include <atomic>
#include <optional>

namespace axon::c4g::apps {

class MonitorApp final : public App {
 public:
  [[nodiscard]] std::string_view name() const noexcept override { return "monitor"; }
  [[nodiscard]] std::string status() const override;
  [[nodiscard]] std::string summary() const override;
  // Cycles the controller spent with each arm's drives on (any thread).
  [[nodiscard]] std::uint64_t drives_on_cycles() const noexcept { return drives_on_cycles_.load(std::memory_order_relaxed); }
  [[nodiscard]] std::uint64_t non_mode0_cycles() const noexcept { return non_mode0_cycles_.load(std::memory_order_relaxed); }

 protected:
  void setup(const protocol::InitPacket& init, const protocol::AxisMap& axes) override;
  void step(const host::CycleContext& ctx, host::ReplyBuilder& reply) override;

 private:
  std::optional<ArmView> arm1_;  // set in setup (before cycles), read by status(): guarded by ready_
  std::atomic<bool> ready_{false};
  std::atomic<std::uint64_t> drives_on_cycles_{0};
  std::atomic<std::uint64_t> non_mode0_cycles_{0};
};

}  // namespace axon::c4g::apps
