// The in-process virtual CAN bus: a medium with any number of attached nodes (Bus endpoints).
//
// Every frame a node sends reaches every other node (never the sender). Each node transmits its
// own frames in order; when several nodes have a frame pending, the one with the lowest
// arbitration key (can/wire.hpp) goes first, as on the real bus. With the wire model on, each
// frame occupies the medium for its exact bit time at the configured bitrate; the medium keeps
// its busy time and, when pacing is on, delivers frames in real time. A fault plan can drop,
// delay, duplicate or corrupt chosen frames.
//
// All nodes of one medium share its executor (single-threaded, like every Bus).
#pragma once

#include "axon/can/bus.hpp"
#include "axon/can/fault_plan.hpp"
#include "axon/can/provider.hpp"

#include <map>
#include <memory>
#include <string>

namespace axon::can {

struct WireModel {
  bool enabled = false;                      // account exact bit times (busy time, load)
  std::uint32_t bitrate = kDefaultBitrate;   // bits per second
  bool pace_realtime = false;                // deliver each frame only after its bit time has elapsed
                                             // (implies the accounting of `enabled`)
};

struct VirtualBusStats {
  std::uint64_t frames = 0;         // frames that won arbitration and went on the medium
  std::uint64_t bits = 0;           // their exact wire bits
  core::Duration busy{0};           // bits / bitrate, summed (wire model on)
  std::uint64_t arbitration_rounds_contended = 0;  // rounds where more than one node had a frame pending
  std::uint64_t fault_dropped = 0;
  std::uint64_t fault_delayed = 0;
  std::uint64_t fault_duplicated = 0;
  std::uint64_t fault_corrupted = 0;
  // Pacing: how much later than their scheduled end frames were handed over (the process woke up
  // late), summed and at most. Large figures mean the machine, not the wire, set the pace.
  core::Duration lateness{0};
  core::Duration max_lateness{0};
  core::TimePoint created{};
};

class VirtualBus : public std::enable_shared_from_this<VirtualBus> {
 public:
  // Throws axon::Exception (CanErrc::bad_spec) for bitrate 0.
  static std::shared_ptr<VirtualBus> create(asio::any_io_executor ex, std::string name, WireModel wire = {});
  ~VirtualBus();

  // A new node on this medium. The node keeps the medium alive; closing or destroying it detaches
  // it and discards the frames it still had queued. options.bitrate is set to the medium's.
  // An empty name becomes "BUS#N".
  std::unique_ptr<Bus> attach(std::string node_name = {}, BusOptions options = {});

  void set_fault_plan(FaultPlan plan);
  [[nodiscard]] const std::string& name() const noexcept;
  [[nodiscard]] const WireModel& wire() const noexcept;
  [[nodiscard]] const VirtualBusStats& stats() const noexcept;
  [[nodiscard]] std::size_t node_count() const noexcept;
  // busy / elapsed since creation; needs the wire model. A frame counts in full from the moment
  // it goes on the wire. With pacing this stays at or near 1 at most; without pacing the virtual
  // medium can carry more than a real bus would, and the figure then exceeds 1.
  [[nodiscard]] double load(core::TimePoint now) const noexcept;

  struct Impl;

 private:
  explicit VirtualBus(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// Named virtual buses: what `axon can bridge` and the simulators serve.
class VirtualBusRegistry final : public BusProvider {
 public:
  explicit VirtualBusRegistry(asio::any_io_executor ex) : executor_(std::move(ex)) {}
  // Adds a medium (CanErrc::bad_spec if the name is empty or taken, or the bitrate is 0).
  Result<std::shared_ptr<VirtualBus>> add(std::string name, WireModel wire = {});
  [[nodiscard]] std::shared_ptr<VirtualBus> find(std::string_view name) const;
  Result<std::unique_ptr<Bus>> open(std::string_view channel, BusOptions options = {}) override;
  [[nodiscard]] std::vector<std::string> channels() const override;

 private:
  asio::any_io_executor executor_;
  std::vector<std::pair<std::string, std::shared_ptr<VirtualBus>>> buses_;
};

}  // namespace axon::can
