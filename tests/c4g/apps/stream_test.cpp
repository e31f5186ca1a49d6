#include "axon/c4g/apps/stream.hpp"

#include "axon/c4g/apps/app_factory.hpp"

#include "harness.hpp"

#include <cmath>

using namespace axon::c4g;
using namespace axon::c4g::apps;
using namespace axon::c4g::apps::test;
using protocol::code;
using protocol::Mode;

namespace {

// Axis 1 from 0 to 10 deg over 1 s, then back to 5 deg at 1.5 s; the others at 0 (wrist at 0).
std::shared_ptr<const Trajectory> ramp() {
  return std::make_shared<Trajectory>(
      Trajectory::parse("# units: deg\nt,j1,j2,j3,j4,j5,j6\n0,0,0,0,0,0,0\n1,10,0,0,0,0,0\n1.5,5,0,0,0,0,0\n", "ramp").value());
}

StreamOptions options(int mode, std::shared_ptr<const Trajectory> t = ramp()) {
  StreamOptions o;
  o.trajectory = std::move(t);
  o.mode = mode;
  o.hold_s = 0.01;
  return o;
}


// Runs the app in `mode` until it asks to leave the open mode (or max cycles); returns cycles run.
int run_until_exit(StreamApp& app, Harness& h, int max_cycles = 2000) {
  for (int k = 0; k < max_cycles; ++k) {
    h.run(app);
    if (h.exit_requested()) return k + 1;
  }
  return max_cycles;
}

}  // namespace

TEST(StreamApp, Mode4StreamsAbsoluteMotorTargetsThenExits) {
  StreamApp app(options(4));
  Harness h;
  h.start(app);
  EXPECT_EQ(app.table_rows(), 751u);  // 1.5 s at 2 ms, both ends included
  h.place_at_link({0, 0, 0, 0, 0, 0});
  h.set_modes(code(Mode::mode0));
  h.run(app);
  EXPECT_EQ(app.phase(), Phase::waiting);
  h.set_modes(code(Mode::mode4));
  h.run(app);  // starts: row 0, then advances to row 1
  EXPECT_EQ(app.phase(), Phase::running);
  EXPECT_NEAR(h.rep.axes[0].d1, h.motor_axis1(10 * kDeg * 0.002), 1e-4);
  for (int k = 0; k < 249; ++k) h.run(app);  // row 250: t = 0.5 s
  EXPECT_NEAR(h.rep.axes[0].d1, h.motor_axis1(5 * kDeg), 1e-4);
  // D2 is the change per cycle (delta motor turns): 10 deg/s on the link.
  EXPECT_NEAR(h.rep.axes[0].d2, h.motor_axis1(10 * kDeg * 0.002) - h.motor_axis1(0), 1e-5);
  // Axis 2 did not move.
  EXPECT_NEAR(h.rep.axes[1].d1, h.transform().calibration()[1], 1e-6);
  const int more = run_until_exit(app, h);
  EXPECT_EQ(more, 500 + 5);  // the rest of the table, then hold_s (5 cycles)
  EXPECT_NEAR(h.rep.axes[0].d1, h.motor_axis1(5 * kDeg), 1e-4);
  // 4': the last target is held; then mode 0 finishes.
  h.set_modes(code(Mode::mode4_standby));
  h.run(app);
  EXPECT_NEAR(h.rep.axes[0].d1, h.motor_axis1(5 * kDeg), 1e-4);
  EXPECT_FALSE(app.finished());
  h.set_modes(code(Mode::mode0));
  h.run(app);
  EXPECT_TRUE(app.finished());
  EXPECT_FALSE(app.has_error());
  const auto events = event_texts(app);
  EXPECT_TRUE(contains(events, "stream: trajectory started"));
  EXPECT_TRUE(contains(events, "arm 1: exit from open sent"));
  EXPECT_TRUE(contains(events, "stream: done"));
}

