// `handover`: serves every open phase a robot program enters, one after the other, as in the
// manual's example of handing the motion over between the controller and the PC (chapter 13:
// GO OPEN TYPE A, WAIT FOR PC, MOVE, GO OPEN TYPE B, ..., data/c4g/handover.yaml).
//
// Each time the arm enters an open mode the app serves it with the matching part and ends it with
// exit from open; then it waits for the next phase:
//   - mode 4 or 5: a trajectory (StreamApp with re-arm: each phase plays the whole trajectory,
//     start-point check included; use a relative trajectory when the phases start at different
//     points), or without a trajectory a hold of hold_s (mode 4 keeps the last target, mode 5 adds
//     nothing) before the exit;
//   - mode 7: a correction (CorrectApp with re-arm: a sine, values from a file or a live feed), or
//     without one a zero correction for hold_s;
//   - other open modes (1, 2, 8, 9): not served here: noted, and exit from open at once.
// The app never finishes by itself: the program's end (504), a stop request or a signal ends it.
// The parts' events (their milestones and exit requests) come out of drain_events() with the app's.
#pragma once

#include "axon/c4g/apps/app.hpp"
#include "axon/c4g/apps/correct.hpp"
#include "axon/c4g/apps/stream.hpp"

#include <memory>
#include <optional>
#include <vector>

namespace axon::c4g::apps {

struct HandoverOptions {
  std::size_t arm = 1;
  // Modes 4/5: the stream settings (its trajectory, relative, tolerances; mode and arm are set
  // here); nullopt: hold.
  std::optional<StreamOptions> stream;
  // Mode 7: the correction (exactly one source, or none: a zero correction of hold_s).
  std::optional<CorrectOptions> correct;
  double hold_s = 0.5;
};

class HandoverApp final : public App {
 public:
  enum : std::int32_t {
    kNoteHoldOver = 1,   // hold time over: exit from open
    kNoteEntered = 100,  // + mode: the arm entered an open mode
    kNoteUnserved = 200, // + mode: no part for this mode: exit from open
    kPartBase = 1000,    // (part index + 1) x kPartBase + the part's own note code
  };

  explicit HandoverApp(HandoverOptions options);
  [[nodiscard]] std::string_view name() const noexcept override { return "handover"; }
  [[nodiscard]] std::string status() const override;
  [[nodiscard]] std::string summary() const override;
  std::vector<Event> drain_events() override;
  // Open phases entered so far (any thread).
  [[nodiscard]] std::uint64_t phases() const noexcept { return phases_.load(std::memory_order_relaxed); }
  [[nodiscard]] const StreamApp* stream(int mode) const noexcept { return mode == 4 ? stream4_ : mode == 5 ? stream5_ : nullptr; }
  [[nodiscard]] const CorrectApp& correct() const noexcept { return *correct_; }

 protected:
  void setup(const protocol::InitPacket& init, const protocol::AxisMap& axes) override;
  void step(const host::CycleContext& ctx, host::ReplyBuilder& reply) override;
  void silence() noexcept override;
  [[nodiscard]] std::string note_text(std::int32_t code) const override;

 private:
  HandoverOptions options_;
  std::vector<std::unique_ptr<App>> parts_;
  StreamApp* stream4_ = nullptr;
  StreamApp* stream5_ = nullptr;
  CorrectApp* correct_ = nullptr;
  std::atomic<std::uint64_t> phases_{0};
  std::atomic<std::int32_t> current_{0};  // mode of the phase being served (0: none)
  // Cycle thread.
  double period_s_ = 0.001;
  std::uint64_t held_ = 0;
  bool hold_noted_ = false;
};

}  // namespace axon::c4g::apps
