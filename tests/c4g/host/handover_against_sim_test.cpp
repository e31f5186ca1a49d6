// The manual's hand-over example (chapter 13: move, GO OPEN TYPE A, WAIT FOR PC, move, GO OPEN TYPE
// B, move, WAIT FOR PC, move) from data/c4g/handover.yaml, played by the simulator against the Server
// over loopback UDP. The PC's part: a trajectory of its own in mode 4 (type A), corrections on the
// controller's move in mode 7 (type B), each ended by exit-from-open; type B is run with the PC's
// exit before and after the end of the controller's move (the manual: either order must work).
#include "c4g/host/sim_events.hpp"
#include "axon/c4g/host/server.hpp"
#include "axon/c4g/protocol/mode.hpp"
#include "axon/c4g/sim/client_runner.hpp"
#include "axon/c4g/sim/controller.hpp"
#include "axon/c4g/sim/robots.hpp"
#include "axon/c4g/sim/scenario.hpp"
#include "axon/c4g/sim/udp_client.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

namespace axon::c4g::test {
namespace {

namespace P = protocol;
namespace H = host;
namespace S = sim;

// The PC's side of the example.
class HandoverPc : public H::Controller {
 public:
  explicit HandoverPc(int exit7_after) : exit7_after_(exit7_after) {}

  void on_cycle(const H::CycleContext& ctx, H::ReplyBuilder& r) override {
    const auto& q = ctx.request;
    const std::int32_t m = q.axes[0].mode;
    if (modes.empty() || modes.back() != m) modes.push_back(m);
    if (m == P::code(P::Mode::mode4)) {
      if (cycles4_ == 0)
        for (std::size_t i = 0; i < q.count; ++i) start_[i] = target_[i] = q.axes[i].d3;
      // Half a cosine of 0.5 motor turns on axis 1 over kSteps cycles, then hold and exit.
      const int k = std::min(cycles4_, kSteps);
      const float before = target_[0];
      target_[0] = start_[0] + 0.25f * static_cast<float>(1.0 - std::cos(std::numbers::pi * k / kSteps));
      for (std::size_t i = 0; i < q.count; ++i) r.axis(i).d1 = target_[i];
      r.axis(0).d2 = target_[0] - before;
      max_pc_travel = std::max(max_pc_travel, std::fabs(static_cast<double>(q.axes[0].d3 - start_[0])));
      if (++cycles4_ > kSteps + 20) r.exit_from_open(1);
    } else if (m == P::code(P::Mode::mode4_standby)) {
      for (std::size_t i = 0; i < q.count; ++i) r.axis(i).d1 = target_[i];
    } else if (m == P::code(P::Mode::mode7)) {
      if (++cycles7_ <= exit7_after_) {
        r.axis(1).d1 = 0.001f;  // 0.001 motor turns more every cycle on axis 2
        correction += 0.001;
      } else {
        r.exit_from_open(1);
      }
    }
  }

  std::vector<std::int32_t> modes;
  double max_pc_travel = 0;
  double correction = 0;

 private:
  static constexpr int kSteps = 200;
  int exit7_after_;
  int cycles4_ = 0, cycles7_ = 0;
  std::array<float, P::kMaxAxes> start_{}, target_{};
};

struct Outcome {
  std::vector<S::Event> events;
  bool done = false, comm_error = false;
  std::uint64_t refused = 0;
  [[nodiscard]] bool has(std::string_view name, std::string_view text) const {
    return test::has_event(events, name, text);
  }
  [[nodiscard]] std::string log() const { return test::event_log(events); }
};

Outcome run_example(const H::Server& server) {
  Outcome o;
  auto scenario = S::Scenario::load_file(std::string(AXON_TESTS_DIR) + "/../data/c4g/handover.yaml");
  EXPECT_TRUE(scenario) << scenario.error().detail;
  if (!scenario) return o;
  auto c = S::Controller::create(S::six_axis_robot(), scenario.value());
  EXPECT_TRUE(c) << c.error().detail;
  auto udp = S::UdpClient::open(net::Endpoint{"127.0.0.1", server.local_address().port});
  EXPECT_TRUE(udp);
  S::RunOptions ro;
  ro.duration_s = 30;
  ro.on_event = [&](const S::Event& e) { o.events.push_back(e); };
  S::run_client(c.value(), udp.value(), ro);
  o.done = c.value().scenario_done();
  o.comm_error = c.value().communication_error();
  o.refused = c.value().stats().refused_requests;
  return o;
}

std::unique_ptr<H::Server> start(HandoverPc& pc) {
  H::ServerOptions o;
  o.listen = net::Endpoint{"127.0.0.1", 0};
  o.max_late_cycles = 0;
  o.verify_reply_fields = true;  // no reply may carry data in a field its mode does not use
  auto s = H::Server::start(pc, o);
  EXPECT_TRUE(s) << s.error().detail;
  return std::move(s).value();
}

TEST(HandoverAgainstSim, ManualExampleWithThePcExitingBeforeTheControllersMoveEnds) {
  HandoverPc pc(50);  // 0.1 s of corrections, the controller's move lasts 0.6 s
  auto server = start(pc);
  const auto o = run_example(*server);
  server->stop();
  EXPECT_TRUE(o.done) << o.log();
  EXPECT_FALSE(o.comm_error);
  EXPECT_EQ(o.refused, 0u) << o.log();
  EXPECT_EQ(server->safety().reason(), H::FaultReason::none) << server->summary();
  // Type A: 4, its standby, 0. Type B, PC first: 7 while both act, 7' (zero correction) until the
  // move ends, 7'' then 0.
  EXPECT_EQ(pc.modes, (std::vector<std::int32_t>{0, 501, 0, 4, 14, 0, 7, 17, 170, 0, 504})) << o.log();
  EXPECT_GT(pc.max_pc_travel, 0.45);  // the PC alone moved the arm in type A
  EXPECT_TRUE(o.has(S::event::kOpenEnd, "open type A (mode 4) ended")) << o.log();
  EXPECT_TRUE(o.has(S::event::kOpenEnd, "open type B (mode 7) ended: PC exit first")) << o.log();
}

TEST(HandoverAgainstSim, ManualExampleWithTheControllersMoveEndingBeforeThePcExits) {
  HandoverPc pc(600);  // 1.2 s of corrections: the PC goes on alone after the move (state S01)
  auto server = start(pc);
  const auto o = run_example(*server);
  server->stop();
  EXPECT_TRUE(o.done) << o.log();
  EXPECT_FALSE(o.comm_error);
  EXPECT_EQ(o.refused, 0u) << o.log();
  EXPECT_EQ(server->safety().reason(), H::FaultReason::none) << server->summary();
  EXPECT_EQ(pc.modes, (std::vector<std::int32_t>{0, 501, 0, 4, 14, 0, 7, 170, 0, 504})) << o.log();
  EXPECT_TRUE(o.has(S::event::kOpenEnd, "open type B (mode 7) ended: controller's trajectory end first")) << o.log();
  EXPECT_NEAR(pc.correction, 0.6, 1e-6);
}

}  // namespace
}  // namespace axon::c4g::test