TEST(StreamApp, Mode5IncrementsAddUpToTheTrajectory) {
  StreamApp app(options(5));
  Harness h;
  h.start(app);
  h.place_at_link({0, 0, 0, 0, 0, 0});
  h.set_modes(code(Mode::mode5));
  double sum = 0, peak = 0;
  for (int k = 0; k < 2000 && !h.exit_requested(); ++k) {
    h.run(app);
    sum += h.rep.axes[0].d1;
    EXPECT_EQ(h.rep.axes[0].d1, h.rep.axes[0].d2);
    if (k == 499) peak = sum;
  }
  EXPECT_TRUE(h.exit_requested());
  EXPECT_NEAR(peak, h.motor_axis1(10 * kDeg) - h.motor_axis1(0), 1e-3);
  EXPECT_NEAR(sum, h.motor_axis1(5 * kDeg) - h.motor_axis1(0), 1e-3);
}

TEST(StreamApp, RefusesAStartPointAwayFromTheRobot) {
  StreamApp app(options(4));
  Harness h;
  h.start(app);
  h.place_at_link({0, 2 * kDeg, 0, 0, 0, 0});  // axis 2 is 2 deg away from the start
  h.set_modes(code(Mode::mode4));
  h.run(app);
  EXPECT_EQ(app.phase(), Phase::refused);
  EXPECT_TRUE(app.has_error());
  EXPECT_NE(app.error().find("axis 2 is at 2.000 deg, the trajectory starts at 0.000 deg"), std::string::npos) << app.error();
  EXPECT_TRUE(h.exit_requested());
  EXPECT_EQ(h.rep.axes[1].d1, h.req.axes[1].d3);  // held where it is
}

TEST(StreamApp, RelativeTrajectoryStartsWhereTheRobotIs) {
  auto o = options(4);
  o.relative = true;
  StreamApp app(o);
  Harness h;
  h.start(app);
  h.place_at_link({20 * kDeg, 2 * kDeg, 0, 0, 0, 0});
  const float start1 = h.req.axes[0].d3, start2 = h.req.axes[1].d3;
  h.set_modes(code(Mode::mode4));
  for (int k = 0; k < 500; ++k) h.run(app);
  EXPECT_FALSE(app.has_error());
  EXPECT_NEAR(h.rep.axes[0].d1, start1 + h.motor_axis1(10 * kDeg) - h.motor_axis1(0), 1e-3);
  EXPECT_NEAR(h.rep.axes[1].d1, start2, 1e-4);
}

TEST(StreamApp, RefusesADiscontinuousTrajectoryBeforeMoving) {
  // 90 deg in 2 ms on axis 1: about 45 motor turns in one cycle.
  auto t = std::make_shared<Trajectory>(
      Trajectory::parse("# units: deg\nt,a,b,c,d,e,f\n0,0,0,0,0,0,0\n0.002,90,0,0,0,0,0\n", "jump").value());
  StreamApp app(options(4, t));
  Harness h;
  h.start(app);
  EXPECT_EQ(app.phase(), Phase::refused);
  EXPECT_NE(app.error().find("not continuous: axis 1"), std::string::npos) << app.error();
  h.place_at_link({0, 0, 0, 0, 0, 0});
  h.set_modes(code(Mode::mode4));
  h.run(app);
  EXPECT_TRUE(h.exit_requested());
}

TEST(StreamApp, RefusesATrajectoryWithTheWrongAxisCount) {
  auto t = std::make_shared<Trajectory>(Trajectory::parse("t,a,b\n0,0,0\n", "two").value());
  StreamApp app(options(4, t));
  Harness h;
  h.start(app);
  EXPECT_EQ(app.error(), "stream: the trajectory has 2 axes, arm 1 has 6");
}

