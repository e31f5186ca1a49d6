#include "axon/c4g/protocol/axis_map.hpp"

#include "axon/c4g/protocol/error.hpp"
#include "c4g/protocol/example_init.hpp"

#include <gtest/gtest.h>

using namespace axon::c4g::protocol;
using axon::c4g::protocol::test::manual_example_init;

TEST(C4gAxisMap, ManualExampleIsArmOneAxesOneToSix) {
  const auto m = AxisMap::from_init(manual_example_init()).value();
  ASSERT_EQ(m.count(), 6u);
  for (std::size_t i = 0; i < 6; ++i) {
    EXPECT_EQ(m.logical(i), (AxisRef{1, static_cast<std::uint8_t>(i + 1)}));
    EXPECT_EQ(m.open_index(1, i + 1), i);
  }
  EXPECT_EQ(m.logical(6), AxisRef{});
  EXPECT_EQ(m.open_index(1, 7), std::nullopt);
  EXPECT_EQ(m.open_index(2, 1), std::nullopt);
  EXPECT_EQ(m.arm_count(1), 6u);
  EXPECT_EQ(m.arm_count(2), 0u);
  EXPECT_EQ(m.arm_first(1), 0u);
  EXPECT_EQ(m.arm_first(2), 6u);
  const auto limits = m.per_open_axis(manual_example_init().current_limit);
  EXPECT_EQ(limits[0], 24.5f);
  EXPECT_EQ(limits[5], 9.5f);
  EXPECT_EQ(limits[6], 0.0f);
}

TEST(C4gAxisMap, TwoArmsWithGapsMapInArmThenListOrder) {
  InitPacket p = manual_example_init();
  p.open_axes = 5;
  p.open_axis_list[0] = {2, 5, -1, 3, 0, 0, 0, 0, 0, 0};  // arm 1: logical 2, 5, 3 (a gap is skipped)
  p.open_axis_list[2] = {7, 1, 0, 0, 0, 0, 0, 0, 0, 0};   // arm 3: logical 7, 1
  p.modes[2][6] = 4;                                      // arm 3 axis 7 starts in mode 4
  p.current_limit[2][6] = 3.0f;
  const auto m = AxisMap::from_init(p).value();
  ASSERT_EQ(m.count(), 5u);
  EXPECT_EQ(m.logical(0), (AxisRef{1, 2}));
  EXPECT_EQ(m.logical(1), (AxisRef{1, 5}));
  EXPECT_EQ(m.logical(2), (AxisRef{1, 3}));
  EXPECT_EQ(m.logical(3), (AxisRef{3, 7}));
  EXPECT_EQ(m.logical(4), (AxisRef{3, 1}));
  EXPECT_EQ(m.open_index(3, 1), 4u);
  EXPECT_EQ(m.arm_first(3), 3u);
  EXPECT_EQ(m.arm_count(3), 2u);
  EXPECT_EQ(m.startup_mode(3), 4);
  EXPECT_EQ(m.startup_mode(0), 0);
  EXPECT_EQ(m.per_open_axis(p.current_limit)[3], 3.0f);
}

TEST(C4gAxisMap, RejectsInconsistentLists) {
  InitPacket p = manual_example_init();
  p.open_axes = 5;  // lists name 6
  EXPECT_EQ(AxisMap::from_init(p).error(), ProtocolErrc::bad_axis_map);
  p = manual_example_init();
  p.open_axis_list[0][1] = 1;  // axis 1 twice
  EXPECT_EQ(AxisMap::from_init(p).error(), ProtocolErrc::bad_axis_map);
  p = manual_example_init();
  p.open_axis_list[0][6] = 11;  // no logical axis 11
  EXPECT_EQ(AxisMap::from_init(p).error(), ProtocolErrc::bad_axis_map);
  p = manual_example_init();
  p.open_axes = 20;
  for (auto& arm : p.open_axis_list) arm = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10};  // 40 axes
  EXPECT_EQ(AxisMap::from_init(p).error(), ProtocolErrc::bad_axis_map);
}
