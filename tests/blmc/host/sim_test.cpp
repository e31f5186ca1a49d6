// The host driver against the board simulator (src/axon/blmc/sim) on the in-process virtual bus: the
// simulator ticks at 1 kHz on the test's io thread, the ControlLoop runs on its own thread.
// Assertions are about behaviour; bounds on tracking error are generous for a loaded machine.
#include "axon/blmc/host/board.hpp"
#include "axon/blmc/host/control_loop.hpp"
#include "axon/blmc/host/error.hpp"
#include "axon/blmc/host/homing.hpp"
#include "axon/blmc/host/pd_controller.hpp"
#include "sim_rig.hpp"

#include <gtest/gtest.h>

#include <cctype>
#include <cmath>

namespace axon::blmc::host {
namespace {

using namespace testing;

// Runs `ctl` in a ControlLoop until `until()` or `seconds` pass or the loop ends; returns the loop's
// fault if any. The io thread keeps serving the simulator meanwhile.
asio::awaitable<std::optional<LoopFault>> run_loop(Board& board, Controller& ctl, SafetyLimits lim, double seconds,
                                                   std::function<bool()> until = {}, LoopStats* stats = nullptr,
                                                   std::uint64_t* velocity_limited = nullptr) {
  auto r = co_await board.start_cyclic();
  EXPECT_TRUE(r) << (r ? "" : r.error().message());
  std::optional<LoopFault> fault;
  {
    ControlLoop loop({&board.port()}, ctl, {lim}, loop_options());
    EXPECT_TRUE(loop.start());
    const auto t0 = std::chrono::steady_clock::now();
    while (loop.running() && std::chrono::steady_clock::now() - t0 < std::chrono::duration<double>(seconds)) {
      if (until && until()) break;
      co_await core::sleep_for(5ms);
      CycleRecord rec;
      while (loop.pop_record(rec)) {
      }
    }
    loop.stop();
    fault = loop.fault();
    if (stats) *stats = loop.stats();
    if (velocity_limited) *velocity_limited = loop.safety(0).counters().velocity_limited;
  }
  auto s = co_await board.stop_cyclic();
  EXPECT_TRUE(s);
  co_return fault;
}

TEST(BlmcHostSim, EnableWaitsForAlignmentThenReady) {
  SimRig rig;
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host);
    EXPECT_FALSE(rig.sim->motor_state(0).ready);
    auto r = co_await board.enable();
    CO_ASSERT(r);
    EXPECT_TRUE(rig.sim->motor_state(0).ready);
    EXPECT_TRUE(rig.sim->motor_state(1).ready);
    const auto& st = board.latest().status.value;
    EXPECT_TRUE(st.system_enabled && st.motor1_ready && st.motor2_ready);
    auto d = co_await board.wait_data(1s, 8);
    EXPECT_TRUE(d);  // SEND_ALL: data flows
    auto off = co_await board.disable();
    EXPECT_TRUE(off);
    co_await eventually([&] { return !rig.sim->status().system_enabled; });
    EXPECT_FALSE(rig.sim->motor_state(0).enabled);
  });
}

