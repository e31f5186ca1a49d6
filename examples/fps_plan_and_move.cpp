// fps_plan_and_move: reconfigure a whole focal plane. The path planner plans collision-free
// trajectories from where every robot stands to its target, its independent checker verifies
// them, the robots run them together, and the program reads every robot back and checks it
// stands within 0.1 degrees of where the plan put it. With no argument it runs on the six-robot
// benchtop plane simulated in this process (and checks the simulator saw no collision). Against a
// real plane, give its layout file (the gateways' addresses come from it):
//   fps_plan_and_move site-layout.yaml
#include <axon/fps/host/client.hpp>
#include <axon/fps/layout/layout_name.hpp>
#include <axon/fps/sim/simulated_plane.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <map>
#include <memory>

int main(int argc, char** argv) try {
  constexpr double kTolerance = 0.1;  // degrees, per arm
  std::unique_ptr<axon::fps::sim::SimulatedPlane> simulated;
  if (argc < 2) simulated = std::make_unique<axon::fps::sim::SimulatedPlane>("benchtop");
  const axon::fps::FocalPlane plane = simulated ? simulated->plane() : axon::fps::resolve_layout(argv[1]).value();

  axon::fps::Client fps;
  fps.open(plane);  // one CAN@net connection per gateway of the layout
  std::printf("%zu robots answered\n", fps.discover().size());

  // Targets: beta half unfolded, alpha turning from robot to robot.
  std::map<std::uint16_t, axon::fps::Angles> targets;
  int k = 0;
  for (const auto& r : plane.robots()) targets[r.id] = {60.0 + 15.0 * (k++ % 7), 160.0};

  const auto done = fps.plan_and_move(targets);  // plan from the live positions, verify, run, follow
  std::printf("plan: %zu robots, %zu not reached, %s (min clearance %.2f mm), %.1f s move, planned in %.2f s\n",
              done.plan.robots, done.plan.not_reached, done.plan.verified ? "verified" : "NOT verified",
              done.plan.min_clearance_mm, done.plan.move_s, done.plan.plan_s);
  std::printf("move: %s\n", done.move.completed ? "every robot completed" : done.move.summary.c_str());

  // Read every robot back and compare with where the plan leaves it.
  double worst = 0;
  std::size_t at_target = 0;
  const auto now = fps.status();
  for (const auto& r : now) {
    if (!r.position || !done.plan.ends.contains(r.id)) continue;
    const auto& end = done.plan.ends.at(r.id);
    const double error = std::max(std::abs(r.position->alpha - end.alpha), std::abs(r.position->beta - end.beta));
    worst = std::max(worst, error);
    at_target += error <= kTolerance ? 1 : 0;
  }
  const auto collisions = simulated ? simulated->collisions() : 0;
  std::printf("check: %zu of %zu robots within %.1f deg of their planned end (worst %.4f deg); %llu collisions\n",
              at_target, now.size(), kTolerance, worst, static_cast<unsigned long long>(collisions));
  const bool ok = done.plan.verified && done.move.completed && !now.empty() && at_target == now.size() && collisions == 0;
  return ok ? 0 : 1;
} catch (const std::exception& e) {  // axon::Exception: what failed, and its error code
  std::fprintf(stderr, "fps_plan_and_move: %s\n", e.what());
  return 1;
}
