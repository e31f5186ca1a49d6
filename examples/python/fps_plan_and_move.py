#!/usr/bin/env python3
"""fps_plan_and_move: reconfigure a whole focal plane from Python, as examples/fps_plan_and_move.cpp
does from C++. The planner plans collision-free trajectories from where every robot stands to its
target, its checker verifies them, the robots run them together, and the program reads every robot
back and checks it stands within 0.1 degrees of where the plan put it. With no argument it runs on
the six-robot benchtop plane simulated in this process (and checks the simulator saw no collision).
Against a real plane, give its layout file (the gateways' addresses come from it):
    python3 fps_plan_and_move.py site-layout.yaml
From the build tree: PYTHONPATH=build/release/python /usr/bin/python3 examples/python/fps_plan_and_move.py
"""

import sys

import axon

TOLERANCE = 0.1  # degrees, per arm


def main(argv):
    simulated = axon.fps.SimulatedPlane("benchtop") if len(argv) < 2 else None
    layout = simulated.layout if simulated else axon.fps.Layout.load(argv[1])

    with axon.fps.Client() as fps:
        fps.open(layout)  # one CAN@net connection per gateway of the layout
        print(f"{len(fps.discover())} robots answered")

        # Targets: beta half unfolded, alpha turning from robot to robot.
        targets = {int(rid): (60.0 + 15.0 * (k % 7), 160.0) for k, rid in enumerate(layout.ids)}
        done = fps.plan_and_move(targets)  # plan from the live positions, verify, run, follow
        plan = done.plan
        print(f"plan: {plan.robots} robots, {plan.not_reached} not reached, "
              f"{'verified' if plan.verified else 'NOT verified'} (min clearance {plan.min_clearance_mm:.2f} mm), "
              f"{plan.move_s:.1f} s move, planned in {plan.plan_s:.2f} s")
        print("move:", "every robot completed" if done.move.completed else done.move.summary)

        # Read every robot back (a numpy table) and compare with where the plan leaves it.
        table = fps.status_table()
        errors = [max(abs(r.alpha - plan.ends[r.id][0]), abs(r.beta - plan.ends[r.id][1]))
                  for r in table if r.id in plan.ends]
        at_target = sum(e <= TOLERANCE for e in errors)
        collisions = simulated.collisions if simulated else 0
        print(f"check: {at_target} of {len(table)} robots within {TOLERANCE} deg of their planned end "
              f"(worst {max(errors, default=0):.4f} deg); {collisions} collisions")
        ok = plan.verified and done.move.completed and len(table) > 0 and at_target == len(table) and collisions == 0
    if simulated:
        simulated.stop()
    return 0 if ok else 1


if __name__ == "__main__":
    try:
        sys.exit(main(sys.argv))
    except axon.Error as e:  # what failed, with its category and code
        print(f"fps_plan_and_move: {e}", file=sys.stderr)
        sys.exit(1)
