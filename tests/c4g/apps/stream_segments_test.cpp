// StreamApp with trajectory segments chosen by the arm's motion type (CMD byte).
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

// Axis 1 by `deg` over 0.1 s (50 cycles at 2 ms), relative.
std::shared_ptr<const Trajectory> move(double deg) {
  return std::make_shared<Trajectory>(
      Trajectory::from_rows({0.0, 0.1}, {{0, 0, 0, 0, 0, 0}, {deg * kDeg, 0, 0, 0, 0, 0}}).value());
}

StreamOptions segments(int mode) {
  StreamOptions o;
  o.mode = mode;
  o.relative = true;
  o.segments = {{1, move(4)}, {2, move(-4)}};
  return o;
}


void set_type(Harness& h, std::uint8_t type) { h.req.cmd = protocol::with_arm_byte(h.req.cmd, 1, type); }

}  // namespace

TEST(StreamSegments, MotionTypePicksTheSegmentAndSegmentsChain) {
  StreamApp app(segments(4));
  Harness h;
  h.start(app);
  h.place_at_link({0, 0, 0, 0, 0, 0});
  const double start = h.req.axes[0].d3;
  set_type(h, 1);
  h.set_modes(code(Mode::mode4));
  for (int k = 0; k < 80; ++k) h.run(app);  // segment 1 and some holding: no exit while holding
  EXPECT_EQ(app.phase(), Phase::holding);
  EXPECT_FALSE(h.exit_requested());
  EXPECT_EQ(app.segment(), 1);
  const double out = h.rep.axes[0].d1;
  EXPECT_NEAR(out - start, h.motor_axis1(4 * kDeg) - h.motor_axis1(0), 1e-4);
  // Motion type 2: the next segment starts from the last command (the robot has not followed here).
  set_type(h, 2);
  h.run(app);
  EXPECT_EQ(app.phase(), Phase::running);
  EXPECT_EQ(app.segment(), 2);
  // Continuous: the first cycle moves one row of segment 2 away from where segment 1 ended.
  const double row = h.motor_axis1(4 * kDeg * 0.02) - h.motor_axis1(0);
  EXPECT_NEAR(h.rep.axes[0].d1 - out, -row, std::fabs(0.1 * row));
  for (int k = 0; k < 60; ++k) h.run(app);
  EXPECT_NEAR(h.rep.axes[0].d1, start, 1e-4);  // back where it began
  // Motion type 0: done with the segments, exit from open.
  set_type(h, 0);
  h.run(app);
  EXPECT_TRUE(h.exit_requested());
  h.set_modes(code(Mode::mode0));
  h.run(app);
  EXPECT_TRUE(app.finished());
  EXPECT_FALSE(app.has_error());
  const auto events = event_texts(app);
  EXPECT_TRUE(contains(events, "stream: segment for motion type 1 started"));
  EXPECT_TRUE(contains(events, "stream: segment for motion type 2 started"));
  EXPECT_TRUE(contains(events, "stream: motion type 0: the segments are over"));
}

TEST(StreamSegments, UnknownMotionTypeHoldsAndIsNoted) {
  StreamApp app(segments(4));
  Harness h;
  h.start(app);
  h.place_at_link({0, 0, 0, 0, 0, 0});
  set_type(h, 1);
  h.set_modes(code(Mode::mode4));
  for (int k = 0; k < 20; ++k) h.run(app);  // mid segment 1
  const double mid = h.rep.axes[0].d1;
  set_type(h, 9);
  for (int k = 0; k < 30; ++k) {
    h.run(app);
    EXPECT_FLOAT_EQ(h.rep.axes[0].d1, static_cast<float>(mid));  // held
    EXPECT_FLOAT_EQ(h.rep.axes[0].d2, 0.0f);
  }
  EXPECT_EQ(app.phase(), Phase::idle);
  EXPECT_FALSE(h.exit_requested());
  EXPECT_TRUE(contains(event_texts(app), "stream: no segment for motion type 9: holding"));
  // A known type again resumes with its segment.
  set_type(h, 2);
  h.run(app);
  EXPECT_EQ(app.phase(), Phase::running);
  EXPECT_FALSE(app.has_error());
}

