#include "axon/c4g/apps/echo.hpp"
#include "axon/c4g/apps/monitor.hpp"

#include "harness.hpp"

using namespace axon::c4g;
using namespace axon::c4g::apps;
using namespace axon::c4g::apps::test;
using protocol::code;
using protocol::Mode;

TEST(EchoApp, ReturnsTargetsUnchangedInModeZeroPrime) {
  EchoApp app;
  Harness h;
  h.start(app);
  h.set_modes(code(Mode::mode0_prime));
  for (std::size_t i = 0; i < 6; ++i) {
    h.req.axes[i].d1 = 1.5f + static_cast<float>(i);
    h.req.axes[i].d2 = -0.01f * static_cast<float>(i);
    h.req.axes[i].d3 = 99.0f;
  }
  const auto& r = h.run(app);
  for (std::size_t i = 0; i < 6; ++i) {
    EXPECT_EQ(r.axes[i].mode, code(Mode::mode0_prime));
    EXPECT_EQ(r.axes[i].d1, h.req.axes[i].d1);
    EXPECT_EQ(r.axes[i].d2, h.req.axes[i].d2);
    EXPECT_EQ(r.axes[i].d3, 0.0f);  // only the references come back
  }
  EXPECT_EQ(app.echoed(), 1u);
}

TEST(EchoApp, LeavesOtherModesToTheSafeReply) {
  EchoApp app;
  Harness h;
  h.start(app);
  h.set_modes(code(Mode::mode0));
  h.req.axes[0].d1 = 3.0f;
  const auto& r = h.run(app);
  EXPECT_EQ(r.axes[0].d1, 0.0f);
  EXPECT_EQ(app.echoed(), 0u);
}

TEST(MonitorApp, ReportsInitModeChangesAndDrives) {
  MonitorApp app;
  Harness h;
  h.start(app);
  h.req.infpar = 0;
  h.run(app);
  h.req.infpar = protocol::kDrivesOn;
  h.set_modes(code(Mode::driving_on));
  h.run(app);
  h.set_modes(code(Mode::mode0));
  h.run(app);
  const auto events = event_texts(app);
  EXPECT_TRUE(contains(events, "initialization packet: 6 open axes, period 2 ms"));
  EXPECT_TRUE(contains(events, "arm 1: drives on"));
  EXPECT_TRUE(contains(events, "axis 1: mode 0 -> 501 (driving_on)"));
  EXPECT_TRUE(contains(events, "axis 6: mode 501 -> 0 (mode0)"));
  EXPECT_EQ(app.drives_on_cycles(), 2u);
  EXPECT_EQ(app.non_mode0_cycles(), 1u);
  EXPECT_TRUE(app.quiescent());
}

TEST(MonitorApp, StatusShowsLinkDegrees) {
  MonitorApp app;
  Harness h;
  h.start(app);
  h.place_at_link({0.5, 0, 0, 0, 0, 0});  // 28.648 deg on axis 1
  h.run(app);
  const auto s = app.status();
  EXPECT_NE(s.find("arm1[deg] 28.648"), std::string::npos) << s;
  EXPECT_NE(s.find("modes 0 0 0 0 0 0"), std::string::npos) << s;
}

TEST(App, RecordsSamplesWhenAsked) {
  MonitorApp app;
  app.record_samples(4);
  Harness h;
  h.start(app);
  for (int i = 0; i < 6; ++i) h.run(app);
  std::vector<std::uint64_t> cycles;
  app.drain_samples([&](const Sample& s) { cycles.push_back(s.cycle); });
  EXPECT_EQ(cycles, (std::vector<std::uint64_t>{0, 1, 2, 3}));
  EXPECT_EQ(app.samples_dropped(), 2u);
}

TEST(App, QuiescentOnlyWhenEveryAxisIsInModeZero) {
  EchoApp app;
  Harness h;
  h.start(app);
  h.set_modes(code(Mode::mode0));
  h.req.axes[3].mode = code(Mode::mode4);
  h.run(app);
  EXPECT_FALSE(app.quiescent());
  h.req.axes[3].mode = code(Mode::mode0);
  h.run(app);
  EXPECT_TRUE(app.quiescent());
  h.set_modes(code(Mode::exit_open));
  h.run(app);
  EXPECT_TRUE(app.controller_exited());
}
