// Positioner against the simulator: every command of the main application's and the bootloader's
// tables through the host API, checked against the simulated robot's state; the datum search and
// the calibration sequence waiting on the status flags.
#include "sim_rig.hpp"

#include "axon/fps/protocol/error.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace axon;
using namespace axon::fps;
using namespace axon::fps::host;
using namespace axon::fps::host::testing;
using protocol::CommandId;
using protocol::ResponseCode;
using protocol::StatusBit;

namespace {

// EXPECT that a Result holds a value; returns it (or a default) so the test can go on.
template <class T>
T value_of(Result<T> r, const char* what) {
  EXPECT_TRUE(r.has_value()) << what << ": " << (r ? "" : r.error().message());
  if (!r) return T{};
  return std::move(r).value();
}
void expect_ok(const Result<void>& r, const char* what) {
  EXPECT_TRUE(r.has_value()) << what << ": " << (r ? "" : r.error().message());
}

constexpr double kTol = 1e-3;

}  // namespace

TEST(PositionerSim, ReadsOfTheMainApplication) {
  SimRig rig;
  rig.add(7, 0);
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    Positioner& p = *rig.array->find(7);
    auto& m = rig.model(7);
    EXPECT_EQ(value_of(co_await p.read_firmware_version(), "version"), (protocol::FirmwareVersion{4, 1, 13}));
    EXPECT_EQ(value_of(co_await p.read_status(), "status").raw(), m.status().raw());
    const auto pos = value_of(co_await p.read_position(), "position");
    EXPECT_NEAR(pos.alpha, m.reported_deg(sim::Arm::alpha), kTol);
    EXPECT_NEAR(pos.beta, 180.0, kTol);
    const auto hall = value_of(co_await p.read_hall_position(), "hall");
    EXPECT_NEAR(hall.beta, m.hall_deg(sim::Arm::beta), kTol);
    const auto off = value_of(co_await p.read_offsets(), "offsets");
    EXPECT_EQ(off, (ArmAngles{0, 0}));
    (void)value_of(co_await p.read_datum_calibration_error(), "datum error");
    (void)value_of(co_await p.read_motor_calibration_error(), "motor error");
    const auto hold = value_of(co_await p.read_holding_current(), "holding");
    EXPECT_EQ(hold.alpha.percent(), 0u);
    EXPECT_EQ(hold.beta.percent(), 30u);
    EXPECT_EQ(value_of(co_await p.read_currents(), "currents").beta, 30);  // holding current while idle
    (void)value_of(co_await p.read_torques(), "torques");
    EXPECT_NEAR(value_of(co_await p.read_position_and_current(Arm::beta), "pos+cur").position.degrees(), 180.0, kTol);
    (void)value_of(co_await p.read_position_and_current(Arm::alpha), "pos+cur alpha");
    (void)value_of(co_await p.read_position_and_torque(Arm::alpha), "pos+torque alpha");
    (void)value_of(co_await p.read_position_and_torque(Arm::beta), "pos+torque beta");
    auto both = co_await p.read_position_and_torque(Arm::both);
    EXPECT_FALSE(both.has_value());
    EXPECT_EQ(value_of(co_await p.read_raw_temperature(), "temperature"), 2100u);
    EXPECT_EQ(value_of(co_await p.read_cogging_vector_length(), "cogging length"), 1024u);
    const auto cp = value_of(co_await p.read_cogging(CoggingTable::positive, 3, 4), "cogging +");
    const auto cn = value_of(co_await p.read_cogging(CoggingTable::negative, 3, 4), "cogging -");
    EXPECT_EQ(cp, value_of(co_await p.read_cogging(CoggingTable::positive, 3, 4), "cogging + again"));
    EXPECT_NE(cp, cn);
    EXPECT_EQ(value_of(co_await p.read_cogging(CoggingTable::angles, 512, 0), "angles").alpha, 180);
    auto bad = co_await p.read_cogging(CoggingTable::angles, 5000, 0);
    EXPECT_FALSE(bad.has_value());
    if (!bad) { EXPECT_EQ(bad.error(), ResponseCode::value_out_of_range); }
  });
}

