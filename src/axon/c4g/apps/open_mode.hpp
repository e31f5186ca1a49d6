// What every application that serves an open mode of one arm shares: the phase machine (waiting
// for the mode, running, fading out, holding, exiting, done, refused), the fade envelope and the
// per-axis sine excitation. The built-in applications (contribute, correct, pid, stream) are
// written on it, and so can a user's own: derive from OpenModeApp, describe the mode in a Gate
// each cycle and let turn() take the common transitions, then write the reply for Turn::start and
// Turn::run (docs/library-c4g.md).
//
// The phase machine, per cycle (turn()):
//   - waiting:  every axis of the arm in the app's mode (Gate::entered) and no stop request ->
//               running (Turn::start: the run's clock and the envelope from zero; the app then
//               calls started(), which counts the run and notes it, or refuses);
//   - running / fading / holding / idle: the arm must stay in the mode (Gate::inside), else the
//               app refuses ("APP: the controller left mode M ...");
//   - exiting:  the app asked for exit from open; it is repeated while the arm is in the mode
//               (the standby codes on the way out are no refusal), and mode 0 on the arm's first
//               axis ends the run (done, note kNoteDone);
//   - done:     with re-arm, mode 0 makes the app wait for the mode again; else finished();
//   - refused:  the error is set (error()); exit from open is sent while the arm is in the mode.
// Phases other than these transitions are the app's: start_fade(), set_phase(holding/idle/exiting).
// Style::exiting_runs: the app keeps writing its reply while exiting (a trajectory holding its
// last target, a loop still closed) and adds the exit from open itself. Style::pc_closes_loops (modes
// 1 and 2: the reply carries currents the robot needs every cycle): mode 0 ends any phase, and a
// refusal sends no exit from open (the CLI drives off instead, App::drive_off_on_error()).
//
// Real time: turn(), advance(), start_fade() and the Envelope/SineExcitation calls neither
// allocate nor lock; the phase and the run's clock are atomics readable from any thread.
#pragma once

#include "axon/c4g/apps/app.hpp"

#include <atomic>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace axon::c4g::apps {

enum class Phase : std::uint8_t { waiting, running, fading, holding, idle, exiting, done, refused };
[[nodiscard]] std::string_view to_string(Phase p) noexcept;

// Axis j's value of a per-axis option: one value applies to every axis, a missing axis gets
// `missing`, an empty option gives `none`.
[[nodiscard]] double per_axis(const std::vector<double>& values, std::size_t j, double none, double missing = 0.0) noexcept;

// A linear fade in over ramp_s from 0 to 1, and (after fade_out()) back to 0 from wherever it is.
// No ramp: 1 at once, 0 at once.
class Envelope {
 public:
  explicit Envelope(double ramp_s = 0) noexcept : ramp_s_(ramp_s) {}
  // Starts over at `level` (0: fades in; 1: starts at full).
  void reset(double level = 0) noexcept { level_ = level, fading_ = false; }
  void fade_out() noexcept { fading_ = true; }
  // Advances one cycle of period_s and returns the level.
  double step(double period_s) noexcept;
  [[nodiscard]] double level() const noexcept { return level_; }
  [[nodiscard]] bool fading() const noexcept { return fading_; }
  // Faded out completely (level below 1e-9 after fade_out()).
  [[nodiscard]] bool faded() const noexcept { return fading_ && level_ < 1e-9; }

 private:
  double ramp_s_ = 0;
  double level_ = 0;
  bool fading_ = false;
};

// A sine per axis, A_j sin(2 pi f_j t), from per-axis options (per_axis(): one amplitude for every
// axis, missing axes 0; frequencies default to 0.5 Hz).
class SineExcitation {
 public:
  static constexpr double kDefaultFrequencyHz = 0.5;
  void configure(const std::vector<double>& amplitude, const std::vector<double>& frequency_hz, std::size_t axes) noexcept;
  [[nodiscard]] double value(std::size_t j, double t) const noexcept;
  [[nodiscard]] double amplitude(std::size_t j) const noexcept { return amplitude_[j]; }
  [[nodiscard]] double frequency(std::size_t j) const noexcept { return frequency_[j]; }
  [[nodiscard]] std::size_t axes() const noexcept { return axes_; }