TEST(StreamSegments, Mode5EntryWithoutAMotionTypeAddsNothing) {
  StreamApp app(segments(5));
  Harness h;
  h.start(app);
  h.place_at_link({0, 0, 0, 0, 0, 0});
  h.set_modes(code(Mode::mode5));
  for (int k = 0; k < 10; ++k) {
    h.run(app);
    EXPECT_FLOAT_EQ(h.rep.axes[0].d1, 0.0f);
  }
  EXPECT_EQ(app.phase(), Phase::idle);
  set_type(h, 1);
  for (int k = 0; k < 60; ++k) h.run(app);
  EXPECT_EQ(app.phase(), Phase::holding);
  EXPECT_FALSE(app.has_error());
}

TEST(StreamSegments, AbsoluteSegmentAwayFromTheRobotIsRefused) {
  StreamOptions o = segments(4);
  o.relative = false;
  o.segments[1].trajectory = std::make_shared<Trajectory>(
      Trajectory::from_rows({0.0, 0.1}, {{20 * kDeg, 0, 0, 0, 0, 0}, {20 * kDeg, 0, 0, 0, 0, 0}}).value());
  StreamApp app(o);
  Harness h;
  h.start(app);
  h.place_at_link({0, 0, 0, 0, 0, 0});
  set_type(h, 1);
  h.set_modes(code(Mode::mode4));
  for (int k = 0; k < 60; ++k) h.run(app);
  set_type(h, 2);
  h.run(app);
  EXPECT_EQ(app.phase(), Phase::refused);
  EXPECT_TRUE(h.exit_requested());
  EXPECT_NE(app.error().find("start point"), std::string::npos) << app.error();
}

TEST(StreamSegments, RejectsDuplicateMotionTypesAndBothKindsOfInput) {
  StreamOptions o = segments(4);
  o.segments[1].motion_type = 1;
  EXPECT_THROW(StreamApp{o}, axon::Exception);
  StreamOptions both = segments(4);
  both.trajectory = move(1);
  EXPECT_THROW(StreamApp{both}, axon::Exception);
}

// Segments given as tables (a binding's path through make_app) play as files do; each motion type
// once, whether it came from a file or a table, and not together with a single trajectory.
TEST(StreamSegments, TablesThroughTheFactoryAreCheckedAsFilesAre) {
  AppConfig c;
  c.app = "stream";
  c.relative = true;
  c.segment_tables = {{1, move(4)}, {2, move(-4)}};
  auto app = make_app(c);
  Harness h;
  h.start(*app);
  h.place_at_link({0, 0, 0, 0, 0, 0});
  const double start = h.req.axes[0].d3;
  set_type(h, 1);
  h.set_modes(code(Mode::mode4));
  for (int k = 0; k < 80; ++k) h.run(*app);
  auto* stream = dynamic_cast<StreamApp*>(app.get());
  ASSERT_NE(stream, nullptr);
  EXPECT_EQ(stream->segment(), 1);
  EXPECT_NEAR(h.rep.axes[0].d1 - start, h.motor_axis1(4 * kDeg) - h.motor_axis1(0), 1e-4);
  EXPECT_FALSE(app->has_error()) << app->error();

  AppConfig twice = c;
  twice.segment_tables.push_back({2, move(1)});
  EXPECT_THROW(make_app(twice), axon::Exception);
  AppConfig both = c;
  both.trajectory = move(1);
  EXPECT_THROW(make_app(both), axon::Exception);
  AppConfig no_type = c;
  no_type.segment_tables[0].motion_type = 0;
  EXPECT_THROW(make_app(no_type), axon::Exception);
}
