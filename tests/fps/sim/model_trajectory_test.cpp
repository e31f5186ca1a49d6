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
  EXPECT_EQ(h.model.sync_pulse(h.now).at(0).id.response, ResponseCode::invalid_trajectory);
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

TEST(FpsSimTrajectory, SyncPulseStartsWithUidZero) {
  Harness h;
  ASSERT_TRUE(all_accepted(upload(h, {{10, 1}}, {})));
  ASSERT_EQ(h.code(CommandId::trajectory_data_end), ResponseCode::accepted);
  auto out = h.model.sync_pulse(h.now);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].id.command, 14);
  EXPECT_EQ(out[0].id.uid, 0);
  EXPECT_EQ(out[0].id.response, ResponseCode::accepted);
  EXPECT_TRUE(h.model.moving());
  // A second pulse finds nothing loaded: accepted, and the running trajectory goes on.
  out = h.model.sync_pulse(h.now);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].id.response, ResponseCode::accepted);
  EXPECT_TRUE(h.model.moving());
  // With the old behaviour the motion check comes first.
  auto c = test_config();
  c.start_without_trajectory = EmptyStart::refuse;
  Harness old(c);
  ASSERT_TRUE(all_accepted(upload(old, {{10, 1}}, {})));
  ASSERT_EQ(old.code(CommandId::trajectory_data_end), ResponseCode::accepted);
  ASSERT_EQ(old.model.sync_pulse(old.now).at(0).id.response, ResponseCode::accepted);
  EXPECT_EQ(old.model.sync_pulse(old.now).at(0).id.response, ResponseCode::already_in_motion);
}

TEST(FpsSimTrajectory, UploadNeedsTheDatum) {
  auto c = test_config();
  c.datums_initialized = false;
  Harness h(c);
  EXPECT_EQ(h.code(CommandId::send_new_trajectory, two_u32(1, 1)), ResponseCode::datum_not_initialized);
}