TEST(PositionerSim, SettingsReachTheRobot) {
  SimRig rig;
  rig.add(7, 0);
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    Positioner& p = *rig.array->find(7);
    auto& m = rig.model(7);
    expect_ok(co_await p.set_speed(1000, 3000), "speed");
    auto too_fast = co_await p.set_speed(9000, 1000);
    EXPECT_FALSE(too_fast.has_value());
    if (!too_fast) { EXPECT_EQ(too_fast.error(), ResponseCode::value_out_of_range); }
    expect_ok(co_await p.set_current(50, 60), "current");
    auto neg = co_await p.set_current(-1, 60);  // refused by the host before sending
    EXPECT_FALSE(neg.has_value());
    if (!neg) { EXPECT_EQ(neg.error(), protocol::ProtocolErrc::value_out_of_range); }
    expect_ok(co_await p.set_holding_current(45, 30), "holding");
    EXPECT_EQ(value_of(co_await p.read_holding_current(), "holding").alpha.percent(), 45u);
    expect_ok(co_await p.set_collision_margin(-10, 25), "margin");
    auto margin = co_await p.set_collision_margin(31, 0);
    EXPECT_FALSE(margin.has_value());
    expect_ok(co_await p.set_offsets({1.5, -2.0}), "offsets");
    const auto off = value_of(co_await p.read_offsets(), "offsets");
    EXPECT_NEAR(off.alpha, 1.5, kTol);
    EXPECT_NEAR(off.beta, -2.0, kTol);
    expect_ok(co_await p.set_offsets({0, 0}), "offsets back");
    expect_ok(co_await p.set_position({10.0, 170.0}), "set position");
    const auto pos = value_of(co_await p.read_position(), "position");
    EXPECT_NEAR(pos.alpha, 10.0, kTol);
    EXPECT_NEAR(pos.beta, 170.0, kTol);

    expect_ok(co_await p.set_loop(Arm::alpha, Loop::open, false), "alpha open loop, no detection");
    auto st = value_of(co_await p.read_status(), "status");
    EXPECT_FALSE(st.has(StatusBit::closed_loop_alpha));
    EXPECT_TRUE(st.has(StatusBit::collision_detect_alpha_disable));
    EXPECT_TRUE(st.has(StatusBit::closed_loop_beta));
    expect_ok(co_await p.set_loop(Arm::beta, Loop::closed, false), "beta closed, no detection");
    EXPECT_FALSE(m.collision_detection(sim::Arm::beta));
    expect_ok(co_await p.set_loop(Arm::both, Loop::closed, true), "both default");
    st = value_of(co_await p.read_status(), "status");
    EXPECT_TRUE(st.has(StatusBit::closed_loop_alpha) && st.has(StatusBit::closed_loop_beta));
    EXPECT_FALSE(st.has(StatusBit::collision_detect_alpha_disable) || st.has(StatusBit::collision_detect_beta_disable));
    expect_ok(co_await p.set_loop(Arm::alpha, Loop::open, true), "alpha open, detection");
    expect_ok(co_await p.set_loop(Arm::alpha, Loop::closed, true), "alpha back");

    expect_ok(co_await p.set_precise_move(Arm::both, false), "precise off");
    st = value_of(co_await p.read_status(), "status");
    EXPECT_FALSE(st.has(StatusBit::precise_move_alpha) || st.has(StatusBit::precise_move_beta));
    expect_ok(co_await p.set_precise_move(Arm::beta, true), "precise beta on");
    st = value_of(co_await p.read_status(), "status");
    EXPECT_TRUE(st.has(StatusBit::precise_move_beta));
    EXPECT_FALSE(st.has(StatusBit::precise_move_alpha));

    expect_ok(co_await p.set_led(true), "led on");
    EXPECT_TRUE(m.led_on());
    expect_ok(co_await p.set_led(false), "led off");
    EXPECT_FALSE(m.led_on());
    expect_ok(co_await p.set_hall(false), "hall off");
    st = value_of(co_await p.read_status(), "status");
    EXPECT_TRUE(st.has(StatusBit::switch_off_hall_after_move));
    // Moves are refused while the sensors sleep, with the document's advice.
    auto asleep = co_await p.start_goto({10, 170}, false);
    EXPECT_FALSE(asleep.has_value());
    if (!asleep) {
      EXPECT_EQ(asleep.error(), ResponseCode::hall_sensors_disabled);
      EXPECT_NE(asleep.error().message().find("SWITCH_ON_HALL"), std::string::npos);
    }
    expect_ok(co_await p.set_hall(true), "hall on");
  });
}

