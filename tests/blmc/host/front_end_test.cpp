// The front end / back end split (front_end.hpp): the back end driven cycle by cycle with made-up
// states (the idle action before the first action, giving up, staleness, counts, torn values,
// allocation), then under MotorBoard against the in-process SimulatedBoard (the run that ends for
// want of a first action, the safety clamp after the law, the idle action once the front end stops,
// a cycle that allocates nothing).
#include "axon/blmc/host/error.hpp"
#include "axon/blmc/host/front_end.hpp"
#include "axon/blmc/host/motor_board.hpp"
#include "axon/blmc/sim/simulated_board.hpp"
#include "motor_board_rig.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <thread>

// Allocation counting: a replaced global operator new counts the allocations of the threads that
// ask for it. The sanitizers bring their own operator new, so there it is left out.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define AXON_COUNT_ALLOCATIONS 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define AXON_COUNT_ALLOCATIONS 0
#endif
#endif
#ifndef AXON_COUNT_ALLOCATIONS
#define AXON_COUNT_ALLOCATIONS 1
#endif

namespace {
thread_local bool tl_count_allocations = false;
std::atomic<std::uint64_t> g_allocations{0};
}  // namespace

#if AXON_COUNT_ALLOCATIONS
void* operator new(std::size_t n) {
  if (tl_count_allocations) g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
#endif

namespace axon::blmc::front_end_tests {  // named: the unity build joins test files
namespace {

using host::HostErrc;
using namespace board_rig;

ControlState at(double t_s, std::uint64_t cycle = 0) {
  ControlState s;
  s.cycle = cycle;
  s.time_s = t_s;
  return s;
}

FrontEndOptions options(std::chrono::milliseconds first, std::chrono::milliseconds stale) {
  FrontEndOptions o;
  o.first_action_timeout = first;
  o.stale_after = stale;
  return o;
}

TEST(BlmcFrontEnd, AppliesZeroCurrentUntilTheFirstActionAndGivesUpAfterItsTimeout) {
  FrontEnd fe(options(200ms, 50ms));
  auto law = fe.law();
  const auto idle = law(at(0.0));
  EXPECT_EQ(idle[0].current_a, 0.0);
  EXPECT_EQ(fe.applied().source, ActionSource::waiting);
  EXPECT_FALSE(fe.gave_up());
  (void)law(at(0.199));
  EXPECT_FALSE(fe.gave_up());
  (void)law(at(0.2));
  EXPECT_TRUE(fe.gave_up());
  EXPECT_EQ(fe.applied().source, ActionSource::gave_up);
  fe.set_currents({1.0, 1.0});  // too late: the run is over
  EXPECT_EQ(law(at(0.201))[0].current_a, 0.0);
  const auto st = fe.stats();
  EXPECT_EQ(st.cycles, 4u);
  EXPECT_EQ(st.idle_cycles, 4u);
  EXPECT_EQ(st.actions, 0u);
  EXPECT_EQ(st.first_action_s, -1.0);
}

TEST(BlmcFrontEnd, AStaleActionGivesWayToZeroCurrentCountedOncePerEpisode) {
  FrontEnd fe(options(1000ms, 100ms));
  auto law = fe.law();
  fe.set_currents({0.5, -0.25});
  EXPECT_EQ(law(at(0.0))[0].current_a, 0.5);
  EXPECT_EQ(law(at(0.1))[1].current_a, -0.25);  // exactly at the bound: still applied
  EXPECT_EQ(fe.applied().source, ActionSource::action);
  EXPECT_EQ(fe.applied().action, 1u);
  EXPECT_EQ(law(at(0.101))[0].current_a, 0.0);
  EXPECT_EQ(law(at(0.102))[1].current_a, 0.0);
  EXPECT_EQ(fe.applied().source, ActionSource::stale);
  EXPECT_NEAR(fe.applied().age_s, 0.102, 1e-12);
  fe.set_currents({0.3, 0});  // a new action resumes control at once
  EXPECT_EQ(law(at(0.103))[0].current_a, 0.3);
  EXPECT_EQ(law(at(0.3))[0].current_a, 0.0);
  const auto st = fe.stats();
  EXPECT_EQ(st.stale_cycles, 3u);
  EXPECT_EQ(st.stale_episodes, 2u);
  EXPECT_EQ(st.actions, 2u);
  EXPECT_EQ(st.idle_cycles, 3u);
  EXPECT_EQ(st.first_action_s, 0.0);
  EXPECT_FALSE(fe.gave_up());
}

TEST(BlmcFrontEnd, PassesPdTargetsAndGainsAndPublishesTheMeasurementsItSaw) {
  FrontEnd fe;
  auto law = fe.law();
  fe.set({MotorCommand::pd(1.5, 0.1, 8, 0.2, 0.05), MotorCommand::current(0.1)});
  auto s = at(0.0, 7);
  s.position_rev = {1.25, -3.0};
  const auto c = law(s);
  EXPECT_EQ(c[0].position_rev, 1.5);
  EXPECT_EQ(c[0].kp, 8.0);
  EXPECT_EQ(c[0].kd, 0.2);
  EXPECT_EQ(c[0].current_a, 0.05);
  EXPECT_EQ(fe.state().cycle, 7u);
  EXPECT_EQ(fe.state().position_rev[1], -3.0);
  EXPECT_EQ(fe.applied().command[1].current_a, 0.1);
  EXPECT_EQ(fe.actions_set(), 1u);
}

TEST(BlmcFrontEnd, AnActionTakenInAnEarlierRunIsNotTakenAgain) {
  FrontEnd fe(options(100ms, 50ms));
  fe.set_currents({0.4, 0});
  auto first = fe.law();
  EXPECT_EQ(first(at(0.0))[0].current_a, 0.4);
  auto second = fe.law();  // the next run: the old action is not a new order
  EXPECT_EQ(second(at(0.0))[0].current_a, 0.0);
  EXPECT_EQ(fe.applied().source, ActionSource::waiting);
}

TEST(BlmcFrontEnd, RefusesNonFiniteValuesNegativeGainsAndZeroTimeoutsInWords) {
  FrontEnd fe;
  const auto refused = [](auto f, const char* words) {
    try {
      f();
      ADD_FAILURE() << "not refused: " << words;
    } catch (const Exception& e) {
      EXPECT_EQ(e.code(), HostErrc::invalid_argument);
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  refused([&] { fe.set_currents({std::nan(""), 0}); }, "motor 1: current_a (A) must be finite");
  refused([&] { fe.set({MotorCommand{}, MotorCommand::pd(0, 0, -1, 0)}); }, "motor 2: the gains must be >= 0");
  refused([] { FrontEnd bad(options(0ms, 10ms)); }, "must be > 0");
  EXPECT_EQ(fe.actions_set(), 0u);
}

// A writer thread sets actions whose every field holds the same number; the back end, on another
// thread, must never apply a mixture of two of them, and must see the numbers only grow.
TEST(BlmcFrontEnd, TheBackEndNeverSeesATornAction) {
  FrontEnd fe(options(100000ms, 100000ms));
  auto law = fe.law();
  std::atomic<bool> done{false};
  std::thread writer([&] {
    for (int k = 1; k <= 20000; ++k) {
      const double v = k;
      fe.set({MotorCommand{v, v, v, v, v}, MotorCommand{v, v, v, v, v}});
    }
    done = true;
  });
  double last = 0;
  std::uint64_t torn = 0, backwards = 0;
  for (std::uint64_t n = 0; !done.load() || n < 10; ++n) {
    const auto c = law(at(0.0, n));
    const double v = c[0].current_a;
    for (const auto& m : c)
      if (m.current_a != v || m.position_rev != v || m.velocity_rev_s != v || m.kp != v || m.kd != v) ++torn;
    if (v < last) ++backwards;
    last = v;
    const auto a = fe.applied();  // the mirror, read while the back end writes it
    if (a.command[0].kd != a.command[1].current_a) ++torn;
  }
  writer.join();
  EXPECT_EQ(torn, 0u);
  EXPECT_EQ(backwards, 0u);
  EXPECT_EQ(law(at(0.0))[1].kd, 20000.0);  // the last one arrives
}

TEST(BlmcFrontEnd, TheBackEndAllocatesNothing) {
  if (!AXON_COUNT_ALLOCATIONS) GTEST_SKIP() << "the sanitizers own operator new";
  FrontEnd fe(options(50ms, 20ms));
  auto law = fe.law();
  fe.set_currents({0.2, 0.1});
  const auto before = g_allocations.load();
  tl_count_allocations = true;
  Command sum{};
  for (int k = 0; k < 100; ++k) sum[0].current_a += law(at(k * 0.001, static_cast<std::uint64_t>(k)))[0].current_a;
  tl_count_allocations = false;
  EXPECT_EQ(g_allocations.load() - before, 0u);
  EXPECT_GT(sum[0].current_a, 0.0);  // it ran: stale after 20 ms, idle then
}

// Against the simulated board.

TEST(BlmcFrontEndBoard, NoFirstActionInTimeEndsTheRunWithTheMotorsDisabled) {
  sim::SimulatedBoard sim(sim_options());
  MotorBoard board(sim.bus_spec(), board_options());
  board.enable();
  FrontEnd fe(options(200ms, 100ms));
  board.start_control(fe, settings());
  ASSERT_TRUE(wait_for([&] { return !board.control_running(); }));
  const auto report = board.stop_control();
  EXPECT_EQ(report.end, ControlEnd::no_first_action);
  EXPECT_FALSE(report.fault) << report.fault_text;
  EXPECT_EQ(report.actions.actions, 0u);
  EXPECT_EQ(report.actions.idle_cycles, report.actions.cycles);
  EXPECT_FALSE(board.enabled());
  expect_board_off(sim);
}

TEST(BlmcFrontEndBoard, TheSafetyClampsTheActionAndTheIdleActionFollowsTheFrontEndsEnd) {
  sim::SimulatedBoard sim(sim_options());
  MotorBoard board(sim.bus_spec(), board_options());
  board.enable();
  FrontEnd fe(options(2000ms, 100ms));
  auto s = settings();
  s.limits.max_current_a = 0.5;
  s.limits.max_velocity_krpm = 100;  // the clamp is under test, not the velocity limit
  board.start_control(fe, s);
  // The front end at its own pace until the board shows the clamped currents.
  const auto clamped = [&] {
    fe.set_currents({2.0, -2.0});
    const auto r = sim.report();
    return r.motors[0].iq_ref_a == 0.5 && r.motors[1].iq_ref_a == -0.5;
  };
  ASSERT_TRUE(wait_for(clamped));
  EXPECT_EQ(fe.applied().command[0].current_a, 2.0);  // the law's action, before the clamp
  EXPECT_EQ(fe.applied().source, ActionSource::action);
  // The front end stops: the back end goes idle after 100 ms and the board gets zero current.
  ASSERT_TRUE(wait_for([&] { return fe.applied().source == ActionSource::stale; }));
  ASSERT_TRUE(wait_for([&] { return sim.report().motors[0].iq_ref_a == 0.0 && sim.report().motors[1].iq_ref_a == 0.0; }));
  const auto report = board.stop_control();
  EXPECT_EQ(report.end, ControlEnd::requested);
  EXPECT_FALSE(report.fault) << report.fault_text;
  EXPECT_GT(report.actions.stale_cycles, 0u);
  EXPECT_GE(report.actions.stale_episodes, 1u);  // the end's, and any stall of this thread before
  EXPECT_GE(report.actions.first_action_s, 0.0);
  EXPECT_TRUE(board.enabled());  // a requested end leaves the motors on, at zero current
}

// The whole cycle on the loop's thread (poll, law, safety, frame, record): counted from the first
// call of the law to its last, so the thread's start and end are not.
TEST(BlmcFrontEndBoard, TheControlCycleAllocatesNothing) {
  if (!AXON_COUNT_ALLOCATIONS) GTEST_SKIP() << "the sanitizers own operator new";
  sim::SimulatedBoard sim(sim_options());
  MotorBoard board(sim.bus_spec(), board_options());
  board.enable();
  FrontEnd fe(options(2000ms, 50ms));
  std::atomic<std::uint64_t> first{0}, last{0};
  ControlLaw back_end = fe.law();
  ControlLaw counted = [&, back_end](const ControlState& s) {
    if (!tl_count_allocations) {
      tl_count_allocations = true;
      first = g_allocations.load();
    }
    last = g_allocations.load();
    return back_end(s);
  };
  fe.set_currents({0.1, -0.1});
  board.start_control(counted, settings());
  ASSERT_TRUE(wait_for([&] { return fe.state().cycle >= 300; }));
  const auto report = board.stop_control();
  EXPECT_FALSE(report.fault) << report.fault_text;
  EXPECT_EQ(last.load(), first.load()) << "allocations between the first and the last cycle";
}

}  // namespace
}  // namespace axon::blmc::front_end_tests
