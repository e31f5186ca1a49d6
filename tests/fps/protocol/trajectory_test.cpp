#include "axon/fps/protocol/trajectory.hpp"

#include "axon/fps/protocol/error.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

using namespace axon::fps::protocol;

// The trajectory example of the interface document (table 8): 3 alpha points and 4 beta points,
// uploaded to positioner 17, then started by broadcast. Every identifier and byte is spelled out.
TEST(FpsTrajectory, ReproducesTheSpecExampleTable) {
  const std::vector<ArmPoint> alpha{{45, 5}, {90, 10}, {45, 15}};
  const std::vector<ArmPoint> beta{{90, 10}, {45, 15}, {90, 20}, {45, 25}};
  const auto t = Trajectory::from_physical(alpha, beta).value();
  const auto frames = upload_frames(17, t).value();

  // positioner 17 -> 0x440000; command 10 -> 0x2800, 11 -> 0x2C00, 12 -> 0x3000; uid n -> n << 4.
  const std::vector<std::string> expected{
      "00442810#0300000004000000",  // step 1: SEND_NEW_TRAJECTORY, 3 alpha and 4 beta points
      "00442C10#0000000810270000",  // step 2: alpha 45 deg (134217728) at 5 s (10000)
      "00442C20#00000010204E0000",  // step 3: alpha 90 deg (268435456) at 10 s (20000)
      "00442C30#0000000830750000",  // step 4: alpha 45 deg at 15 s (30000)
      "00442C40#00000010204E0000",  // step 5: beta 90 deg at 10 s
      "00442C50#0000000830750000",  // step 6: beta 45 deg at 15 s
      "00442C60#00000010409C0000",  // step 7: beta 90 deg at 20 s (40000)
      "00442C70#0000000850C30000",  // step 8: beta 45 deg at 25 s (50000)
      "00443010#",                  // step 9: TRAJECTORY_DATA_END
  };
  ASSERT_EQ(frames.size(), expected.size());
  for (std::size_t i = 0; i < frames.size(); ++i) EXPECT_EQ(frames[i].to_string(), expected[i]) << "step " << i + 1;
  // step 10: START_TRAJECTORY, broadcast with uid 0.
  EXPECT_EQ(make_request(0, CommandId::start_trajectory, 0).value().to_string(), "00003800#");

  // The same sequence from wire values.
  const auto w = Trajectory::make({{Angle::from_steps(134217728), Time::from_ticks(10000)},
                                   {Angle::from_steps(268435456), Time::from_ticks(20000)},
                                   {Angle::from_steps(134217728), Time::from_ticks(30000)}},
                                  {{Angle::from_steps(268435456), Time::from_ticks(20000)},
                                   {Angle::from_steps(134217728), Time::from_ticks(30000)},
                                   {Angle::from_steps(268435456), Time::from_ticks(40000)},
                                   {Angle::from_steps(134217728), Time::from_ticks(50000)}})
                     .value();
  EXPECT_EQ(upload_frames(17, w).value(), frames);
  EXPECT_EQ(t.size(), (TrajectorySize{3, 4}));
  EXPECT_DOUBLE_EQ(t.duration().seconds(), 25.0);
}

TEST(FpsTrajectory, RequestsInUploadOrder) {
  const std::vector<ArmPoint> alpha{{10, 1}};
  const auto t = Trajectory::from_physical(alpha, {}).value();
  const auto r = t.requests();
  ASSERT_EQ(r.size(), 3u);
  EXPECT_EQ(r[0].command, CommandId::send_new_trajectory);
  EXPECT_EQ(r[0].payload.to_hex(), "01 00 00 00 00 00 00 00");
  EXPECT_EQ(r[1].command, CommandId::send_trajectory_data);
  EXPECT_EQ(r[2].command, CommandId::trajectory_data_end);
}

TEST(FpsTrajectory, UidsWrapFrom63To1) {
  std::vector<ArmPoint> alpha;
  for (int i = 1; i <= 70; ++i) alpha.push_back({0.1 * i, 0.1 * i});
  const auto frames = upload_frames(3, Trajectory::from_physical(alpha, {}).value(), 60).value();
  auto uid = [&](std::size_t i) { return (frames[i].id() >> 4) & 0x3F; };
  EXPECT_EQ(uid(0), 60u);  // SEND_NEW_TRAJECTORY has its own count
  EXPECT_EQ(uid(1), 60u);
  EXPECT_EQ(uid(4), 63u);
  EXPECT_EQ(uid(5), 1u);
  EXPECT_EQ(uid(frames.size() - 1), 60u);  // TRAJECTORY_DATA_END
  for (const auto& f : frames) EXPECT_NE((f.id() >> 4) & 0x3F, 0u);
}

TEST(FpsTrajectory, RejectsInvalidTrajectories) {
  using V = std::vector<ArmPoint>;
  EXPECT_EQ(Trajectory::from_physical(V{}, V{}).error(), ProtocolErrc::invalid_trajectory);
  // Time 0 belongs to the firmware's own first point.
  EXPECT_EQ(Trajectory::from_physical(V{{10, 0}}, V{}).error(), ProtocolErrc::invalid_trajectory);
  EXPECT_EQ(Trajectory::from_physical(V{{10, 2}, {20, 1}}, V{}).error(), ProtocolErrc::invalid_trajectory);
  EXPECT_EQ(Trajectory::from_physical(V{}, V{{10, 2}, {20, 2}}).error(), ProtocolErrc::invalid_trajectory);
  // Two times that round to the same 0.5 ms step.
  EXPECT_EQ(Trajectory::from_physical(V{{10, 1.0}, {20, 1.0002}}, V{}).error(), ProtocolErrc::invalid_trajectory);
  EXPECT_EQ(Trajectory::from_physical(V{{800, 1}}, V{}).error(), ProtocolErrc::value_out_of_range);
  EXPECT_EQ(Trajectory::from_physical(V{{10, -1}}, V{}).error(), ProtocolErrc::value_out_of_range);
  V many;
  for (int i = 1; i <= 1024; ++i) many.push_back({0, 0.01 * i});
  EXPECT_EQ(Trajectory::from_physical(many, V{}).error(), ProtocolErrc::invalid_trajectory);
  many.pop_back();
  const auto ok = Trajectory::from_physical(many, many);
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok.value().request_count(), 2u + 2 * 1023);
  EXPECT_EQ(upload_frames(0, ok.value()).error(), ProtocolErrc::broadcast_not_allowed);
  EXPECT_EQ(upload_frames(1, ok.value(), 0).error(), ProtocolErrc::uid_out_of_range);
}
