#!/usr/bin/env python3
"""c4g_trajectory: a mode 4 server streaming a joint trajectory from numpy to a C4G controller, as
examples/c4g_joint_trajectory.cpp does from C++. Arm 1's axes 1-3 move 10, -5 and 5 degrees and
back over 3 s, relative to where the arm starts (a row every 10 ms, sampled each controller cycle).
The trajectory is handed to the server whole before the first packet: Python never runs inside the
cycle. It checks that the trajectory was played, no safety stop, every packet answered (late replies
are counted, not failed) and, on the simulated controller, that the arm came back to where it began
(within 0.05 degrees). With no argument an in-process simulated controller plays the robot program;
against a real controller give the address to serve on (its program must DRIVE ON, GO OPEN TYPE A
in mode 4, WAIT FOR PC):
    python3 c4g_trajectory.py 10.2.12.149:1000
From the build tree: PYTHONPATH=build/release/python /usr/bin/python3 examples/python/c4g_trajectory.py
"""

import sys

import numpy as np

import axon

TOLERANCE = 0.05  # degrees, per joint, back at the start


def main(argv):
    # A raised cosine out and back, one row per 10 ms: (301, 6) degrees, offsets from the start.
    t = np.arange(301) * 0.01
    s = 0.5 - 0.5 * np.cos(2 * np.pi * t / 3.0)
    positions = np.outer(s, [10.0, -5.0, 5.0, 0.0, 0.0, 0.0])
    app = axon.c4g.Stream(positions, dt_s=0.01, mode=4, relative=True)

    listen = argv[1] if len(argv) > 1 else "127.0.0.1:0"
    # until_controller_ends: answer the robot program to its end, not only our part of it;
    # duration_s: a bound, should the controller never end.
    with axon.c4g.Server(app, listen=listen, until_controller_ends=True, duration_s=60) as server:
        print(f"serving mode 4 on {server.address}")
        controller = None
        if len(argv) <= 1:
            # The lenient reply window (a whole period): this runs on shared, loaded test machines;
            # reply_window="manual" holds the server to the manual's 500 us.
            controller = axon.c4g.SimulatedController(server, program=axon.c4g.open_program(4, delay_s=0.2),
                                                      reply_window="period")
        report = server.run()
        print(report.text(), end="")
        stats = report.stats
        ok = report.finished and stats.safety_fault == "none"
        print(f"check: trajectory played: {'yes' if report.finished else 'no'} ({app.rows} cycles); "
              f"{stats.cyclic_packets} cycles, processing time p99 {stats.timing.cycle_time_p99_s * 1e6:.0f} us, "
              f"{stats.controller_late} late, safety fault: {stats.safety_fault}")
        if controller:
            seen = controller.wait()
            back = seen.joints_deg(1)
            print(f"check: controller: {seen.outcome_text}, {seen.stats.packets_sent} packets sent, "
                  f"{stats.packets} answered, {seen.stats.misses} late; arm 1 back at "
                  f"{back[0]:.3f} {back[1]:.3f} {back[2]:.3f} deg (bound {TOLERANCE})")
            ok = (ok and seen.exit_code == 0 and stats.packets == seen.stats.packets_sent
                  and bool(np.all(np.abs(back) < TOLERANCE)))
    print("OK" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    try:
        sys.exit(main(sys.argv))
    except axon.Error as e:  # what failed, with its category and code
        print(f"c4g_trajectory: {e}", file=sys.stderr)
        sys.exit(1)
