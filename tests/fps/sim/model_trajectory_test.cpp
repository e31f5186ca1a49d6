// PositionerModel: trajectory upload, checks on every point and at the end, start, interpolation
// from the current position at time 0, and interruption.
#include "harness.hpp"

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::sim;
using namespace axon::fps::sim::testing;

namespace {

// Uploads alpha and beta points (degrees, seconds); returns every point's response code.
std::vector<ResponseCode> upload(Harness& h, const std::vector<std::pair<double, double>>& alpha,
                                 const std::vector<std::pair<double, double>>& beta) {
  std::vector<ResponseCode> codes;
  codes.push_back(h.code(CommandId::send_new_trajectory,
                         two_u32(static_cast<std::uint32_t>(alpha.size()), static_cast<std::uint32_t>(beta.size()))));
  for (const auto& [d, s] : alpha) codes.push_back(h.code(CommandId::send_trajectory_data, point(d, s)));
  for (const auto& [d, s] : beta) codes.push_back(h.code(CommandId::send_trajectory_data, point(d, s)));
  return codes;
}

bool all_accepted(const std::vector<ResponseCode>& codes) {
  for (auto c : codes) {
    if (c != ResponseCode::accepted) return false;
  }
  return true;
}

}  // namespace

// The interface document's example (table 8): 3 alpha points, 4 beta points.
TEST(FpsSimTrajectory, RunsTheSpecExample) {
  Harness h;
  ASSERT_TRUE(all_accepted(upload(h, {{45, 5}, {90, 10}, {45, 15}}, {{90, 10}, {45, 15}, {90, 20}, {45, 25}})));
  auto s = h.status();
  EXPECT_TRUE(s.has(StatusBit::receiving_trajectory));
  EXPECT_TRUE(s.trajectory_received());
  ASSERT_EQ(h.code(CommandId::trajectory_data_end), ResponseCode::accepted);
  s = h.status();
  EXPECT_FALSE(s.has(StatusBit::receiving_trajectory));
  EXPECT_TRUE(s.trajectory_received());

  ASSERT_EQ(h.code(CommandId::start_trajectory), ResponseCode::accepted);
  EXPECT_FALSE(h.status().has(StatusBit::displacement_completed));
  EXPECT_FALSE(h.status().trajectory_received());
  h.wait(2500ms);  // alpha interpolates from 0 at t=0 to 45 at 5 s
  EXPECT_NEAR(h.position().first, 22.5, 1e-3);
  EXPECT_NEAR(h.position().second, 180 - 90.0 / 10 * 2.5, 1e-3);  // 180 -> 90 over 10 s
  h.wait(10s);                                                     // t = 12.5 s
  EXPECT_NEAR(h.position().first, 67.5, 1e-3);
  h.wait(3s);  // 15.5 s: alpha finished, beta still going
  auto st = h.status();
  EXPECT_TRUE(st.has(StatusBit::displacement_completed_alpha));
  EXPECT_FALSE(st.has(StatusBit::displacement_completed_beta));
  h.wait(10s);
  st = h.status();
  EXPECT_TRUE(st.has(StatusBit::displacement_completed));
  EXPECT_NEAR(h.position().first, 45, 1e-6);
  EXPECT_NEAR(h.position().second, 45, 1e-6);
}

TEST(FpsSimTrajectory, PointTooFastIsOutOfRangeAndSpoilsTheEnd) {
  Harness h;  // at most 5000 rpm = 30 deg/s at the arm
  const auto codes = upload(h, {{40, 1}}, {});
  EXPECT_EQ(codes[1], ResponseCode::value_out_of_range);
  EXPECT_EQ(h.code(CommandId::trajectory_data_end), ResponseCode::invalid_trajectory);
  // The spoiled trajectory was dropped: a start finds nothing to run.
  EXPECT_EQ(h.code(CommandId::start_trajectory), ResponseCode::accepted);
  EXPECT_FALSE(h.model.moving());
}

