#include "axon/c4g/apps/correct.hpp"

#include "harness.hpp"

#include <cmath>
#include <limits>

using namespace axon::c4g;
using namespace axon::c4g::apps;
using namespace axon::c4g::apps::test;
using protocol::code;
using protocol::Mode;

TEST(CorrectApp, SineIncrementsAddUpToTheCorrection) {
  CorrectOptions o;
  o.amplitude_rad = {0, 0, 0, 2 * kDeg};  // axis 4 only: it also moves motors 5 and 6 (wrist coupling)
  o.frequency_hz = {1.0};
  CorrectApp app(o);
  Harness h;
  h.start(app);
  h.set_modes(code(Mode::mode7));
  std::array<double, 6> sum{};
  for (int k = 0; k < 125; ++k) {  // 0.25 s: the sine's peak
    h.run(app);
    for (std::size_t j = 0; j < 6; ++j) sum[j] += h.rep.axes[j].d1;
  }
  EXPECT_NEAR(sum[3], motor_of(h, 3, 2 * kDeg, 3), 1e-4);
  EXPECT_NEAR(sum[4], motor_of(h, 3, 2 * kDeg, 4), 1e-4);
  EXPECT_NE(sum[4], 0.0);
  EXPECT_NEAR(sum[0], 0.0, 1e-9);
  EXPECT_NEAR(app.applied(3), sum[3], 1e-4);
  EXPECT_FALSE(h.exit_requested());
}

TEST(CorrectApp, FadesOutAfterTheOpenTimeThenExits) {
  CorrectOptions o;
  o.amplitude_rad = {1 * kDeg};
  o.frequency_hz = {2.0};
  o.open_time_s = 0.2;
  o.ramp_s = 0.1;
  CorrectApp app(o);
  Harness h;
  h.start(app);
  h.set_modes(code(Mode::mode7));
  std::array<double, 6> sum{};
  int k = 0;
  for (; k < 1000 && !h.exit_requested(); ++k) {
    h.run(app);
    for (std::size_t j = 0; j < 6; ++j) sum[j] += h.rep.axes[j].d1;
  }
  EXPECT_NEAR(k, 150, 1);  // 0.2 s then 0.1 s of fading at 2 ms
  for (double s : sum) EXPECT_NEAR(s, 0.0, 1e-6);  // the correction is back to zero
  h.set_modes(code(Mode::mode7_standby_exit));
  h.run(app);
  EXPECT_EQ(h.rep.axes[0].d1, 0.0f);
  h.set_modes(code(Mode::mode0));
  h.run(app);
  EXPECT_TRUE(app.finished());
}

TEST(CorrectApp, ValuesFromAFileAreInterpolated) {
  CorrectOptions o;
  o.values = std::make_shared<Trajectory>(
      Trajectory::parse("# units: deg\nt,a,b,c,d,e,f\n0,0,0,0,0,0,0\n0.1,0,0.5,0,0,0,0\n0.2,0,0.5,0,0,0,0\n", "f").value());
  CorrectApp app(o);
  Harness h;
  h.start(app);
  h.set_modes(code(Mode::mode7));
  double sum = 0;
  int k = 0;
  for (; k < 1000 && !h.exit_requested(); ++k) {
    h.run(app);
    sum += h.rep.axes[1].d1;
    if (k == 24) {
      EXPECT_NEAR(sum, motor_of(h, 1, 0.25 * kDeg, 1), 1e-5);  // t = 0.05 s
    }
  }
  EXPECT_NEAR(k, 100, 1);  // the file's end
  EXPECT_NEAR(sum, motor_of(h, 1, 0.5 * kDeg, 1), 1e-5);  // its last offset stays applied
}

TEST(CorrectApp, RefusesACorrectionTooFastForTheMotors) {
  CorrectOptions o;
  o.amplitude_rad = {30 * kDeg};
  o.frequency_hz = {5.0};  // about 76 motor turns/s on axis 1 at the peak (ratio 181)
  o.max_motor_speed = 50;
  o.limits.max_abs_rad = {40 * kDeg};  // the correction bounds allow it: the motors' limit decides
  o.limits.max_step_rad = {2 * kDeg};
  CorrectApp app(o);
  Harness h;
  h.start(app);
  EXPECT_EQ(app.phase(), Phase::refused);
  EXPECT_NE(app.error().find("motor turns/s on axis 1"), std::string::npos) << app.error();
  h.set_modes(code(Mode::mode7));
  h.run(app);
  EXPECT_EQ(h.rep.axes[0].d1, 0.0f);
  EXPECT_TRUE(h.exit_requested());
}