TEST(PositionerSim, MovesWaitForTheEndAndCheckThePosition) {
  SimRig rig;
  rig.add(7, 0);
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    Positioner& p = *rig.array->find(7);
    auto& m = rig.model(7);
    auto a = co_await p.goto_absolute({20.0, 150.0});
    EXPECT_TRUE(a.has_value()) << (a ? "" : a.error().message());
    if (a) {
      EXPECT_NEAR(a.value().reached.alpha, 20.0, 0.1);
      EXPECT_NEAR(a.value().reached.beta, 150.0, 0.1);
      EXPECT_GT(a.value().eta.alpha.ticks(), 0u);
    }
    EXPECT_FALSE(m.moving());
    EXPECT_NEAR(m.reported_deg(sim::Arm::alpha), 20.0, 0.1);
    auto r = co_await p.goto_relative({-5.0, 10.0});
    EXPECT_TRUE(r.has_value()) << (r ? "" : r.error().message());
    if (r) { EXPECT_NEAR(r.value().target.alpha, 15.0, 0.01); }
    EXPECT_NEAR(m.reported_deg(sim::Arm::beta), 160.0, 0.1);
    // Beyond the hard stops: the robot refuses, nothing moves.
    auto out = co_await p.goto_absolute({400.0, 150.0});
    EXPECT_FALSE(out.has_value());
    if (!out) { EXPECT_EQ(out.error(), ResponseCode::value_out_of_range); }
    EXPECT_FALSE(m.moving());
    // A move can be aborted and stopped.
    auto eta = co_await p.start_goto({200.0, 20.0}, false);
    EXPECT_TRUE(eta.has_value());
    auto busy = co_await p.start_goto({10.0, 20.0}, false);
    EXPECT_FALSE(busy.has_value());
    if (!busy) { EXPECT_EQ(busy.error(), ResponseCode::already_in_motion); }
    expect_ok(co_await p.abort(), "abort");
    EXPECT_FALSE(m.moving());
    expect_ok(co_await p.stop(), "stop");
    auto idle = co_await p.wait_until_idle(5s);
    EXPECT_TRUE(idle.has_value());
  });
}

TEST(PositionerSim, DatumSearchWaitsForTheInitialisedFlags) {
  SimRig rig;
  rig.add(7, 0, [](sim::PositionerConfig& c) { c.datums_initialized = false; });
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    Positioner& p = *rig.array->find(7);
    auto no_datum = co_await p.goto_absolute({10, 10});
    EXPECT_FALSE(no_datum.has_value());
    if (!no_datum) { EXPECT_EQ(no_datum.error(), ResponseCode::datum_not_initialized); }
    auto st = co_await p.go_to_datums();
    EXPECT_TRUE(st.has_value()) << (st ? "" : st.error().message());
    if (st) {
      EXPECT_TRUE(st.value().has(StatusBit::datum_alpha_initialized));
      EXPECT_TRUE(st.value().has(StatusBit::datum_beta_initialized));
      EXPECT_FALSE(st.value().has(StatusBit::datum_initialization));
      EXPECT_TRUE(st.value().idle());
    }
    auto move = co_await p.goto_absolute({10, 10});
    EXPECT_TRUE(move.has_value()) << (move ? "" : move.error().message());
  });
}