TEST(FpsSimTrajectory, SpeedIsCheckedBetweenPointsToo) {
  Harness h;
  const auto codes = upload(h, {{20, 1}, {100, 2}}, {});
  EXPECT_EQ(codes[1], ResponseCode::accepted);
  EXPECT_EQ(codes[2], ResponseCode::value_out_of_range);
}

TEST(FpsSimTrajectory, PointBeyondTheHardStopIsOutOfRange) {
  Harness h;
  const auto codes = upload(h, {}, {{366, 60}});
  EXPECT_EQ(codes[1], ResponseCode::value_out_of_range);
  EXPECT_EQ(h.code(CommandId::trajectory_data_end), ResponseCode::invalid_trajectory);
}

TEST(FpsSimTrajectory, TimesMustIncrease) {
  Harness h;
  const auto codes = upload(h, {{10, 2}, {11, 2}}, {});
  EXPECT_EQ(codes[2], ResponseCode::value_out_of_range);
}

TEST(FpsSimTrajectory, TooManyPointsAnnounced) {
  Harness h;
  EXPECT_EQ(h.code(CommandId::send_new_trajectory, two_u32(1024, 1)), ResponseCode::value_out_of_range);
  EXPECT_EQ(h.code(CommandId::send_new_trajectory, two_u32(1023, 1023)), ResponseCode::accepted);
}

TEST(FpsSimTrajectory, MorePointsThanAnnouncedIsAnInvalidTrajectory) {
  Harness h;
  ASSERT_TRUE(all_accepted(upload(h, {{10, 2}}, {})));
  EXPECT_EQ(h.code(CommandId::send_trajectory_data, point(11, 3)), ResponseCode::invalid_trajectory);
  EXPECT_EQ(h.code(CommandId::trajectory_data_end), ResponseCode::invalid_trajectory);
}

TEST(FpsSimTrajectory, EndBeforeAllPointsIsInvalid) {
  Harness h;
  ASSERT_EQ(h.code(CommandId::send_new_trajectory, two_u32(2, 0)), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::send_trajectory_data, point(10, 2)), ResponseCode::accepted);
  EXPECT_EQ(h.code(CommandId::trajectory_data_end), ResponseCode::invalid_trajectory);
  EXPECT_FALSE(h.status().has(StatusBit::receiving_trajectory));
}

TEST(FpsSimTrajectory, DataWithoutAnnouncementIsInvalid) {
  Harness h;
  EXPECT_EQ(h.code(CommandId::send_trajectory_data, point(10, 2)), ResponseCode::invalid_trajectory);
  EXPECT_EQ(h.code(CommandId::trajectory_data_end), ResponseCode::invalid_trajectory);
}

TEST(FpsSimTrajectory, AnnouncingAgainRestartsTheCount) {
  Harness h;
  ASSERT_EQ(h.code(CommandId::send_new_trajectory, two_u32(2, 0)), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::send_trajectory_data, point(10, 2)), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::send_new_trajectory, two_u32(1, 0)), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::send_trajectory_data, point(20, 2)), ResponseCode::accepted);
  EXPECT_EQ(h.code(CommandId::trajectory_data_end), ResponseCode::accepted);
}

TEST(FpsSimTrajectory, StartWithoutTrajectoryIsAcceptedAndTheRobotStays) {
  Harness h;  // the default: as robots in service do
  const auto before = h.position();
  EXPECT_EQ(h.code(CommandId::start_trajectory), ResponseCode::accepted);
  EXPECT_FALSE(h.model.moving());
  h.wait(5s);
  EXPECT_EQ(h.position(), before);
  EXPECT_TRUE(h.status().has(StatusBit::displacement_completed));
}

