#include "axon/fps/layout/focal_plane.hpp"
#include "axon/fps/sim/focal_plane_sim.hpp"
#include "axon/web/fps_sim_view.hpp"

#include <boost/asio/io_context.hpp>
#include <gtest/gtest.h>

namespace axon::web {
namespace {

namespace sim = fps::sim;

// Three robots in a row on two buses of one gateway, two fiducials; the simulator on this thread.
class FpsSimViewTest : public ::testing::Test {
 protected:
  FpsSimViewTest() {
    fps::FocalPlaneSpec spec;
    spec.name = "row";
    spec.gateways = {fps::GatewaySite{1, "127.0.0.1:1", 1, 4}};
    for (std::uint16_t id = 1; id <= 3; ++id) {
      fps::RobotSite r;
      r.id = id;
      r.x_mm = 22.4 * id;  // 22.4, 44.8, 67.2
      r.sextant = 1;
      r.bus = fps::BusRef{1, static_cast<std::uint8_t>(id < 3 ? 1 : 2)};
      spec.robots.push_back(r);
    }
    spec.fiducials = {{1, 0, 20}, {2, 90, 20}};
    plane_ = std::make_unique<fps::FocalPlane>(fps::FocalPlane::build(spec).value());
    sim::FocalPlaneSimOptions o;
    o.plc = false;
    o.random_start = false;
    sim_ = sim::FocalPlaneSimulator::start(io_.get_executor(), *plane_, o).value();
    view_ = std::make_unique<FpsSimView>(*plane_, *sim_);
  }
  ~FpsSimViewTest() override {
    view_.reset();
    sim_->stop();
    io_.poll();
  }

  boost::asio::io_context io_;
  std::unique_ptr<fps::FocalPlane> plane_;
  std::unique_ptr<sim::FocalPlaneSimulator> sim_;
  std::unique_ptr<FpsSimView> view_;
};

TEST_F(FpsSimViewTest, InfoHasEveryRobotFiducialAndStatusBit) {
  const auto info = view_->info_json();
  EXPECT_NE(info.find("{\"id\":1,\"x\":22.4,\"y\":0,\"orientation\":0,\"alpha_mm\":7.4,\"beta_mm\":14.7,\"bus\":\"gw1/1\",\"sextant\":1}"),
            std::string::npos) << info;
  EXPECT_NE(info.find("\"fiducials\":[{\"id\":1,\"x\":0,\"y\":20},{\"id\":2,\"x\":90,\"y\":20}]"), std::string::npos) << info;
  EXPECT_NE(info.find("{\"bit\":12,\"name\":\"COLLISION_BETA\""), std::string::npos) << info;
  EXPECT_NE(info.find("\"states\":[\"ready\",\"moving\",\"not-initialised\",\"collided\",\"offline\",\"bootloader\"]"),
            std::string::npos) << info;
}

TEST_F(FpsSimViewTest, StateHasEveryRobotFoldedAndReady) {
  view_->update();
  const auto state = view_->state_json();
  EXPECT_NE(state.find("\"states\":{\"ready\":3,\"moving\":0,"), std::string::npos) << state;
  EXPECT_NE(state.find("{\"id\":2,\"a\":0.000,\"b\":180.000,\"s\":\"ready\",\"st\":\""), std::string::npos) << state;
  EXPECT_NE(state.find("\"fw\":\"04.01.13\""), std::string::npos) << state;
  EXPECT_NE(state.find("\"lock\":{\"locked\":false,\"robot\":0,"), std::string::npos) << state;
}

TEST_F(FpsSimViewTest, ACollisionLocksAndNamesTheFirstRobotUntilTheFlagsClear) {
  ASSERT_TRUE(sim_->simulator().force_collision(3, sim::Arm::beta));
  view_->update();
  ASSERT_TRUE(sim_->simulator().force_collision(1, sim::Arm::alpha));
  view_->update();
  const auto& lock = view_->lock();
  EXPECT_TRUE(lock.locked);
  EXPECT_EQ(lock.robot, 3);  // first seen, although robot 1 has the lower id
  EXPECT_EQ(lock.bus, "gw1/2");
  EXPECT_EQ(lock.arm, "beta");
  EXPECT_EQ(lock.collided, (std::vector<std::uint16_t>{3, 1}));
  EXPECT_EQ(lock.count, 1u);
  const auto state = view_->state_json();
  EXPECT_NE(state.find("\"lock\":{\"locked\":true,\"robot\":3,\"bus\":\"gw1/2\",\"arm\":\"beta\",\"count\":1,\"collided\":[3,1]}"),
            std::string::npos) << state;
  EXPECT_NE(state.find("{\"id\":3,\"a\":0.000,\"b\":180.000,\"s\":\"collided\""), std::string::npos) << state;
  const auto metrics = view_->metrics();
  EXPECT_NE(metrics.find("\naxon_fps_sim_locked 1\n"), std::string::npos);
  EXPECT_NE(metrics.find("\naxon_fps_sim_bus_locks_total{bus=\"gw1/2\"} 1\n"), std::string::npos) << metrics;
  EXPECT_NE(metrics.find("\naxon_fps_sim_robot_collision_reports_total{robot=\"3\",bus=\"gw1/2\"} 1\n"), std::string::npos)
      << metrics;
}

TEST_F(FpsSimViewTest, PublishSendsStateEveryTimeAndMetricsEveryNth) {
  Source source("fps", "row");
  view_->publish(source, 3);
  const auto first_metrics = source.metrics();
  ASSERT_NE(first_metrics, nullptr);
  EXPECT_NE(first_metrics->find("# TYPE axon_fps_sim_robots gauge\naxon_fps_sim_robots{state=\"ready\"} 3\n"), std::string::npos)
      << *first_metrics;
  view_->publish(source, 3);
  view_->publish(source, 3);
  EXPECT_EQ(source.latest()->sequence, 3u);
  EXPECT_EQ(source.metrics(), first_metrics);  // not rebuilt yet
  view_->publish(source, 3);
  EXPECT_NE(source.metrics(), first_metrics);
}

}  // namespace
}  // namespace axon::web
