// HandoverApp: every open phase of a program served in turn, with synthetic packets.
#include "axon/c4g/apps/handover.hpp"

#include "harness.hpp"

using namespace axon::c4g;
using namespace axon::c4g::apps;
using namespace axon::c4g::apps::test;
using protocol::code;
using protocol::Mode;

namespace {

// Runs cycles in the current modes until the app asks for exit (or max); cycles run.
int until_exit(App& app, Harness& h, int max = 2000) {
  for (int k = 0; k < max; ++k) {
    h.run(app);
    if (h.exit_requested()) return k + 1;
  }
  return max;
}

void leave(App& app, Harness& h, Mode standby) {
  h.set_modes(code(standby));
  h.run(app);
  h.set_modes(code(Mode::mode0));
  h.run(app);
  h.run(app);
}

}  // namespace

TEST(HandoverApp, ServesEachPhaseAndReArms) {
  HandoverOptions o;
  StreamOptions s;
  s.trajectory = std::make_shared<Trajectory>(
      Trajectory::from_rows({0.0, 0.2}, {{0, 0, 0, 0, 0, 0}, {2 * kDeg, 0, 0, 0, 0, 0}}).value());
  s.relative = true;
  s.hold_s = 0.01;
  o.stream = s;
  CorrectOptions c;
  c.amplitude_rad = {0.5 * kDeg};
  c.open_time_s = 0.1;
  c.ramp_s = 0.02;
  o.correct = c;
  HandoverApp app(o);
  Harness h;
  h.start(app);
  h.place_at_link({0, 0, 0, 0, 0, 0});
  h.set_modes(code(Mode::mode0));
  h.run(app);
  for (int round = 0; round < 2; ++round) {
    h.set_modes(code(Mode::mode4));
    EXPECT_EQ(until_exit(app, h), 100 + 5) << round;  // 0.2 s of rows, hold 0.01 s
    leave(app, h, Mode::mode4_standby);
    h.set_modes(code(Mode::mode7));
    const int n = until_exit(app, h);
    EXPECT_GT(n, 50);
    EXPECT_LT(n, 70);
    leave(app, h, Mode::mode7_standby_exit);
  }
  EXPECT_FALSE(app.has_error()) << app.error();
  EXPECT_FALSE(app.finished());
  EXPECT_EQ(app.phases(), 4u);
  EXPECT_EQ(app.stream(4)->runs(), 2u);
  EXPECT_EQ(app.correct().runs(), 2u);
  const auto events = event_texts(app);
  EXPECT_TRUE(contains(events, "handover: arm 1 entered open mode 4 (trajectory)"));
  EXPECT_TRUE(contains(events, "handover: arm 1 entered open mode 7 (correction)"));
  EXPECT_TRUE(contains(events, "stream: done"));
  EXPECT_TRUE(contains(events, "correct: done"));
}

TEST(HandoverApp, WithoutPartsHoldsThenExitsAndDoesNotServeMode1) {
  HandoverOptions o;
  o.hold_s = 0.02;  // 10 cycles
  HandoverApp app(o);
  Harness h;
  h.start(app);
  h.place_at_link({0, 0, 0, 0, 0, 0});
  h.set_modes(code(Mode::mode0));
  h.run(app);
  h.set_modes(code(Mode::mode4));
  EXPECT_EQ(until_exit(app, h), 10);
  EXPECT_FLOAT_EQ(h.rep.axes[0].d1, h.req.axes[0].d3);  // the safe reply's hold is untouched
  leave(app, h, Mode::mode4_standby);
  h.set_modes(code(Mode::mode1));
  EXPECT_EQ(until_exit(app, h), 1);
  const auto events = event_texts(app);
  EXPECT_TRUE(contains(events, "hold time over"));
  EXPECT_TRUE(contains(events, "no part serves mode 1"));
  EXPECT_FALSE(app.has_error());
}

TEST(HandoverApp, APartsErrorIsTheAppsError) {
  HandoverOptions o;
  StreamOptions s;
  s.trajectory = std::make_shared<Trajectory>(
      Trajectory::from_rows({0.0, 0.2}, {{30 * kDeg, 0, 0, 0, 0, 0}, {30 * kDeg, 0, 0, 0, 0, 0}}).value());
  o.stream = s;
  HandoverApp app(o);
  Harness h;
  h.start(app);
  h.place_at_link({0, 0, 0, 0, 0, 0});
  h.set_modes(code(Mode::mode4));
  h.run(app);
  EXPECT_TRUE(app.has_error());
  EXPECT_NE(app.error().find("start point"), std::string::npos) << app.error();
}