TEST(FpsSimTrajectory, StartWithoutTrajectoryAnswersEveryRobotOfABroadcastWithAcceptance) {
  // What a host in service relies on when it moves a subset with one START_TRAJECTORY broadcast.
  Harness loaded(test_config(1)), idle(test_config(2));
  ASSERT_TRUE(all_accepted(upload(loaded, {{10, 1}}, {})));
  ASSERT_EQ(loaded.code(CommandId::trajectory_data_end), ResponseCode::accepted);
  for (Harness* h : {&loaded, &idle}) {
    const auto out = h->send(CommandId::start_trajectory, {}, 0);
    ASSERT_EQ(out.size(), 1u);
    EXPECT_EQ(out[0].id.response, ResponseCode::accepted) << "robot " << h->id();
  }
  EXPECT_TRUE(loaded.model.moving());
  EXPECT_FALSE(idle.model.moving());
}

TEST(FpsSimTrajectory, StartWithoutTrajectoryIsInvalidWhenConfiguredSo) {
  auto c = test_config();
  c.start_without_trajectory = EmptyStart::refuse;
  Harness h(c);
  EXPECT_EQ(h.code(CommandId::start_trajectory), ResponseCode::invalid_trajectory);
  EXPECT_EQ(h.sync_pulse(10ms).at(0).id.response, ResponseCode::invalid_trajectory);
}

TEST(FpsSimTrajectory, FirstPointIsCheckedAgainAtTheStartFromWhereTheArmIsThen) {
  Harness h;
  ASSERT_TRUE(all_accepted(upload(h, {{29, 1}}, {})));
  ASSERT_EQ(h.code(CommandId::trajectory_data_end), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::go_to_absolute_position, positions(-3, 180)), ResponseCode::accepted);
  h.wait_idle();
  EXPECT_EQ(h.code(CommandId::start_trajectory), ResponseCode::value_out_of_range);  // 32 deg in 1 s
}

TEST(FpsSimTrajectory, StopInterruptsAndDropsTheTrajectory) {
  Harness h;
  ASSERT_TRUE(all_accepted(upload(h, {{90, 10}}, {})));
  ASSERT_EQ(h.code(CommandId::trajectory_data_end), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::start_trajectory), ResponseCode::accepted);
  h.wait(5s);
  ASSERT_EQ(h.code(CommandId::stop_trajectory), ResponseCode::accepted);
  h.wait(10s);
  EXPECT_NEAR(h.position().first, 45, 1e-3);
  EXPECT_EQ(h.code(CommandId::start_trajectory), ResponseCode::accepted);  // nothing left to run
  h.wait(10s);
  EXPECT_NEAR(h.position().first, 45, 1e-3);
}

TEST(FpsSimTrajectory, AbortDuringUploadDropsIt) {
  Harness h;
  ASSERT_EQ(h.code(CommandId::send_new_trajectory, two_u32(1, 0)), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::trajectory_abort), ResponseCode::accepted);
  EXPECT_FALSE(h.status().has(StatusBit::receiving_trajectory));
  EXPECT_EQ(h.code(CommandId::send_trajectory_data, point(10, 2)), ResponseCode::invalid_trajectory);
}