TEST(BlmcHostSim, EveryCommandReachesTheFirmware) {
  SimRig rig;
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host);
    using proto::CommandCode;
    const char* texts[] = {"ENABLE_SYS=1", "SEND_CURRENT=1", "SEND_POSITION=1", "SEND_VELOCITY=1", "SEND_ADC6=1",
                           "SEND_ENC_INDEX=1", "SET_CAN_RECV_TIMEOUT=77", "ENABLE_POS_ROLLOVER_ERROR=1",
                           "ENABLE_MTR1=1", "ENABLE_MTR2=1", "ENABLE_VSPRING1=1", "ENABLE_VSPRING2=1",
                           "CAN_CMD_P_CONTROLLER_LIMIT_IQ_MTR1=0.5", "CAN_CMD_P_CONTROLLER_LIMIT_IQ_MTR2=0.75",
                           "CAN_CMD_D_CONTROLLER_LIMIT_IQ_MTR1=0.25", "CAN_CMD_D_CONTROLLER_LIMIT_IQ_MTR2=0.125"};
    for (const char* t : texts) {
      const auto cmd = proto::Command::parse(t).value();
      auto r = co_await board.command(cmd);
      EXPECT_TRUE(r) << t;
    }
    const auto& s = rig.sim->settings();
    co_await eventually([&] { return rig.sim->stats().commands >= std::size(texts); });
    EXPECT_TRUE(s.system_enabled);
    EXPECT_TRUE(s.send_current && s.send_position && s.send_velocity && s.send_adc && s.send_enc_index);
    EXPECT_EQ(s.recv_timeout_ms, 77u);
    EXPECT_TRUE(s.rollover_error);
    EXPECT_TRUE(rig.sim->motor_state(0).enabled && rig.sim->motor_state(1).enabled);
    EXPECT_TRUE(rig.sim->motor_state(0).vspring && rig.sim->motor_state(1).vspring);
    EXPECT_EQ(rig.sim->motor_state(0).p_limit_a, 0.5);
    EXPECT_EQ(rig.sim->motor_state(1).p_limit_a, 0.75);
    EXPECT_EQ(rig.sim->motor_state(0).d_limit_a, 0.25);
    EXPECT_EQ(rig.sim->motor_state(1).d_limit_a, 0.125);
    const char* off[] = {"SEND_ALL=0", "ENABLE_VSPRING1=0", "ENABLE_MTR2=0", "ENABLE_SYS=0"};
    for (const char* t : off) {
      const auto cmd = proto::Command::parse(t).value();
      auto r = co_await board.command(cmd);
      EXPECT_TRUE(r) << t;
    }
    co_await eventually([&] { return !s.system_enabled; });
    EXPECT_FALSE(s.send_current || s.send_position || s.send_velocity || s.send_adc);
    EXPECT_FALSE(rig.sim->motor_state(0).vspring);
    EXPECT_FALSE(rig.sim->motor_state(1).enabled);
    EXPECT_EQ(rig.sim->stats().malformed, 0u);
  });
}

TEST(BlmcHostSim, ReceiveTimeoutThenRecovery) {
  SimRig rig;
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host);
    auto r = co_await board.enable();
    CO_ASSERT(r);
    auto t = co_await board.set_recv_timeout(20);
    EXPECT_TRUE(t);
    auto c = co_await board.send_currents({0.1, 0.0});  // then the host goes quiet
    EXPECT_TRUE(c);
    proto::ErrorCode seen = proto::ErrorCode::none;
    for (int i = 0; i < 4 && seen == proto::ErrorCode::none; ++i) {
      auto st = co_await board.wait_status(2500ms);
      CO_ASSERT(st);
      seen = st.value().error;
    }
    EXPECT_EQ(seen, proto::ErrorCode::can_recv_timeout);
    EXPECT_FALSE(board.latest().status.value.system_enabled);
    auto rec = co_await board.recover();
    EXPECT_TRUE(rec) << (rec ? "" : rec.error().message());
    EXPECT_EQ(board.latest().status.value.error, proto::ErrorCode::none);
    auto off = co_await board.disable();
    EXPECT_TRUE(off);
  });
}

// One case per test, so that ctest runs them side by side (each waits for the 1 Hz status).
struct ErrorCase {
  std::vector<sim::FaultKind> kinds;
  proto::ErrorCode expect;
};

void PrintTo(const ErrorCase& c, std::ostream* os) {
  for (auto k : c.kinds) *os << sim::name(k) << " ";
  *os << "-> " << proto::name(c.expect);
}

class BlmcHostSimErrors : public ::testing::TestWithParam<ErrorCase> {};

