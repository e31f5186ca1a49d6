#include "axon/c4g/apps/contribute.hpp"

#include "harness.hpp"

#include <cmath>

using namespace axon;
using namespace axon::c4g;
using namespace axon::c4g::apps;
using namespace axon::c4g::apps::test;
using protocol::code;
using protocol::Mode;

namespace {

TEST(ContributeApp, Mode9SendsASineCurrentFadedInAndOutThenExits) {
  ContributeOptions o;
  o.mode = 9;
  o.amplitude = {2.0};  // every axis
  o.frequency_hz = {1.0};
  o.open_time_s = 0.5;
  o.ramp_s = 0.1;
  ContributeApp app(o);
  Harness h;  // 2 ms cycle
  h.start(app);
  h.set_modes(code(Mode::mode9));
  h.run(app);
  EXPECT_EQ(app.phase(), Phase::running);
  // t = 2 ms: envelope 0.02, sin(2 pi 0.002) -> tiny; at t = 0.25 s the sine peaks at full envelope.
  int k = 1;
  for (; k < 125; ++k) h.run(app);
  EXPECT_NEAR(h.rep.axes[0].d5, 2.0, 1e-3);
  EXPECT_NEAR(h.rep.axes[5].d5, 2.0, 1e-3);
  EXPECT_EQ(h.rep.axes[0].d4, 0.0f);  // mode 9 touches D5 only
  for (; k < 1000 && !h.exit_requested(); ++k) h.run(app);
  EXPECT_NEAR(k, 300, 1);  // 0.5 s then 0.1 s of fade at 2 ms
  EXPECT_NEAR(h.rep.axes[0].d5, 0.0, 1e-6);
  h.set_modes(code(Mode::mode0));
  h.run(app);
  EXPECT_TRUE(app.finished());
  EXPECT_NEAR(app.peak(0), 2.0, 1e-3);
}

TEST(ContributeApp, Mode8ConvertsTurnsPerSecondToTurnsPerCycle) {
  ContributeOptions o;
  o.mode = 8;
  o.amplitude = {1.0, 0.5};  // axes 1 and 2; the others 0
  o.frequency_hz = {1.0};
  o.ramp_s = 0;
  ContributeApp app(o);
  Harness h;
  h.start(app);
  h.set_modes(code(Mode::mode8));
  for (int k = 0; k < 125; ++k) h.run(app);  // t = 0.25 s: the sine's peak
  EXPECT_NEAR(h.rep.axes[0].d4, 1.0 * 0.002, 1e-7);
  EXPECT_NEAR(h.rep.axes[1].d4, 0.5 * 0.002, 1e-7);
  EXPECT_EQ(h.rep.axes[2].d4, 0.0f);
  EXPECT_EQ(h.rep.axes[0].d5, 0.0f);
  app.request_stop();
  h.run(app);  // no ramp: straight to exit
  EXPECT_TRUE(h.exit_requested());
}

TEST(ContributeApp, LeavingTheModeUnaskedIsAnError) {
  ContributeOptions o;
  o.amplitude = {1.0};
  ContributeApp app(o);
  Harness h;
  h.start(app);
  h.set_modes(code(Mode::mode9));
  h.run(app);
  h.set_modes(code(Mode::mode0));
  h.run(app);
  EXPECT_EQ(app.phase(), Phase::refused);
  EXPECT_NE(app.error().find("left mode 9"), std::string::npos) << app.error();
}

TEST(ContributeApp, RejectsOtherModesAndMissingAmplitudes) {
  ContributeOptions o;
  o.mode = 7;
  o.amplitude = {1.0};
  EXPECT_THROW(ContributeApp{o}, Exception);
  o.mode = 9;
  o.amplitude.clear();
  EXPECT_THROW(ContributeApp{o}, Exception);
  o.amplitude = {std::nan("")};
  EXPECT_THROW(ContributeApp{o}, Exception);
  o.mode = 8;
  o.amplitude = {1, 9999};  // motor turns/s
  try {
    ContributeApp app(o);
    FAIL() << "a 9999 turns/s velocity contribution was accepted";
  } catch (const Exception& e) {
    EXPECT_NE(std::string(e.what()).find("9999 motor turns/s on axis 2 exceeds --max-motor-speed 100"), std::string::npos) << e.what();
  }
  o.max_motor_speed = 10000;
  EXPECT_NO_THROW(ContributeApp{o});
}

}  // namespace
