// Checking a layout against what answered: the pure rules, then a real sweep over simulated buses.
#include "axon/fps/layout/layout_check.hpp"
#include "axon/fps/host/layout_sweep.hpp"

#include "fps/host/sim_rig.hpp"

#include <gtest/gtest.h>

namespace axon::fps {
namespace {

namespace asio = boost::asio;
using namespace std::chrono_literals;

// Robots 1-3 on gw1/1, 4-5 on gw1/2 (5 marked offline), 6 on gw2/1.
FocalPlane bench() {
  FocalPlaneSpec s;
  s.name = "check";
  s.gateways = {GatewaySite{1, "a:1", 0, 2}, GatewaySite{2, "b:1", 0, 1}};
  auto robot = [](std::uint16_t id, std::uint16_t gw, std::uint8_t ch) {
    RobotSite r;
    r.id = id;
    r.x_mm = 30.0 * id;
    r.sextant = 1;
    r.bus = BusRef{gw, ch};
    return r;
  };
  s.robots = {robot(1, 1, 1), robot(2, 1, 1), robot(3, 1, 1), robot(4, 1, 2), robot(5, 1, 2), robot(6, 2, 1)};
  s.robots[4].offline = true;
  return FocalPlane::build(s).value();
}

const BusRef b11{1, 1}, b12{1, 2}, b21{2, 1};

TEST(LayoutCheck, EverythingInPlace) {
  BusSweep sweep;
  sweep.found[b11] = {1, 2, 3};
  sweep.found[b12] = {4};
  sweep.found[b21] = {6};
  const auto c = check_layout(bench(), sweep);
  EXPECT_TRUE(c.ok()) << c.to_text();
  EXPECT_EQ(c.matched, (std::vector<std::uint16_t>{1, 2, 3, 4, 6}));
  EXPECT_EQ(c.offline_silent, (std::vector<std::uint16_t>{5}));
  EXPECT_NE(c.to_text().find("OK: 5 matched"), std::string::npos) << c.to_text();
}

TEST(LayoutCheck, MissingUnexpectedAndWrongBus) {
  BusSweep sweep;
  sweep.found[b11] = {1, 3, 4};  // 2 missing, 4 answered on the wrong bus
  sweep.found[b12] = {77};       // 77 is not in the layout
  sweep.found[b21] = {6};
  const auto c = check_layout(bench(), sweep);
  EXPECT_FALSE(c.ok());
  EXPECT_EQ(c.missing, (std::vector<std::uint16_t>{2}));
  ASSERT_EQ(c.wrong_bus.size(), 1u);
  EXPECT_EQ(c.wrong_bus[0].id, 4);
  EXPECT_EQ(c.wrong_bus[0].expected, b12);
  EXPECT_EQ(c.wrong_bus[0].found, (std::vector<BusRef>{b11}));
  ASSERT_EQ(c.unexpected.size(), 1u);
  EXPECT_EQ(c.unexpected[0].id, 77);
  const auto text = c.to_text();
  EXPECT_NE(text.find("missing      robot 2"), std::string::npos) << text;
  EXPECT_NE(text.find("robot 4 answered on gw1/1 (layout: gw1/2)"), std::string::npos) << text;
  EXPECT_NE(text.find("robot 77 answered on gw1/2"), std::string::npos) << text;
  EXPECT_NE(text.find("MISMATCH"), std::string::npos) << text;
}

TEST(LayoutCheck, SameIdOnTwoBusesIsDuplicated) {
  BusSweep sweep;
  sweep.found[b11] = {1, 2, 3, 6};
  sweep.found[b12] = {4};
  sweep.found[b21] = {6};
  const auto c = check_layout(bench(), sweep);
  EXPECT_FALSE(c.ok());
  ASSERT_EQ(c.duplicated.size(), 1u);
  EXPECT_EQ(c.duplicated[0].id, 6);
  EXPECT_TRUE(c.wrong_bus.empty());
}

TEST(LayoutCheck, OfflineRobotThatAnswersIsANoteNotAFailure) {
  BusSweep sweep;
  sweep.found[b11] = {1, 2, 3};
  sweep.found[b12] = {4, 5};
  sweep.found[b21] = {6};
  const auto c = check_layout(bench(), sweep);
  EXPECT_TRUE(c.ok());
  EXPECT_EQ(c.offline_answered, (std::vector<std::uint16_t>{5}));
}

TEST(LayoutCheck, UnsweptAndFailedBusesAreNotChecked) {
  BusSweep sweep;
  sweep.found[b11] = {1, 2, 3};
  sweep.failed[b12] = "gateway channel down";
  const auto c = check_layout(bench(), sweep);
  EXPECT_TRUE(c.ok()) << c.to_text();
  EXPECT_EQ(c.not_checked, (std::vector<std::uint16_t>{4, 5, 6}));
  EXPECT_NE(c.to_text().find("bus failed   gw1/2: gateway channel down"), std::string::npos);
}

// The sweep over two simulated buses: robot 2 is missing, 9 is on the wrong bus, 40 is a stranger.
TEST(LayoutSweep, FindsMissingWrongBusAndUnexpectedOverSimulatedBuses) {
  FocalPlaneSpec s;
  s.gateways = {GatewaySite{1, "sim", 0, 2}};
  for (std::uint16_t id : {1, 2, 3, 9}) {
    RobotSite r;
    r.id = id;
    r.x_mm = 30.0 * id;
    r.sextant = 1;
    r.bus = BusRef{1, static_cast<std::uint8_t>(id == 9 ? 2 : 1)};
    s.robots.push_back(r);
  }
  const auto plane = FocalPlane::build(s).value();

  host::testing::SimRig rig(2);
  rig.add(1, 0);
  rig.add(3, 0);
  rig.add(9, 0);
  rig.add(40, 1);
  rig.start();
  LayoutCheck check;
  rig.run([&]() -> asio::awaitable<void> {
    LayoutBuses buses{{BusRef{1, 1}, &rig.array->client(0)}, {BusRef{1, 2}, &rig.array->client(1)}};
    check = co_await check_layout_on_buses(plane, buses, 300ms);
  });
  EXPECT_EQ(check.matched, (std::vector<std::uint16_t>{1, 3}));
  EXPECT_EQ(check.missing, (std::vector<std::uint16_t>{2}));
  ASSERT_EQ(check.wrong_bus.size(), 1u);
  EXPECT_EQ(check.wrong_bus[0].id, 9);
  ASSERT_EQ(check.unexpected.size(), 1u);
  EXPECT_EQ(check.unexpected[0].id, 40);
}

}  // namespace
}  // namespace axon::fps