TEST_P(BlmcHostSimErrors, EachErrorCodeIsSeenByNameWithPrecedence) {
  const ErrorCase& c = GetParam();
  SimRig rig;
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host);
    auto r = co_await board.enable();
    CO_ASSERT(r);
    for (auto k : c.kinds) rig.sim->inject(k);
    auto again = co_await board.wait_ready(2500ms);
    CO_ASSERT(!again);
    EXPECT_EQ(again.error(), HostErrc::board_error);
    EXPECT_NE(again.error().detail.find(std::string(proto::name(c.expect))), std::string::npos) << again.error().detail;
    // The glitch is gone: the documented recovery brings the board back.
    auto rec = co_await board.recover();
    EXPECT_TRUE(rec) << (rec ? "" : rec.error().message());
  });
}

INSTANTIATE_TEST_SUITE_P(
    Faults, BlmcHostSimErrors,
    ::testing::Values(ErrorCase{{sim::FaultKind::encoder}, proto::ErrorCode::encoder},
                      ErrorCase{{sim::FaultKind::pos_converter}, proto::ErrorCode::pos_converter},
                      ErrorCase{{sim::FaultKind::transmit}, proto::ErrorCode::other},
                      ErrorCase{{sim::FaultKind::over_current}, proto::ErrorCode::other},
                      ErrorCase{{sim::FaultKind::pos_converter, sim::FaultKind::encoder}, proto::ErrorCode::encoder},
                      ErrorCase{{sim::FaultKind::over_current, sim::FaultKind::pos_converter}, proto::ErrorCode::pos_converter}),
    // A stable, readable test name: the injected faults and the error code expected.
    [](const ::testing::TestParamInfo<ErrorCase>& info) {
      std::string n;
      for (auto k : info.param.kinds) n += std::string(sim::name(k)) + "_";
      n += "gives_" + std::string(proto::name(info.param.expect));
      for (char& ch : n)
        if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
      return n;
    });

TEST(BlmcHostSim, BoardErrorDuringControlStopsAndIsNamed) {
  SimRig rig;
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host);
    auto r = co_await board.enable();
    CO_ASSERT(r);
    FunctionController ctl([](const ControlInput&, std::span<MotorPair> out) { out[0] = {0.05, 0.05}; });
    bool injected = false;
    int cycles = 0;
    const std::function<bool()> inject = [&] {
      if (!injected && ++cycles > 20) {
        rig.sim->inject(sim::FaultKind::encoder);
        injected = true;
      }
      return false;
    };
    auto f = co_await run_loop(board, ctl, test_limits(), 5.0, inject);
    CO_ASSERT(f.has_value());
    EXPECT_EQ(f->fault.board_error, proto::ErrorCode::encoder) << f->fault.describe();
    EXPECT_NE(f->fault.describe().find("ENCODER"), std::string::npos) << f->fault.describe();
  });
}

TEST(BlmcHostSim, StalledBoardIsStaleDataOnTheHost) {
  sim::BoardFaultPlan plan;
  plan.stalls.push_back({1500ms, 4000ms, sim::LinkDirection::tx});
  SimRig rig(SimRig::config(), plan);
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host);
    auto r = co_await board.enable();
    CO_ASSERT(r);
    FunctionController ctl([](const ControlInput&, std::span<MotorPair> out) { out[0] = {}; });
    auto f = co_await run_loop(board, ctl, test_limits(), 5.0);
    CO_ASSERT(f.has_value());
    EXPECT_EQ(f->fault.kind, FaultKind::stale_data) << f->fault.describe();
    EXPECT_EQ(f->fault.board_error, proto::ErrorCode::none);
    // The host disabled the motors.
    co_await eventually([&] { return !rig.sim->motor_state(0).enabled; });
    EXPECT_FALSE(rig.sim->motor_state(0).enabled);
    EXPECT_FALSE(rig.sim->motor_state(1).enabled);
  });
}

TEST(BlmcHostSim, PositionLimitTripsAndDisables) {
  SimRig rig;
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host);
    auto r = co_await board.enable();
    CO_ASSERT(r);
    FunctionController ctl([](const ControlInput&, std::span<MotorPair> out) { out[0] = {0.3, 0.0}; });
    SafetyLimits lim = test_limits();
    lim.position[0] = {true, -0.5, 0.5};
    auto f = co_await run_loop(board, ctl, lim, 10.0);
    CO_ASSERT(f.has_value());
    EXPECT_EQ(f->fault.kind, FaultKind::position_limit) << f->fault.describe();
    EXPECT_EQ(f->fault.motor, 0);
    co_await eventually([&] { return !rig.sim->motor_state(0).enabled; });
    EXPECT_FALSE(rig.sim->motor_state(0).enabled);
    EXPECT_FALSE(rig.sim->motor_state(1).enabled);
  });
}

