#include "axon/c4g/apps/pid.hpp"

#include "harness.hpp"

#include <cmath>

using namespace axon::c4g;
using namespace axon::c4g::apps;
using namespace axon::c4g::apps::test;
using protocol::code;
using protocol::Mode;

namespace {

// A motor-side axis: inertia, torque constant, a constant load torque (gravity) given as a current.
struct Plant {
  double inertia = 3e-3;  // [kg m^2]
  double kt = 1.0;        // [N m / A]
  double load_current = 0;  // [A] the current that holds the load
  double position = 0;    // [turns]
  double velocity = 0;    // [turns/s]
  void step(double current, double dt) {
    const double accel = kt * (current - load_current) / inertia / (2 * std::numbers::pi);  // turns/s^2
    velocity += accel * dt;
    position += velocity * dt;
  }
};

}  // namespace

TEST(AxisPid, PushesTowardsTheTarget) {
  AxisPid pid;
  const PidGains g{10, 0.5, 5};
  EXPECT_GT(pid.update(g, 1.0, 0, 0.9, 0, 0, 10, 0.002), 0.0);
  pid.reset();
  EXPECT_LT(pid.update(g, 1.0, 0, 1.1, 0, 0, 10, 0.002), 0.0);
  pid.reset();
  EXPECT_DOUBLE_EQ(pid.update(g, 1.0, 0, 1.0, 0, 2.5, 10, 0.002), 2.5);  // on target: the feed-forward alone
}

TEST(AxisPid, SaturatesAndDoesNotWindUp) {
  AxisPid pid;
  const PidGains g{10, 0.5, 5};
  for (int k = 0; k < 1000; ++k) {
    EXPECT_DOUBLE_EQ(pid.update(g, 100.0, 0, 0, 0, 0, 1.5, 0.002), 1.5);
    EXPECT_TRUE(pid.saturated());
  }
  EXPECT_DOUBLE_EQ(pid.integral(), 0.0);  // never integrated while pushing into the limit
  // The error reverses: the output follows at once instead of unwinding a huge integral.
  EXPECT_LT(pid.update(g, 0.0, 0, 0.5, 0, 0, 1.5, 0.002), 0.0);
  // No limit given: no clamp.
  pid.reset();
  EXPECT_GT(pid.update(g, 100.0, 0, 0, 0, 0, 0, 0.002), 100.0);
}

TEST(AxisPid, IntegralRemovesASteadyLoad) {
  AxisPid pid;
  Plant plant;
  plant.load_current = 2.0;
  const PidGains g{10, 0.5, 5};
  for (int k = 0; k < 5000; ++k) plant.step(pid.update(g, 0.0, 0, plant.position, plant.velocity, 0, 24, 0.002), 0.002);
  EXPECT_NEAR(plant.position, 0.0, 1e-3);
  EXPECT_NEAR(pid.integral(), 2.0, 0.05);
}

TEST(PidApp, Mode1HoldsThePositionFoundAtTheStart) {
  PidApp app(PidOptions{});
  Harness h;
  h.start(app);
  h.place_at_link({0.1, 0.2, 0.3, 0, 0, 0});
  h.set_modes(code(Mode::mode1));
  for (std::size_t i = 0; i < 6; ++i) h.req.axes[i].ext1 = 0.25f;
  h.run(app);
  for (std::size_t i = 0; i < 6; ++i) {
    EXPECT_FLOAT_EQ(h.rep.axes[i].d1, h.req.axes[i].d3);
    EXPECT_FLOAT_EQ(h.rep.axes[i].d2, 0.0f);
    EXPECT_NEAR(h.rep.axes[i].d5, 0.25f, 1e-6);  // on target: the dynamic-model current
  }
  // Pushed away: the current pulls back; far away: the limit of the initialization packet (9.5 A).
  h.req.axes[0].d3 += 0.1f;
  h.req.axes[3].d3 += 50.0f;
  h.run(app);
  EXPECT_LT(h.rep.axes[0].d5, 0.0f);
  EXPECT_FLOAT_EQ(h.rep.axes[3].d5, -9.5f);
  EXPECT_GT(app.max_following_error(), 49.0);
  EXPECT_GE(app.saturated_cycles(), 1u);
}