TEST(CorrectApp, ControllerLeavingModeSevenIsAnError) {
  CorrectOptions o;
  o.amplitude_rad = {1 * kDeg};
  CorrectApp app(o);
  Harness h;
  h.start(app);
  h.set_modes(code(Mode::mode7));
  h.run(app);
  h.set_modes(code(Mode::mode0));
  h.run(app);
  EXPECT_EQ(app.phase(), Phase::refused);
  EXPECT_NE(app.error().find("left mode 7"), std::string::npos);
}

TEST(CorrectApp, StopRequestFadesOut) {
  CorrectOptions o;
  o.amplitude_rad = {1 * kDeg};
  o.ramp_s = 0.05;
  CorrectApp app(o);
  Harness h;
  h.start(app);
  h.set_modes(code(Mode::mode7));
  for (int k = 0; k < 60; ++k) h.run(app);
  app.request_stop();
  int k = 0;
  for (; k < 1000 && !h.exit_requested(); ++k) h.run(app);
  EXPECT_NEAR(k, 26, 1);
  EXPECT_NEAR(app.applied(0), 0.0, 1e-9);
}

TEST(CorrectLimits, DefaultsAndValidation) {
  CorrectionLimits l;
  EXPECT_NEAR(l.max_abs(0), 5 * kDeg, 1e-12);
  EXPECT_NEAR(l.max_step(5), 0.1 * kDeg, 1e-12);
  EXPECT_TRUE(validate(l));
  l.max_abs_rad = {1 * kDeg, 2 * kDeg};
  EXPECT_NEAR(l.max_abs(0), 1 * kDeg, 1e-12);
  EXPECT_NEAR(l.max_abs(4), 2 * kDeg, 1e-12);  // the last value applies to the axes after it
  for (double bad : {0.0, -1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    l.max_step_rad = {bad};
    auto v = validate(l);
    ASSERT_FALSE(v) << bad;
    EXPECT_NE(v.error().detail.find("must be > 0"), std::string::npos) << v.error().detail;
  }
  l.max_step_rad = {};
  EXPECT_FALSE(validate(l));
}

TEST(CorrectLimits, ASineBeyondTheLimitIsRefusedWhenBuilt) {
  CorrectOptions o;
  o.amplitude_rad = {0, 90 * kDeg};
  try {
    CorrectApp app(o);
    FAIL() << "a 90 deg sine was accepted";
  } catch (const axon::Exception& e) {
    EXPECT_NE(std::string(e.what()).find("sine amplitude 90 deg on axis 2 exceeds the correction limit 5 deg"), std::string::npos)
        << e.what();
  }
  o.amplitude_rad = {std::nan("")};
  EXPECT_THROW(CorrectApp{o}, axon::Exception);
  o.amplitude_rad = {1 * kDeg};
  o.frequency_hz = {-1};
  EXPECT_THROW(CorrectApp{o}, axon::Exception);
}

TEST(CorrectLimits, AFileBeyondTheLimitIsRefusedWhenBuilt) {
  CorrectOptions o;
  o.values = std::make_shared<Trajectory>(
      Trajectory::parse("# units: deg\nt,a,b,c,d,e,f\n0,0,0,0,0,0,0\n1,0,0,9999,0,0,0\n", "f").value());
  try {
    CorrectApp app(o);
    FAIL() << "a 9999 deg file was accepted";
  } catch (const axon::Exception& e) {
    EXPECT_NE(std::string(e.what()).find("row 2 (t=1 s) asks 9999 deg on axis 3"), std::string::npos) << e.what();
  }
}

TEST(CorrectLimits, ASineTooFastPerCycleIsRefusedAtTheInitializationPacket) {
  CorrectOptions o;
  o.amplitude_rad = {4 * kDeg};
  o.frequency_hz = {5.0};  // 2 pi 5 Hz 4 deg = 126 deg/s: 0.25 deg per 2 ms cycle
  CorrectApp app(o);
  Harness h;
  h.start(app);
  EXPECT_EQ(app.phase(), Phase::refused);
  EXPECT_NE(app.error().find("in one cycle on axis 1"), std::string::npos) << app.error();
  h.set_modes(code(Mode::mode7));
  h.run(app);
  EXPECT_EQ(h.rep.axes[0].d1, 0.0f);
  EXPECT_TRUE(h.exit_requested());
}

TEST(CorrectLimits, AShortFadeCountsAgainstTheStepLimit) {
  CorrectOptions o;
  o.amplitude_rad = {4 * kDeg};
  o.frequency_hz = {0.1};
  o.ramp_s = 0.01;  // 4 deg faded out in 5 cycles: 0.8 deg per cycle
  CorrectApp app(o);
  Harness h;
  h.start(app);
  EXPECT_EQ(app.phase(), Phase::refused);
  o.ramp_s = 0.5;  // 0.016 deg per cycle
  CorrectApp slow(o);
  h.start(slow);
  EXPECT_EQ(slow.phase(), Phase::waiting);
}
