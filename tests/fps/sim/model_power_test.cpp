// PositionerModel: power cycles (what survives, what is reset), the bootloader, firmware upgrades
// with good and bad CRCs, and the watchdog's return to the previous image.
#include "axon/fps/protocol/firmware_image.hpp"
#include "axon/fps/sim/firmware_marker.hpp"
#include "harness.hpp"

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::sim;
using namespace axon::fps::sim::testing;
using protocol::BootloaderBit;

namespace {

protocol::BootloaderStatus boot_status(Harness& h) {
  const auto m = h.ask(CommandId::get_status);
  EXPECT_EQ(m.payload.size(), 4u);
  return protocol::BootloaderStatus::decode(m.payload.span()).value();
}

std::string version(Harness& h) {
  return protocol::FirmwareVersion::decode(h.ask(CommandId::get_firmware_version).payload.span()).value().to_string();
}

// Sends the whole image; returns the number of refused frames.
int upload(Harness& h, const protocol::FirmwareImage& image) {
  int refused = h.code(CommandId::start_firmware_upgrade, image.header().encode()) == ResponseCode::accepted ? 0 : 1;
  for (std::size_t i = 0; i < image.chunk_count(); ++i) {
    if (h.code(CommandId::firmware_data, image.chunk(i).encode()) != ResponseCode::accepted) ++refused;
  }
  return refused;
}

}  // namespace

TEST(FpsSimPower, SilentWhileOffAndWhileBooting) {
  Harness h;  // boot time 50 ms
  h.model.power_off(h.now);
  EXPECT_EQ(h.model.run_state(), RunState::off);
  EXPECT_TRUE(h.send(CommandId::get_id).empty());
  h.model.power_on(h.now);
  EXPECT_EQ(h.model.run_state(), RunState::booting);
  EXPECT_TRUE(h.send(CommandId::get_id).empty());
  h.wait(50ms);
  EXPECT_EQ(h.model.run_state(), RunState::application);
  EXPECT_EQ(h.code(CommandId::get_id), ResponseCode::accepted);
  EXPECT_EQ(h.model.counters().ignored, 2u);
}

TEST(FpsSimPower, PositionIsSavedAtPowerDownAndRestored) {
  Harness h;
  ASSERT_EQ(h.code(CommandId::go_to_absolute_position, positions(30, 100)), ResponseCode::accepted);
  h.wait_idle();
  h.model.power_cycle(h.now);
  h.wait(1s);
  const auto s = h.status();
  EXPECT_TRUE(s.initialized());
  EXPECT_TRUE(s.has(StatusBit::position_restored));
  EXPECT_FALSE(s.has(StatusBit::estimated_position));
  EXPECT_NEAR(h.position().first, 30, 1e-6);
  EXPECT_NEAR(h.position().second, 100, 1e-6);
}

TEST(FpsSimPower, PowerLostDuringAMoveLeavesAnEstimate) {
  Harness h;
  ASSERT_EQ(h.code(CommandId::go_to_absolute_position, positions(90, 180)), ResponseCode::accepted);
  h.wait(1s);
  h.model.power_cycle(h.now);
  h.wait(1s);
  const auto s = h.status();
  EXPECT_TRUE(s.has(StatusBit::estimated_position));
  EXPECT_TRUE(s.has(StatusBit::displacement_completed));
  EXPECT_NEAR(h.model.physical_deg(Arm::alpha), 12, 1e-3);  // stopped where the power went
}

TEST(FpsSimPower, PowerLostWithoutSavingLosesTheDatum) {
  Harness h;
  h.model.power_off(h.now, /*save_position=*/false);
  h.model.power_on(h.now);
  h.wait(1s);
  const auto s = h.status();
  EXPECT_FALSE(s.has(StatusBit::datum_alpha_initialized));
  EXPECT_FALSE(s.has(StatusBit::datum_beta_initialized));
  EXPECT_FALSE(s.has(StatusBit::position_restored));
  EXPECT_EQ(h.code(CommandId::go_to_absolute_position, positions(1, 1)), ResponseCode::datum_not_initialized);
  EXPECT_EQ(h.code(CommandId::go_to_relative_position, positions(1, 1)), ResponseCode::accepted);  // allowed blind
}