TEST(PidApp, Mode1ClosedLoopFollowsASineAndLeavesAfterTheOpenTime) {
  PidOptions o;
  o.amplitude_rad = {0.05};  // every axis
  o.frequency_hz = {1.0};
  o.open_time_s = 1.0;
  o.ramp_s = 0.2;
  PidApp app(o);
  Harness h;
  h.start(app);
  h.place_at_link({0, 0, 0, 0, 0, 0});
  h.set_modes(code(Mode::mode1));
  std::array<Plant, 6> plants;
  for (std::size_t i = 0; i < 6; ++i) plants[i].position = h.req.axes[i].d3;
  double worst = 0;
  int k = 0;
  for (; k < 2000 && !h.exit_requested(); ++k) {
    h.run(app);
    for (std::size_t i = 0; i < 6; ++i) {
      plants[i].step(h.rep.axes[i].d5, h.period());
      h.req.axes[i].d3 = static_cast<float>(plants[i].position);
      h.req.axes[i].d4 = static_cast<float>(plants[i].velocity * h.period());
      worst = std::max(worst, static_cast<double>(std::fabs(h.rep.axes[i].d1 - h.req.axes[i].d3)));
    }
  }
  // 1 s, then 0.2 s of fading, then until the robot settles on the hold position (soft switching
  // back needs it still; at most 1 s), at 2 ms.
  EXPECT_GE(k, 600);
  EXPECT_LE(k, 1101);
  for (std::size_t i = 0; i < 6; ++i) EXPECT_LT(std::fabs(h.rep.axes[i].d1 - h.req.axes[i].d3), 2.5e-4) << "axis " << i;
  EXPECT_LT(worst, 0.5);   // motor turns; the sine is about 1.4 turns peak on axis 1
  EXPECT_FALSE(app.has_error());
  h.set_modes(code(Mode::mode1_standby));
  const float held = h.rep.axes[0].d1;
  h.run(app);
  EXPECT_FLOAT_EQ(h.rep.axes[0].d1, held);  // 1': still holding
  h.set_modes(code(Mode::mode0));
  h.run(app);
  EXPECT_TRUE(app.finished());
}

TEST(PidApp, Mode2TracksTheControllersTrajectory) {
  PidApp app(PidOptions{});
  Harness h;
  h.start(app);
  h.place_at_link({0, 0, 0, 0, 0, 0});
  h.set_modes(code(Mode::mode2));
  Plant plant;
  plant.position = h.req.axes[2].d3;
  plant.load_current = 1.0;
  const double target = plant.position + 0.5;
  for (int k = 0; k < 3000; ++k) {
    h.req.axes[2].d1 = static_cast<float>(target);
    h.req.axes[2].d2 = 0;
    h.run(app);
    EXPECT_FLOAT_EQ(h.rep.axes[2].d4, 0.0f);
    plant.step(h.rep.axes[2].d5, h.period());
    h.req.axes[2].d3 = static_cast<float>(plant.position);
    h.req.axes[2].d4 = static_cast<float>(plant.velocity * h.period());
  }
  EXPECT_NEAR(plant.position, target, 2e-3);
  EXPECT_FALSE(h.exit_requested());  // mode 2 is ended by the controller
  h.set_modes(code(Mode::mode2_standby));
  h.run(app);
  h.set_modes(code(Mode::mode0));
  h.run(app);
  EXPECT_TRUE(app.finished());
}

TEST(PidApp, ReportsAnArmWithoutOpenAxes) {
  PidOptions o;
  o.arm = 2;
  PidApp app(o);
  Harness h;
  h.start(app);
  EXPECT_TRUE(app.has_error());
  EXPECT_TRUE(app.drive_off_on_error());
}

TEST(PidApp, ASineBeyondTheLimitsIsRefused) {
  PidOptions o;
  o.amplitude_rad = {9999 * kDeg};
  try {
    PidApp app(o);
    FAIL() << "a 9999 deg sine was accepted";
  } catch (const axon::Exception& e) {
    EXPECT_NE(std::string(e.what()).find("pid: the sine amplitude 9999 deg on axis 1 exceeds the correction limit 5 deg"),
              std::string::npos) << e.what();
  }
  o.amplitude_rad = {std::nan("")};
  EXPECT_THROW(PidApp{o}, axon::Exception);
  o.amplitude_rad = {4 * kDeg};
  o.frequency_hz = {5.0};  // 0.25 deg per 2 ms cycle
  PidApp fast(o);
  Harness h;
  h.start(fast);
  EXPECT_EQ(fast.phase(), Phase::refused);
  EXPECT_NE(fast.error().find("in one cycle on axis 1"), std::string::npos) << fast.error();
}
