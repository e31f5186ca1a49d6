// A user's control law as a callable, served on one open mode of one arm with the phase machine of
// open_mode.hpp: the law writes the reply, the app decides when a run starts (every axis of the arm
// in the mode), fades it in and out (LawCycle::envelope), and when the PC leaves the mode (after
// open_time_s or a stop request: the envelope fades out, the law holds for settle_s, then exit
// from open; modes 2, 4', 7', ... end as the controller says).
//
// The law runs on the server's cycle thread, once per packet while a run is under way, and must
// follow the real-time rules: return well within the controller budget (ServerOptions::
// controller_budget, 400 us by default), no allocation, no locks, no I/O, no exceptions (one that
// escapes latches a server fault: drive off). Capture what it needs by reference or value when
// building the LawApp; read results from other threads through atomics.
//
// Modes 1 and 2 (the PC closes the loops): the law's reply carries the motor currents (D5) every
// cycle, also while the controller switches control over (T1..T3; LawCycle::switching tells,
// CycleContext::switching has the details); the run's clock and the envelope wait until the
// switch is done. A refusal there asks for drive off (App::drive_off_on_error()).
// Packets that stop during a run (the controller's communication error, a restart) refuse the run.
#pragma once

#include "axon/c4g/apps/open_mode.hpp"

#include <functional>
#include <optional>
#include <string>

namespace axon::c4g::apps {

struct LawOptions {
  std::size_t arm = 1;
  int mode = 1;             // the open mode served: 1, 2, 4, 5, 7, 8 or 9
  double open_time_s = 0;   // the PC leaves the mode after this long (0: at a stop request)
  double ramp_s = 0.2;      // the envelope's fade in and out
  double settle_s = 0.1;    // after the fade out, the law runs this long before the exit from open
  bool rearm = false;       // serve the mode again each time the program enters it
};

// One cycle as the law sees it.
struct LawCycle {
  const host::CycleContext& ctx;  // the controller's packet (per axis D1..D5, EXT1...), soft switching
  const ArmView& arm;             // the arm's open axes (first, count), period, link/motor transform
  double t = 0;                   // the run's time [s] (from 0 when the mode is entered and switched)
  double envelope = 0;            // 0..1: faded in at the start, out before leaving
  bool first = false;             // the run's first cycle (capture a hold point here)
  bool switching = false;         // modes 1/2: control is being handed over (T1..T3)
  bool leaving = false;           // the envelope fades out or the exit from open was asked
};

using Law = std::function<void(const LawCycle&, host::ReplyBuilder&)>;

class LawApp final : public OpenModeApp {
 public:
  // Throws axon::Exception (invalid_argument) for a mode the app cannot serve or no law.
  LawApp(LawOptions options, Law law, std::string name = "law");
  [[nodiscard]] std::string_view name() const noexcept override { return name_; }
  [[nodiscard]] bool drive_off_on_error() const noexcept override { return style().pc_closes_loops; }

 protected:
  void setup(const protocol::InitPacket& init, const protocol::AxisMap& axes) override;
  void step(const host::CycleContext& ctx, host::ReplyBuilder& reply) override;
  // Packets stopped during a run: refused (the robot's state is unknown from here).
  void silence() noexcept override;

 private:
  // Advances the run's clock and the envelope, and decides the fade and the exit.
  void schedule() noexcept;

  LawOptions options_;
  Law law_;
  std::string name_;
  std::optional<ArmView> view_;
  // Cycle thread.
  double settled_s_ = 0;
};

}  // namespace axon::c4g::apps