TEST(PositionerSim, CalibrationSequenceFollowsTheDocumentsOrderAndSaves) {
  SimRig rig(1, fast_sim(100));
  rig.add(7, 0, [](sim::PositionerConfig& c) {
    c.motors_calibrated = false;
    c.datums_calibrated = false;
    c.cogging_calibrated = false;
    c.datums_initialized = false;
    c.cogging_calibration_time = 20s;
  });
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    Positioner& p = *rig.array->find(7);
    auto& m = rig.model(7);
    // Out of order: the datum cannot be calibrated before the motors.
    auto early = co_await p.calibrate_datums();
    EXPECT_FALSE(early.has_value());
    if (!early) { EXPECT_EQ(early.error(), ResponseCode::motor_not_calibrated); }
    CalibrationPlan plan;
    plan.cogging = true;
    auto rep = co_await p.calibrate(plan);
    EXPECT_TRUE(rep.has_value()) << (rep ? "" : rep.error().message());
    if (rep) {
      const auto& st = rep.value().final_status;
      EXPECT_TRUE(st.motors_calibrated());
      EXPECT_TRUE(st.datums_calibrated());
      EXPECT_TRUE(st.has(StatusBit::cogging_alpha_calibrated) && st.has(StatusBit::cogging_beta_calibrated));
      EXPECT_TRUE(st.initialized());
      EXPECT_TRUE(rep.value().saved);
      EXPECT_TRUE(rep.value().motor_error.has_value());
      EXPECT_TRUE(rep.value().datum_error.has_value());
      if (rep.value().datum_error) {
        EXPECT_EQ(rep.value().datum_error->alpha, m.calibration().datum_error[sim::Arm::alpha]);
      }
    }
    EXPECT_TRUE(m.flash().calibration.motor[sim::Arm::alpha]);
    EXPECT_TRUE(m.flash().calibration.datum[sim::Arm::beta]);
    EXPECT_TRUE(m.flash().calibration.cogging[sim::Arm::beta]);
  });
}

TEST(PositionerSim, SingleArmCalibrationsWaitForThatArmsFlag) {
  SimRig rig(1, fast_sim(100));
  rig.add(7, 0, [](sim::PositionerConfig& c) {
    c.motors_calibrated = false;
    c.datums_calibrated = false;
  });
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    Positioner& p = *rig.array->find(7);
    auto st = co_await p.calibrate_motors(Arm::beta);
    EXPECT_TRUE(st.has_value()) << (st ? "" : st.error().message());
    if (st) {
      EXPECT_TRUE(st.value().has(StatusBit::motor_beta_calibrated));
      EXPECT_FALSE(st.value().has(StatusBit::motor_alpha_calibrated));
    }
    st = co_await p.calibrate_datums(Arm::beta);
    EXPECT_TRUE(st.has_value()) << (st ? "" : st.error().message());
    if (st) { EXPECT_TRUE(st.value().has(StatusBit::datum_beta_calibrated)); }
    auto d = co_await p.go_to_datums(Arm::beta);
    EXPECT_TRUE(d.has_value()) << (d ? "" : d.error().message());
    expect_ok(co_await p.save_calibration(), "save");
    EXPECT_TRUE(rig.model(7).flash().calibration.datum[sim::Arm::beta]);
  });
}

TEST(PositionerSim, BootloaderAnswersItsOwnCommandsAndRefusesTheApplications) {
  SimRig rig;
  rig.add(9, 0, [](sim::PositionerConfig& c) { c.sync_line_low_at_power_on = true; });
  rig.start();
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    Positioner& p = *rig.array->find(9);
    const auto v = value_of(co_await p.read_firmware_version(), "version");
    EXPECT_TRUE(v.is_bootloader());
    EXPECT_TRUE(p.in_bootloader());
    const auto bs = value_of(co_await p.read_bootloader_status(), "bootloader status");
    EXPECT_TRUE(bs.has(protocol::BootloaderBit::bootloader_init));
    auto app = co_await p.read_status();
    EXPECT_FALSE(app.has_value());
    if (!app) { EXPECT_EQ(app.error(), HostErrc::not_ready); }
    auto move = co_await p.start_goto({1, 1}, false);
    EXPECT_FALSE(move.has_value());
    if (!move) { EXPECT_EQ(move.error(), ResponseCode::invalid_bootloader_command); }
    // START_FIRMWARE_UPGRADE with a size the robot cannot take.
    auto big = co_await p.client().call<CommandId::start_firmware_upgrade>(9, {10'000'000u, 0u});
    EXPECT_FALSE(big.has_value());
    if (!big) { EXPECT_EQ(big.error(), ResponseCode::value_out_of_range); }
  });
}

