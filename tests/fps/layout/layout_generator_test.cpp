// The generated default layout: the counts the electrical interface prescribes and a clean grid.
#include "axon/fps/layout/layout_generator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

namespace axon::fps {
namespace {

const FocalPlane& plane() {
  static const FocalPlane p = generate_layout().value();
  return p;
}

TEST(LayoutGenerator, FiveHundredRobotsWithDistinctIds) {
  EXPECT_EQ(plane().robots().size(), 500u);
  std::set<std::uint16_t> ids;
  for (const auto& r : plane().robots()) ids.insert(r.id);
  EXPECT_EQ(ids.size(), 500u);
  EXPECT_EQ(*ids.begin(), 1);
  EXPECT_EQ(*ids.rbegin(), 500);
}

TEST(LayoutGenerator, SextantsHold83Or84RobotsAndOneGatewayEach) {
  const auto by = plane().by_sextant();
  ASSERT_EQ(by.size(), 6u);
  int with84 = 0;
  for (const auto& [s, ids] : by) {
    EXPECT_TRUE(ids.size() == 83 || ids.size() == 84) << "sextant " << s << ": " << ids.size();
    with84 += ids.size() == 84 ? 1 : 0;
    for (auto id : ids) EXPECT_EQ(plane().find(id)->bus.gateway, s);
  }
  EXPECT_EQ(with84, 2);
  ASSERT_EQ(plane().gateways().size(), 6u);
  for (const auto& g : plane().gateways()) {
    EXPECT_EQ(g.channels, 4);
    EXPECT_EQ(g.sextant, g.id);
  }
}

TEST(LayoutGenerator, TwentyFourBusesOf20To21Robots) {
  const auto by = plane().by_bus();
  ASSERT_EQ(by.size(), 24u);
  for (const auto& [bus, ids] : by) {
    EXPECT_GE(ids.size(), 20u) << bus.to_string();
    EXPECT_LE(ids.size(), 21u) << bus.to_string();
    EXPECT_GE(bus.channel, 1);
    EXPECT_LE(bus.channel, 4);
  }
}

TEST(LayoutGenerator, RobotsAndFiducialsSitOnTheHexGrid) {
  const double p = plane().pitch_mm();
  EXPECT_DOUBLE_EQ(p, 22.4);
  const double row = p * std::sqrt(3.0) / 2;
  auto on_grid = [&](double x, double y) {
    const double r = y / row;
    if (std::abs(r - std::round(r)) > 1e-9) return false;
    const double q = x / p - std::round(r) / 2;
    return std::abs(q - std::round(q)) < 1e-9;
  };
  double nearest = 1e9;
  const auto& robots = plane().robots();
  for (std::size_t i = 0; i < robots.size(); ++i) {
    EXPECT_TRUE(on_grid(robots[i].x_mm, robots[i].y_mm)) << robots[i].id;
    for (std::size_t j = 0; j < i; ++j)
      nearest = std::min(nearest, std::hypot(robots[i].x_mm - robots[j].x_mm, robots[i].y_mm - robots[j].y_mm));
  }
  EXPECT_NEAR(nearest, p, 1e-9);
  EXPECT_EQ(plane().fiducials().size(), 61u);
  for (const auto& f : plane().fiducials()) EXPECT_TRUE(on_grid(f.x_mm, f.y_mm)) << "fiducial " << f.id;
  // Compact: everything within the field the planner in service uses.
  for (const auto& r : robots) {
    EXPECT_LE(std::abs(r.x_mm), 300.0);
    EXPECT_LE(std::abs(r.y_mm), 300.0);
  }
}

TEST(LayoutGenerator, ThreeHundredApogeeFibresAndEveryRobotHasBoss) {
  int apogee = 0;
  for (const auto& r : plane().robots()) {
    EXPECT_TRUE(r.carries(Fibre::boss));
    EXPECT_TRUE(r.carries(Fibre::metrology));
    apogee += r.carries(Fibre::apogee) ? 1 : 0;
  }
  EXPECT_EQ(apogee, 300);
}

TEST(LayoutGenerator, InteriorRobotsHaveSixAdjacentAndEighteenNeighbours) {
  const auto& p = plane();
  int interior = 0;
  std::size_t most = 0;
  for (const auto& r : p.robots()) {
    const auto& n = p.neighbours(r.id);
    EXPECT_LE(n.adjacent.size(), 6u);
    most = std::max(most, n.robots.size());
    // Interior: all six grid sites around it are robots or fiducials.
    int occupied = 0;
    for (int k = 0; k < 6; ++k) {
      const double a = k * 3.14159265358979 / 3;
      const double x = r.x_mm + p.pitch_mm() * std::cos(a);
      const double y = r.y_mm + p.pitch_mm() * std::sin(a);
      for (const auto& o : p.robots()) occupied += std::hypot(o.x_mm - x, o.y_mm - y) < 1e-6 ? 1 : 0;
    }
    if (occupied == 6) {
      ++interior;
      EXPECT_EQ(n.adjacent.size(), 6u) << r.id;
    }
    for (auto id : n.robots) {
      const auto* o = p.find(id);
      EXPECT_LE(std::hypot(o->x_mm - r.x_mm, o->y_mm - r.y_mm), p.neighbour_options().robot_radius_mm);
    }
  }
  EXPECT_GT(interior, 150);  // 200: the rest touch the edge or a fiducial
  EXPECT_EQ(most, 18u);  // 6 at one pitch, 6 at sqrt(3) pitches, 6 at two pitches
  // Symmetric relation.
  for (const auto& r : p.robots())
    for (auto id : p.neighbours(r.id).robots) {
      const auto& back = p.neighbours(id).robots;
      EXPECT_NE(std::find(back.begin(), back.end(), r.id), back.end());
    }
}

TEST(LayoutGenerator, RobotsNextToFiducialsKnowThem) {
  const auto& p = plane();
  // The centre fiducial (1) has six robots around it, each of which lists it first.
  int around_centre = 0;
  for (const auto& r : p.robots()) {
    if (std::hypot(r.x_mm, r.y_mm) < p.pitch_mm() + 1e-6) {
      ++around_centre;
      ASSERT_FALSE(p.neighbours(r.id).fiducials.empty());
      EXPECT_EQ(p.neighbours(r.id).fiducials.front(), 1);
    }
  }
  EXPECT_EQ(around_centre, 6);
}

TEST(LayoutGenerator, OtherCountsAndBadOptions) {
  LayoutGeneratorOptions o;
  o.robots = 60;
  o.fiducials_per_sextant = 2;
  o.apogee_per_sextant = 5;
  auto small = generate_layout(o);
  ASSERT_TRUE(small.has_value()) << small.error().message();
  EXPECT_EQ(small.value().robots().size(), 60u);
  EXPECT_EQ(small.value().fiducials().size(), 13u);
  o.robots = 3;
  EXPECT_FALSE(generate_layout(o).has_value());
  o.robots = 500;
  o.buses_per_sextant = 5;
  EXPECT_FALSE(generate_layout(o).has_value());
}

}  // namespace
}  // namespace axon::fps