// Interface document 6: a rising edge, a second look a few ms later, and a start only if the line
// is still high then; the reply is START_TRAJECTORY's with uid 0.
TEST(FpsSimTrajectory, SyncLineStartsAtTheSecondLookWithUidZero) {
  Harness h;
  ASSERT_TRUE(all_accepted(upload(h, {{90, 10}}, {})));
  ASSERT_EQ(h.code(CommandId::trajectory_data_end), ResponseCode::accepted);
  const SimDuration recheck = h.model.config().sync_recheck;
  ASSERT_GT(recheck, 0ms);
  EXPECT_TRUE(h.model.set_sync_line(true, h.now).empty());
  EXPECT_EQ(h.model.sync_check_at(), h.now + recheck);
  h.wait(recheck - 1ms);
  EXPECT_FALSE(h.model.moving());
  EXPECT_TRUE(h.unsolicited.empty());
  h.wait(1ms);
  ASSERT_EQ(h.unsolicited.size(), 1u);
  EXPECT_EQ(h.unsolicited[0].id.command, 14);
  EXPECT_EQ(h.unsolicited[0].id.uid, 0);
  EXPECT_EQ(h.unsolicited[0].id.response, ResponseCode::accepted);
  EXPECT_TRUE(h.model.moving());
  EXPECT_EQ(h.model.counters().sync_starts, 1u);
  // Held high, the line starts nothing more.
  h.wait(1s);
  EXPECT_EQ(h.unsolicited.size(), 1u);
  // A second pulse finds nothing loaded: accepted, and the running trajectory goes on.
  EXPECT_TRUE(h.model.set_sync_line(false, h.now).empty());
  auto out = h.sync_pulse(500ms);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].id.response, ResponseCode::accepted);
  EXPECT_TRUE(h.model.moving());
  // With the old behaviour the motion check comes first.
  auto c = test_config();
  c.start_without_trajectory = EmptyStart::refuse;
  Harness old(c);
  ASSERT_TRUE(all_accepted(upload(old, {{10, 1}}, {})));
  ASSERT_EQ(old.code(CommandId::trajectory_data_end), ResponseCode::accepted);
  ASSERT_EQ(old.sync_pulse(500ms).at(0).id.response, ResponseCode::accepted);
  EXPECT_EQ(old.sync_pulse(500ms).at(0).id.response, ResponseCode::already_in_motion);
}

TEST(FpsSimTrajectory, SyncPulseShorterThanTheSecondLookStartsNothing) {
  Harness h;
  ASSERT_TRUE(all_accepted(upload(h, {{10, 1}}, {})));
  ASSERT_EQ(h.code(CommandId::trajectory_data_end), ResponseCode::accepted);
  const SimDuration recheck = h.model.config().sync_recheck;
  // Jitter: up and down again before the second look; its look finds the line low.
  EXPECT_TRUE(h.sync_pulse(recheck - 1ms).empty());
  h.wait(1s);
  // A bounce: the second rise arms no look of its own; the first one's finds the line low again.
  EXPECT_TRUE(h.model.set_sync_line(true, h.now).empty());
  h.wait(1ms);
  EXPECT_TRUE(h.model.set_sync_line(false, h.now).empty());
  h.wait(1ms);
  EXPECT_TRUE(h.model.set_sync_line(true, h.now).empty());  // the first look is still pending
  h.wait(recheck - 3ms);
  EXPECT_TRUE(h.model.set_sync_line(false, h.now).empty());
  h.wait(1s);
  EXPECT_TRUE(h.unsolicited.empty());
  EXPECT_FALSE(h.model.moving());
  EXPECT_EQ(h.model.counters().sync_glitches, 2u);
  EXPECT_EQ(h.model.counters().sync_starts, 0u);
  // The trajectory is still loaded: a proper pulse starts it.
  const auto out = h.sync_pulse(recheck);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].id.response, ResponseCode::accepted);
  EXPECT_TRUE(h.model.moving());
}

TEST(FpsSimTrajectory, SyncRecheckIsConfigurable) {
  auto c = test_config();
  c.sync_recheck = 0ms;  // an edge is enough
  Harness h(c);
  ASSERT_TRUE(all_accepted(upload(h, {{10, 1}}, {})));
  ASSERT_EQ(h.code(CommandId::trajectory_data_end), ResponseCode::accepted);
  const auto out = h.model.set_sync_line(true, h.now);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].id.uid, 0);
  EXPECT_TRUE(h.model.moving());
  const auto yaml = core::ConfigNode::load_string("sync_recheck_s: 0.25\n");
  ASSERT_TRUE(yaml.has_value());
  const auto read = PositionerConfig::from_config(yaml.value());
  ASSERT_TRUE(read.has_value()) << read.error().message();
  EXPECT_EQ(read.value().sync_recheck, 250ms);
}

TEST(FpsSimTrajectory, UploadNeedsTheDatum) {
  auto c = test_config();
  c.datums_initialized = false;
  Harness h(c);
  EXPECT_EQ(h.code(CommandId::send_new_trajectory, two_u32(1, 1)), ResponseCode::datum_not_initialized);
}
