// OpenModeApp: the phase machine the built-in applications share, driven through a small user
// application (as a user would write one), plus its envelope and sine helpers.
#include "axon/c4g/apps/open_mode.hpp"

#include "harness.hpp"

#include <cmath>

using namespace axon;
using namespace axon::c4g;
using namespace axon::c4g::apps;
using namespace axon::c4g::apps::test;
using protocol::code;
using protocol::Mode;

namespace {

// A mode-9 current sine on the six axes of arm 1, written as user code on OpenModeApp.
class SineCurrent final : public OpenModeApp {
 public:
  // open_s: fade out after this long (0: at a stop request).
  explicit SineCurrent(bool rearm = false, double open_s = 0)
      : OpenModeApp({.app = "sine", .waiting = "waiting", .running = "running", .mode = "9", .ramp_s = 0.02, .rearm = rearm}),
        open_s_(open_s) {
    sine_.configure({1.0}, {5.0}, 6);
  }
  [[nodiscard]] std::string_view name() const noexcept override { return "sine"; }

 protected:
  void step(const host::CycleContext& ctx, host::ReplyBuilder& reply) override {
    const Turn turned = turn(gate_for(ctx.request, 0, 6, code(Mode::mode9)), reply, 1);
    if (turned == Turn::skip) return;
    if (turned == Turn::start) started();
    const double t = advance(0.002);
    if (phase() == Phase::running && (stop_requested() || (open_s_ > 0 && t >= open_s_ - 1e-9))) start_fade();
    const double env = envelope().step(0.002);
    if (envelope().faded()) set_phase(Phase::exiting);
    for (std::size_t j = 0; j < 6; ++j) reply.axis(j).d5 = static_cast<float>(env * sine_.value(j, t));
    if (phase() == Phase::exiting) exit_from_open(reply, 1);
  }

 private:
  SineExcitation sine_;
  double open_s_;
};

TEST(OpenMode, PerAxisOptions) {
  EXPECT_EQ(per_axis({}, 3, 0.5), 0.5);
  EXPECT_EQ(per_axis({2.0}, 3, 0.5), 2.0);       // one value: every axis
  EXPECT_EQ(per_axis({1.0, 2.0}, 1, 0.5), 2.0);
  EXPECT_EQ(per_axis({1.0, 2.0}, 4, 0.5), 0.0);  // missing axes
  EXPECT_EQ(per_axis({1.0, 2.0}, 4, 0.5, 7.0), 7.0);
}

TEST(OpenMode, EnvelopeFadesInAndOutFromWhereItIs) {
  Envelope e(0.01);  // 5 cycles of 2 ms
  for (int k = 0; k < 3; ++k) e.step(0.002);
  EXPECT_NEAR(e.level(), 0.6, 1e-12);
  e.fade_out();  // during the fade in: down from 0.6, no jump to 1
  EXPECT_NEAR(e.step(0.002), 0.4, 1e-12);
  e.step(0.002);
  EXPECT_FALSE(e.faded());
  e.step(0.002);
  EXPECT_TRUE(e.faded());
  EXPECT_EQ(e.level(), 0.0);
  Envelope at_once;
  EXPECT_EQ(at_once.step(0.002), 1.0);
  at_once.fade_out();
  EXPECT_EQ(at_once.step(0.002), 0.0);
  EXPECT_TRUE(at_once.faded());
}

TEST(OpenMode, SineExcitationPerAxis) {
  SineExcitation s;
  s.configure({0.5, 1.0}, {}, 3);
  EXPECT_EQ(s.frequency(2), SineExcitation::kDefaultFrequencyHz);
  EXPECT_EQ(s.amplitude(2), 0.0);
  EXPECT_NEAR(s.value(1, 1.0), 0.0, 1e-12);  // sin(pi)
  EXPECT_NEAR(s.value(1, 0.5), 1.0, 1e-12);  // sin(pi / 2)
  EXPECT_NEAR(s.value(0, 0.5), 0.5, 1e-12);  // one amplitude per axis
}

TEST(OpenMode, WaitsRunsFadesExitsAndIsDoneAtModeZero) {
  SineCurrent app;
  Harness h;
  h.start(app);
  h.set_modes(code(Mode::mode0));
  h.run(app);
  EXPECT_EQ(app.phase(), Phase::waiting);
  EXPECT_EQ(app.phase_text(), "waiting");
  h.set_modes(code(Mode::mode9));
  for (int k = 0; k < 50; ++k) h.run(app);
  EXPECT_EQ(app.phase(), Phase::running);
  EXPECT_EQ(app.runs(), 1u);
  EXPECT_NEAR(app.elapsed_s(), 0.1, 1e-9);
  EXPECT_NE(h.rep.axes[0].d5, 0.0f);
  app.request_stop();
  int k = 0;
  for (; k < 100 && !h.exit_requested(); ++k) h.run(app);
  EXPECT_EQ(k, 10);  // 0.02 s of fade at 2 ms
  EXPECT_EQ(app.phase(), Phase::exiting);
  EXPECT_EQ(h.rep.axes[0].d5, 0.0f);
  h.run(app);  // still in mode 9: the exit is repeated, the reply stays safe
  EXPECT_TRUE(h.exit_requested());
  h.set_modes(code(Mode::mode0));
  h.run(app);
  EXPECT_EQ(app.phase(), Phase::done);
  EXPECT_TRUE(app.finished());
  EXPECT_FALSE(app.has_error());
  bool done_noted = false;
  for (const auto& e : app.drain_events())
    if (e.kind == EventKind::note && app.describe(e) == "sine: done, the arm is back in mode 0") done_noted = true;
  EXPECT_TRUE(done_noted);
}

TEST(OpenMode, LeavingTheModeRefusesAndAsksForTheExitWhileInIt) {
  SineCurrent app;
  Harness h;
  h.start(app);
  h.set_modes(code(Mode::mode9));
  for (int k = 0; k < 5; ++k) h.run(app);
  h.set_modes(code(Mode::mode0));
  h.run(app);
  EXPECT_EQ(app.phase(), Phase::refused);
  EXPECT_NE(app.error().find("sine: the controller left mode 9"), std::string::npos) << app.error();
  h.set_modes(code(Mode::mode9));
  h.run(app);
  EXPECT_TRUE(h.exit_requested());
  EXPECT_EQ(h.rep.axes[0].d5, 0.0f);
  EXPECT_FALSE(app.finished());
}

TEST(OpenMode, RearmServesTheModeAgainAndNeverFinishes) {
  SineCurrent app(true, 0.01);
  Harness h;
  h.start(app);
  for (int run = 0; run < 2; ++run) {
    h.set_modes(code(Mode::mode9));
    for (int k = 0; k < 25; ++k) h.run(app);
    EXPECT_TRUE(h.exit_requested());
    h.set_modes(code(Mode::mode0));
    h.run(app);
    EXPECT_EQ(app.phase(), Phase::done);
    EXPECT_FALSE(app.finished());
    h.run(app);
    EXPECT_EQ(app.phase(), Phase::waiting);
  }
  // A stop request keeps it from starting again.
  app.request_stop();
  h.set_modes(code(Mode::mode9));
  h.run(app);
  EXPECT_EQ(app.phase(), Phase::waiting);
  EXPECT_EQ(app.runs(), 2u);
}

}  // namespace