TEST(FpsSimPower, VolatileSettingsReturnToTheirDefaults) {
  Harness h;
  ASSERT_EQ(h.code(CommandId::alpha_open_loop_without_collision_detection), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::switch_off_precise_move_beta), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::set_speed, two_u32(1000, 1000)), ResponseCode::accepted);
  ASSERT_EQ(h.code(CommandId::switch_off_hall), ResponseCode::accepted);
  (void)h.model.inject_collision(Arm::beta, h.now);
  h.model.power_cycle(h.now);
  h.wait(1s);
  const auto s = h.status();
  EXPECT_TRUE(s.has(StatusBit::closed_loop_alpha));
  EXPECT_FALSE(s.has(StatusBit::collision_detect_alpha_disable));
  EXPECT_TRUE(s.has(StatusBit::precise_move_beta));
  EXPECT_FALSE(s.hall_disabled());
  EXPECT_FALSE(s.collided());
  const auto t = protocol::ArmTimes::decode(h.ask(CommandId::go_to_relative_position, positions(12, 0)).payload.span());
  EXPECT_NEAR(t.value().alpha.seconds(), (12 + 1.8) / 12.0, 0.001);  // back at 2000 rpm
}

TEST(FpsSimBootloader, SyncLineLowAtPowerOnEntersTheBootloader) {
  Harness h;
  h.model.power_cycle(h.now, /*sync_line_low=*/true);
  EXPECT_EQ(h.model.run_state(), RunState::bootloader);
  EXPECT_EQ(version(h), "03.80.01");
  EXPECT_TRUE(boot_status(h).has(BootloaderBit::bootloader_init));
  EXPECT_EQ(h.code(CommandId::get_id), ResponseCode::accepted);
  EXPECT_EQ(h.code(CommandId::go_to_absolute_position, positions(1, 1)), ResponseCode::invalid_bootloader_command);
  EXPECT_EQ(h.code(CommandId::stop_trajectory), ResponseCode::invalid_bootloader_command);
  EXPECT_EQ(h.ask(CommandId::get_id, Payload().put_u8(1)).id.response, ResponseCode::incorrect_data_length);
  EXPECT_EQ(h.raw(77).at(0).id.response, ResponseCode::unknown_command);
  auto out = h.send(CommandId::start_firmware_upgrade, two_u32(8, 0), 0);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].id.response, ResponseCode::invalid_broadcast);
  EXPECT_TRUE(h.sync_pulse(10ms).empty());
}

TEST(FpsSimBootloader, TimesOutIntoTheApplicationAndValidCommandsRestartTheWait) {
  Harness h;  // 10 s wait, 50 ms boot
  h.model.power_cycle(h.now, true);
  h.wait(9s);
  ASSERT_EQ(h.code(CommandId::get_status), ResponseCode::accepted);  // restarts the 10 s
  h.wait(9s);
  (void)h.raw(77);  // refused commands do not count
  EXPECT_EQ(h.model.run_state(), RunState::bootloader);
  h.wait(1s + 10ms);
  EXPECT_EQ(h.model.run_state(), RunState::booting);
  h.wait(50ms);
  EXPECT_EQ(h.model.run_state(), RunState::application);
  EXPECT_EQ(version(h), "04.01.13");
}

TEST(FpsSimBootloader, UpgradeWithGoodChecksumReplacesTheApplication) {
  Harness h;
  h.model.power_cycle(h.now, true);
  const auto bytes = make_firmware_image({4, 1, 20}, 1003).value();
  const auto image = protocol::FirmwareImage::make(bytes).value();
  ASSERT_EQ(h.code(CommandId::start_firmware_upgrade, image.header().encode()), ResponseCode::accepted);
  EXPECT_TRUE(boot_status(h).receiving());
  for (std::size_t i = 0; i < image.chunk_count(); ++i) {
    ASSERT_EQ(h.code(CommandId::firmware_data, image.chunk(i).encode()), ResponseCode::accepted) << i;
  }
  const auto s = boot_status(h);
  EXPECT_FALSE(s.receiving());
  EXPECT_TRUE(s.upgrade_succeeded());
  EXPECT_TRUE(s.has(BootloaderBit::bsettings_changed));
  EXPECT_FALSE(s.upgrade_failed());
  EXPECT_EQ(version(h), "03.80.01");  // still the bootloader
  h.model.power_cycle(h.now);
  h.wait(1s);
  EXPECT_EQ(version(h), "04.01.20");
  EXPECT_EQ(h.model.counters().firmware_received, 1u);
}

TEST(FpsSimBootloader, BadChecksumIsReportedAndTheOldImageStays) {
  Harness h;
  h.model.power_cycle(h.now, true);
  const auto bytes = make_firmware_image({4, 1, 20}, 64).value();
  const auto image = protocol::FirmwareImage::make(bytes).value();
  auto header = image.header();
  header.crc32 ^= 1;
  ASSERT_EQ(h.code(CommandId::start_firmware_upgrade, header.encode()), ResponseCode::accepted);
  for (std::size_t i = 0; i < image.chunk_count(); ++i) {
    ASSERT_EQ(h.code(CommandId::firmware_data, image.chunk(i).encode()), ResponseCode::accepted);
  }
  const auto s = boot_status(h);
  EXPECT_TRUE(s.has(BootloaderBit::new_firmware_received));
  EXPECT_TRUE(s.upgrade_failed());
  EXPECT_FALSE(s.has(BootloaderBit::new_firmware_check_ok));
  h.model.power_cycle(h.now);
  h.wait(1s);
  EXPECT_EQ(version(h), "04.01.13");
  EXPECT_EQ(h.model.counters().firmware_rejected, 1u);
}