// Every command of both tables goes out through the client and gets the answer the interface
// document gives for the robot's state (a sweep, on top of the typed calls above).
TEST(PositionerSim, EveryCommandOfBothTablesIsAnswered) {
  SimRig rig(1, fast_sim(100));
  rig.add(7, 0, [](sim::PositionerConfig& c) { c.cogging_calibration_time = 10s; });
  rig.add(9, 0, [](sim::PositionerConfig& c) { c.sync_line_low_at_power_on = true; });
  rig.start();
  std::vector<std::string> answered;
  rig.run([&]() -> asio::awaitable<void> {
    co_await rig.discover();
    CommandClient& client = rig.array->client(0);
    Positioner& app = *rig.array->find(7);
    for (const auto& info : protocol::kCommands) {
      if (!info.host_sends) continue;
      protocol::Payload payload;
      switch (info.id) {
        case CommandId::go_to_absolute_position:
        case CommandId::set_current_position:
          payload = protocol::ArmPositions{protocol::Angle::from_degrees(10).value(),
                                           protocol::Angle::from_degrees(170).value()}.encode();
          break;
        case CommandId::go_to_relative_position:
        case CommandId::set_offsets: payload = protocol::ArmPositions{}.encode(); break;
        case CommandId::set_speed: payload = protocol::Payload().put_u32(2000).put_u32(2000); break;
        case CommandId::set_current:
        case CommandId::set_holding_current: payload = protocol::Payload().put_u32(0).put_u32(30); break;
        case CommandId::set_collision_margin: payload = protocol::Payload().put_i32(-5).put_i32(20); break;
        case CommandId::get_cogging_positive:
        case CommandId::get_cogging_negative:
        case CommandId::get_cogging_angles: payload = protocol::Payload().put_u32(1).put_u32(2); break;
        case CommandId::send_new_trajectory: payload = protocol::Payload().put_u32(1).put_u32(0); break;
        case CommandId::send_trajectory_data:
          payload = protocol::TrajectoryPoint{protocol::Angle::from_degrees(1).value(),
                                              protocol::Time::from_seconds(1).value()}.encode();
          break;
        case CommandId::start_firmware_upgrade: payload = protocol::Payload().put_u32(8).put_u32(0); break;
        case CommandId::firmware_data: payload = protocol::Payload().put_u32(0).put_u32(0); break;
        default: break;
      }
      // The robot that runs the firmware taking the command, and what it must answer.
      const bool boot = info.bootloader && !info.application;
      const std::uint16_t to = boot ? 9 : 7;
      auto r = co_await client.request(to, info.id, payload);
      const bool timed_out = !r && r.error() == HostErrc::timeout;
      EXPECT_FALSE(timed_out) << info.name;
      // Everything is accepted by the robots in their state; the start (14) too, although the
      // one-point trajectory was closed (12) and then dropped by TRAJECTORY_ABORT (13): robots in
      // service accept a start with nothing loaded and stay (docs/fps-simulator.md).
      EXPECT_TRUE(r.has_value()) << info.name << ": " << (r ? "" : r.error().message());
      if (!timed_out) answered.emplace_back(info.name);
      // Whatever moved is stopped before the next command.
      if (!boot) {
        if (auto st = co_await app.read_status(); st && (!st.value().idle() || st.value().calibrating())) {
          if (info.id != CommandId::send_new_trajectory && info.id != CommandId::send_trajectory_data &&
              info.id != CommandId::trajectory_data_end) {
            (void)co_await app.stop();
          }
        }
      }
    }
    // The other firmware refuses what it does not have.
    auto in_boot = co_await client.request(9, CommandId::go_to_datums);
    EXPECT_FALSE(in_boot.has_value());
    if (!in_boot) { EXPECT_EQ(in_boot.error(), ResponseCode::invalid_bootloader_command); }
    auto in_app = co_await client.request(7, CommandId::start_firmware_upgrade, protocol::Payload().put_u32(8).put_u32(0));
    EXPECT_FALSE(in_app.has_value());
    if (!in_app) { EXPECT_EQ(in_app.error(), ResponseCode::invalid_command); }
  });
  std::size_t sendable = 0;
  for (const auto& info : protocol::kCommands) sendable += info.host_sends ? 1 : 0;
  EXPECT_EQ(answered.size(), sendable);
}
