// The planner's request from a status table: unknown poses are refused, robots not ready are held.
#include "axon/fps/host/plan_and_move.hpp"
#include "axon/fps/layout/layout_name.hpp"
#include "axon/fps/plan/layout_model.hpp"

#include <gtest/gtest.h>

namespace axon::fps::host {
namespace {

struct Benchtop {
  FocalPlane plane = resolve_layout("benchtop").value();
  plan::CollisionModel model = plan::model_from_layout(plane).value();

  // Every robot at (0, 180) and ready to move, but `silent`, which did not answer.
  StatusTable table(std::uint16_t silent = 0) const {
    StatusTable t;
    for (const auto& r : model.robots()) {
      const auto id = static_cast<std::uint16_t>(r.id());
      StatusRow row;
      row.id = id;
      if (id == silent) {
        row.error = "timeout";
      } else {
        row.position = ArmAngles{0, 180};
        row.status = protocol::PositionerStatus()
                         .set(protocol::StatusBit::system_initialized)
                         .set(protocol::StatusBit::datum_alpha_initialized)
                         .set(protocol::StatusBit::datum_beta_initialized)
                         .set(protocol::StatusBit::displacement_completed);
      }
      t.rows.push_back(row);
    }
    return t;
  }
  std::vector<plan::Pose> targets() const { return std::vector<plan::Pose>(model.size(), plan::Pose{40, 160}); }
};

TEST(RequestFromStatus, RefusesToPlanAroundARobotWithoutAPosition) {
  Benchtop b;
  const auto r = request_from_status(b.plane, b.model, b.table(3), b.targets());
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error().code, HostErrc::unknown_positioner);
  EXPECT_NE(r.error().detail.find("robots 3 "), std::string::npos) << r.error().detail;
}

TEST(RequestFromStatus, StartsFromTheReadPositions) {
  Benchtop b;
  const auto req = request_from_status(b.plane, b.model, b.table(), b.targets()).value();
  ASSERT_EQ(req.current.size(), b.model.size());
  EXPECT_DOUBLE_EQ(req.current[0].beta_deg, 180.0);
}

TEST(RequestFromStatus, HoldsRobotsThatAreNotReady) {
  Benchtop b;
  auto table = b.table();
  table.rows[1].status = protocol::PositionerStatus();  // no datum
  const auto req = request_from_status(b.plane, b.model, table, b.targets()).value();
  EXPECT_TRUE(req.frozen[1]);
  EXPECT_DOUBLE_EQ(req.target[1].alpha_deg, 0.0);
  EXPECT_DOUBLE_EQ(req.target[0].alpha_deg, 40.0);
}

TEST(RequestFromStatus, WantsOneTargetPerRobot) {
  Benchtop b;
  EXPECT_EQ(request_from_status(b.plane, b.model, b.table(), {}).error().code, HostErrc::invalid_argument);
}

}  // namespace
}  // namespace axon::fps::host