TEST(StreamApp, StopRequestSlowsDownAlongThePathAndExits) {
  auto o = options(4);
  o.stop_ramp_s = 0.1;
  StreamApp app(o);
  Harness h;
  h.start(app);
  h.place_at_link({0, 0, 0, 0, 0, 0});
  h.set_modes(code(Mode::mode4));
  for (int k = 0; k < 100; ++k) h.run(app);
  app.request_stop();
  double last = h.rep.axes[0].d1, last_step = h.rep.axes[0].d2;
  int cycles = 0;
  while (!h.exit_requested() && cycles < 1000) {
    h.run(app);
    ++cycles;
    EXPECT_LE(std::fabs(h.rep.axes[0].d2), std::fabs(last_step) + 1e-6);  // never faster
    last_step = h.rep.axes[0].d2;
    EXPECT_GE(h.rep.axes[0].d1 * std::copysign(1.0, h.motor_axis1(1) - h.motor_axis1(0)),
              last * std::copysign(1.0, h.motor_axis1(1) - h.motor_axis1(0)) - 1e-6);  // onward along the path
    last = h.rep.axes[0].d1;
  }
  EXPECT_EQ(cycles, 50);  // 0.1 s ramp at 2 ms
  EXPECT_NEAR(h.rep.axes[0].d2, 0.0, 1e-6);
  EXPECT_LT(app.progress(), 750);  // stopped before the end
}

TEST(StreamApp, LeavingTheModeDuringTheTrajectoryIsAnError) {
  StreamApp app(options(4));
  Harness h;
  h.start(app);
  h.place_at_link({0, 0, 0, 0, 0, 0});
  h.set_modes(code(Mode::mode4));
  for (int k = 0; k < 10; ++k) h.run(app);
  h.set_modes(code(Mode::drive_off));
  h.run(app);
  EXPECT_EQ(app.phase(), Phase::refused);
  EXPECT_NE(app.error().find("left mode 4"), std::string::npos) << app.error();
}

TEST(StreamApp, PerCycleTablePlaysOneRowEachCycleWhateverThePeriod) {
  // 11 rows, axis 1 up 0.1 deg a row: with per_cycle, row k is the target of cycle k (2 ms here).
  std::vector<double> values(11 * 6, 0.0);
  for (std::size_t k = 0; k < 11; ++k) values[k * 6] = 0.1 * static_cast<double>(k);
  auto o = options(4, std::make_shared<Trajectory>(Trajectory::from_table(values, 6, 1.0, AngleUnit::deg).value()));
  o.per_cycle = true;
  StreamApp app(o);
  Harness h;
  h.start(app);
  EXPECT_EQ(app.table_rows(), 11u);  // not 11 / 0.002 rows: the clock counts cycles
  h.place_at_link({0, 0, 0, 0, 0, 0});
  h.set_modes(code(Mode::mode4));
  h.run(app);  // row 1 goes out at the start (as in Mode4StreamsAbsoluteMotorTargetsThenExits)
  EXPECT_NEAR(h.rep.axes[0].d1, h.motor_axis1(0.1 * kDeg), 1e-4);
  for (int k = 0; k < 4; ++k) h.run(app);
  EXPECT_NEAR(h.rep.axes[0].d1, h.motor_axis1(0.5 * kDeg), 1e-4);
  run_until_exit(app, h);
  EXPECT_NEAR(h.rep.axes[0].d1, h.motor_axis1(1.0 * kDeg), 1e-4);
  EXPECT_FALSE(app.has_error());
}

TEST(StreamApp, MadeByNameFromATrajectoryInMemory) {
  std::vector<double> values(11 * 6, 0.0);
  for (std::size_t k = 0; k < 11; ++k) values[k * 6] = 0.1 * static_cast<double>(k);
  AppConfig c;
  c.app = "stream";
  c.trajectory = std::make_shared<Trajectory>(Trajectory::from_table(values, 6, 1.0, AngleUnit::deg).value());
  c.per_cycle = true;
  auto app = make_app(c);
  ASSERT_EQ(app->name(), "stream");
  Harness h;
  h.start(*app);
  EXPECT_EQ(static_cast<StreamApp&>(*app).table_rows(), 11u);  // per_cycle reached the app
  c.file = "trajectory.csv";
  try {
    make_app(c);
    ADD_FAILURE() << "a trajectory and a file were both taken";
  } catch (const axon::Exception& e) {
    EXPECT_EQ(e.error().code, axon::CoreErrc::invalid_argument);
    EXPECT_EQ(e.error().detail, "give a trajectory or --file/--segment, not both");
  }
}