TEST(BlmcHostSim, VelocityLimitCutsTheCurrent) {
  SimRig rig;
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host);
    auto r = co_await board.enable();
    CO_ASSERT(r);
    FunctionController ctl([](const ControlInput&, std::span<MotorPair> out) { out[0] = {0.5, 0.0}; });
    SafetyLimits lim = test_limits();
    lim.max_velocity_krpm = 0.3;  // 5 rev/s
    std::uint64_t limited = 0;
    auto f = co_await run_loop(board, ctl, lim, 1.0, {}, nullptr, &limited);
    EXPECT_FALSE(f.has_value()) << f->fault.describe();
    EXPECT_GT(limited, 0u);
    // Without current above the limit the motor cannot run away: it stays near the limit.
    EXPECT_LT(std::abs(rig.sim->motor(0).velocity_rev_s()), 3 * 5.0);
    auto off = co_await board.disable();
    EXPECT_TRUE(off);
  });
}

TEST(BlmcHostSim, HomingFindsTheIndex) {
  auto cfg = SimRig::config();
  cfg.motors[0].index_offset_rev = 0.3;
  cfg.motors[1].index_offset_rev = 0.7;
  SimRig rig(cfg);
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host);
    auto r = co_await board.enable();
    CO_ASSERT(r);
    HomingOptions ho;
    ho.speed_rev_s = 1.0;
    HomingController homing(1, ho);
    const std::function<bool()> done = [&] { return homing.done(); };
    auto f = co_await run_loop(board, homing, test_limits(), 10.0, done);
    EXPECT_FALSE(f.has_value()) << f->fault.describe();
    CO_ASSERT(homing.done());
    EXPECT_TRUE(homing.all_found());
    const double want[2] = {0.3, 0.7};
    for (int k = 0; k < 2; ++k) {
      const auto& h = homing.result(0, k);
      EXPECT_EQ(h.state, MotorHoming::State::found);
      // The index position modulo one turn is where the mark sits.
      const double frac = h.index_rev - std::floor(h.index_rev);
      EXPECT_NEAR(frac, want[k], 1e-3) << "motor " << k + 1 << " index at " << h.index_rev;
    }
    auto off = co_await board.disable();
    EXPECT_TRUE(off);
  });
}

TEST(BlmcHostSim, PdTracksASineWithinTolerance) {
  SimRig rig;
  rig.run([&]() -> asio::awaitable<void> {
    Board board(*rig.host);
    auto r = co_await board.enable();
    CO_ASSERT(r);
    PdTarget sine{true, 0.5, 1.0, 0.0};
    PdController pd(1, {10.0, 0.1}, {sine, sine}, 300ms);
    LoopStats stats;
    auto f = co_await run_loop(board, pd, test_limits(), 2.5, {}, &stats);
    EXPECT_FALSE(f.has_value()) << f->fault.describe();
    for (int k = 0; k < 2; ++k) {
      const auto& t = pd.tracking(0, k);
      EXPECT_GT(t.samples, 1000u);
      // Stated bound: 0.5 rev amplitude at 1 Hz, kp 10 A/rev, kd 0.1 A/(rev/s): max error under
      // 0.1 rev (20 % of the amplitude), rms under 0.05 rev, on a non-real-time test machine.
      EXPECT_LT(t.max_abs_error_rev, 0.1) << "motor " << k + 1;
      EXPECT_LT(t.rms_rev(), 0.05) << "motor " << k + 1;
    }
    auto off = co_await board.disable();
    EXPECT_TRUE(off);
  });
}

}  // namespace
}  // namespace axon::blmc::host
