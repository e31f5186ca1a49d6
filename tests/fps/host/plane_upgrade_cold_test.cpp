// After a whole-plane firmware upgrade the robots have been power-cycled and run the firmware's
// default speed and holding current; the upgrade applies the cold policy again at its end.
#include "plane_rig.hpp"

#include "axon/fps/host/cold_control.hpp"
#include "axon/fps/host/plane_upgrade.hpp"
#include "axon/fps/sim/firmware_marker.hpp"

#include <gtest/gtest.h>

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::host;
using namespace axon::fps::host::testing;
using protocol::FirmwareVersion;

namespace {

PlaneUpgradeOptions quick(bool reapply) {
  PlaneUpgradeOptions o;
  o.expected_version = FirmwareVersion{4, 2, 0};
  o.power_off_time = 50ms;
  o.bootloader_wait = 3s;
  o.boot_wait = 3s;
  o.poll = 20ms;
  o.reapply_cold = reapply;
  return o;
}

void upgrade_at_minus_12(bool reapply) {
  PlaneRig rig;
  const auto image = sim::make_firmware_image(FirmwareVersion{4, 2, 0}, 2000).value();
  rig.runner.run([&]() -> asio::awaitable<void> {
    co_await rig.connect();
    if (!rig.fpa) co_return;
    // Cold: limited speed and heating, applied before the upgrade.
    EXPECT_TRUE(rig.sim->plc()->set_sensor("fps_plate_edge", -12.0).has_value());
    ColdControl cold(*rig.fpa);
    auto c = co_await cold.step(true);
    EXPECT_TRUE(c.has_value());
    EXPECT_TRUE(robots_at(*rig.sim, 3000, 45, 30));

    auto r = co_await upgrade_plane(*rig.fpa, image, quick(reapply));
    EXPECT_TRUE(r.has_value());
    if (!r) co_return;
    EXPECT_TRUE(r.value().ok()) << r.value().summary();
    if (reapply) {
      EXPECT_TRUE(robots_at(*rig.sim, 3000, 45, 30)) << r.value().summary();
      EXPECT_TRUE(r.value().cold.has_value());
      if (r.value().cold) {
        EXPECT_EQ(r.value().cold->applied.size(), 12u);
      }
      EXPECT_NE(r.value().summary().find("cold policy re-applied after the power cycles"), std::string::npos)
          << r.value().summary();
    } else {
      // Without it the robots are back at the firmware's defaults: not heated, full speed.
      EXPECT_FALSE(robots_at(*rig.sim, 3000, 45, 30));
      EXPECT_FALSE(r.value().cold.has_value());
    }
  });
}

}  // namespace

TEST(PlaneUpgradeCold, ColdPolicyIsAppliedAgainAfterTheUpgrade) { upgrade_at_minus_12(true); }

TEST(PlaneUpgradeCold, WithoutItTheRobotsComeBackAtTheirDefaults) { upgrade_at_minus_12(false); }