TEST(FpsSimBootloader, UpgradeRefusals) {
  auto c = test_config();
  c.max_firmware_size = 100;
  Harness h(c);
  h.model.power_cycle(h.now, true);
  EXPECT_EQ(h.code(CommandId::start_firmware_upgrade, two_u32(101, 0)), ResponseCode::value_out_of_range);
  EXPECT_EQ(h.code(CommandId::start_firmware_upgrade, two_u32(0, 0)), ResponseCode::value_out_of_range);
  EXPECT_EQ(h.code(CommandId::firmware_data, Payload().put_u32(1)), ResponseCode::value_out_of_range);  // no header
  ASSERT_EQ(h.code(CommandId::start_firmware_upgrade, two_u32(12, 0)), ResponseCode::accepted);
  EXPECT_EQ(h.code(CommandId::firmware_data, Payload().put_u32(1)), ResponseCode::incorrect_data_length);  // 4 of 8
  EXPECT_EQ(h.code(CommandId::firmware_data, Payload().put_u64(1)), ResponseCode::accepted);
  EXPECT_EQ(h.code(CommandId::firmware_data, Payload().put_u64(1)), ResponseCode::incorrect_data_length);  // 8 of 4
  EXPECT_EQ(h.code(CommandId::firmware_data, Payload().put_u32(1)), ResponseCode::accepted);
  EXPECT_EQ(h.code(CommandId::firmware_data, Payload().put_u32(1)), ResponseCode::value_out_of_range);  // complete
  EXPECT_EQ(h.code(CommandId::firmware_data, Payload()), ResponseCode::incorrect_data_length);
}

TEST(FpsSimBootloader, ImageThatDoesNotBootIsReplacedByTheWatchdog) {
  Harness h;  // watchdog 30 s
  h.model.power_cycle(h.now, true);
  const auto bytes = make_bricked_firmware_image(200).value();
  ASSERT_EQ(upload(h, protocol::FirmwareImage::make(bytes).value()), 0);
  EXPECT_TRUE(boot_status(h).upgrade_succeeded());  // the CRC is fine
  h.model.power_cycle(h.now);
  EXPECT_EQ(h.model.run_state(), RunState::failed_boot);
  h.wait(29s);
  EXPECT_TRUE(h.send(CommandId::get_id).empty());
  h.wait(1s);
  h.wait(50ms);
  EXPECT_EQ(h.model.run_state(), RunState::application);
  EXPECT_EQ(version(h), "04.01.13");
  EXPECT_EQ(h.model.counters().watchdog_resets, 1u);
}

TEST(FpsSimBootloader, TheBackupIsTheLastImageThatBooted) {
  Harness h;
  h.model.power_cycle(h.now, true);
  ASSERT_EQ(upload(h, protocol::FirmwareImage::make(make_firmware_image({4, 1, 20}, 100).value()).value()), 0);
  h.model.power_cycle(h.now);
  h.wait(1s);
  ASSERT_EQ(version(h), "04.01.20");  // booted: the next bootloader entry keeps it as backup
  h.model.power_cycle(h.now, true);
  EXPECT_TRUE(boot_status(h).has(BootloaderBit::bsettings_changed));
  EXPECT_EQ(h.model.flash().backup.version, (protocol::FirmwareVersion{4, 1, 20}));
  ASSERT_EQ(upload(h, protocol::FirmwareImage::make(make_bricked_firmware_image(100).value()).value()), 0);
  h.model.power_cycle(h.now);
  h.wait(31s);
  EXPECT_EQ(version(h), "04.01.20");
}

TEST(FpsSimBootloader, ImageWithoutTagKeepsTheVersionNumber) {
  Harness h;
  h.model.power_cycle(h.now, true);
  const std::vector<std::uint8_t> bytes(37, 0xA5);
  ASSERT_EQ(upload(h, protocol::FirmwareImage::make(bytes).value()), 0);
  EXPECT_TRUE(boot_status(h).upgrade_succeeded());
  h.model.power_cycle(h.now);
  h.wait(1s);
  EXPECT_EQ(version(h), "04.01.13");
  EXPECT_EQ(h.model.flash().main.crc32, protocol::firmware_crc32(bytes));
}