 private:
  std::array<double, protocol::kAxesPerArm> amplitude_{}, frequency_{};
  std::size_t axes_ = 0;
};

class OpenModeApp : public App {
 public:
  // Note codes the phase machine emits; an app's own notes start at kFirstAppNote.
  enum : std::int32_t { kNoteStarted = 1, kNoteFading = 2, kNoteDone = 3, kFirstAppNote = 4 };

  [[nodiscard]] Phase phase() const noexcept { return phase_.load(std::memory_order_acquire); }
  // Done and not re-armed (App::finished).
  [[nodiscard]] bool finished() const noexcept override { return !style_.rearm && phase() == Phase::done; }
  // Runs started so far; the current run's time [s] (any thread).
  [[nodiscard]] std::uint64_t runs() const noexcept { return runs_.load(std::memory_order_relaxed); }
  [[nodiscard]] double elapsed_s() const noexcept { return elapsed_.load(std::memory_order_relaxed); }
  // "APP cycles N modes ... PHASE t=T s" (the phase in the app's words).
  [[nodiscard]] std::string status() const override;
  // The phase in the app's words (e.g. "correcting", "waiting for mode 7").
  [[nodiscard]] std::string_view phase_text() const noexcept;

  struct Style {
    std::string app;                // prefixes messages: "correct"
    std::string_view waiting;       // status while waiting: "waiting for mode 7"
    std::string_view running;       // status while running: "correcting"
    std::string_view mode;          // the mode in messages: "7", "1/2"
    double ramp_s = 0;              // the envelope's fade time
    bool fade_in = true;            // the envelope starts at 0 (else at full)
    bool rearm = false;             // serve the mode again after each run
    bool exiting_runs = false;      // the app writes its reply while exiting (header comment)
    bool pc_closes_loops = false;   // modes 1/2 (header comment)
  };

 protected:
  // Where the arm is this cycle, as the app judges it.
  struct Gate {
    bool present = false;   // the arm's axes are in the packet
    bool entered = false;   // every axis in the app's mode: a run may start
    bool inside = false;    // a run may go on (the mode, or what the app allows besides)
    bool at_rest = false;   // the arm's first axis in mode 0
    std::int32_t first_mode = 0;
  };
  // The usual gate: every axis of [first, first + count) in `mode` (inside = entered).
  [[nodiscard]] static Gate gate_for(const protocol::Packet& request, std::size_t first, std::size_t count,
                                     std::int32_t mode) noexcept;

  enum class Turn : std::uint8_t { skip, start, run };

  explicit OpenModeApp(Style style);

  // The app's set-up begins with this: false when the app is over for good (done without re-arm,
  // or refused); else the phase is waiting.
  bool begin_setup() noexcept;
  // fail() and the refused phase.
  void refuse(const char* format, ...) noexcept __attribute__((format(printf, 2, 3)));
  void set_phase(Phase p) noexcept { phase_.store(p, std::memory_order_release); }

  // The common transitions of this cycle (header comment). skip: the reply stays as it is (the
  // server's safe reply, an exit from open added where due); start: a run begins (reset the app's
  // state, then run it); run: the app writes its reply.
  Turn turn(const Gate& gate, host::ReplyBuilder& reply, std::size_t arm) noexcept;
  // A run began (after Turn::start): counts it and notes `code` (aux: the note's value).
  void started(std::int32_t code = kNoteStarted, std::int32_t aux = 0) noexcept;
  // The run's clock: one more cycle of period_s; returns the run's time.
  double advance(double period_s) noexcept;
  [[nodiscard]] double run_time() const noexcept { return t_; }
  // Fades the envelope out (phase fading, note kNoteFading); the app moves on to exiting once
  // envelope().faded().
  void start_fade() noexcept;
  Envelope& envelope() noexcept { return envelope_; }
  [[nodiscard]] const Style& style() const noexcept { return style_; }
  [[nodiscard]] std::string note_text(std::int32_t code) const override;

 private:
  Style style_;
  Envelope envelope_;
  std::atomic<Phase> phase_{Phase::waiting};
  std::atomic<std::uint64_t> runs_{0};
  std::atomic<double> elapsed_{0};
  std::uint64_t ticks_ = 0;  // cycle thread
  double t_ = 0;
};

}  // namespace axon::c4g::apps
