#!/usr/bin/env python3
"""c4g_control_law: mode 1 from Python, where the PC closes the position and velocity loops of arm 1
and sends the motor currents, as examples/c4g_control_law.cpp does with a law of its own. Python
cannot run inside the 2 ms cycle, so the law here is the library's built-in one (axon.c4g.Pid: a
P-P cascade with the controller's dynamic-model current as feed-forward), configured from Python and
run on the server's real-time thread: hold the arm where the mode begins and swing axis 1 by 0.1 deg
at 1 Hz for 2 s (faded in and out), then leave mode 1. It checks the following error stayed within
0.01 motor turns, no safety fault, every cycle answered, and the arm back where it began.
    python3 c4g_control_law.py                   an in-process simulated controller plays the program
    python3 c4g_control_law.py 10.2.12.149:1000  serve a real controller on this address; its program
                                                 must DRIVE ON, GO OPEN TYPE A in mode 1, WAIT FOR PC
From the build tree: PYTHONPATH=build/release/python /usr/bin/python3 examples/python/c4g_control_law.py
"""

import sys

import numpy as np

import axon

BOUND_TURNS = 0.01  # following error, motor side
SWING_DEG = [0.1, 0, 0, 0, 0, 0]


def main(argv):
    app = axon.c4g.Pid(amplitude_deg=SWING_DEG, frequency_hz=1.0, open_time_s=2.0, ramp_s=0.3)
    listen = argv[1] if len(argv) > 1 else "127.0.0.1:0"
    with axon.c4g.Server(app, listen=listen, until_controller_ends=True, duration_s=60) as server:
        print(f"serving mode 1 on {server.address}")
        if len(argv) > 1:
            report, seen = server.run(), None
        else:
            # reply_window="period": the lenient window, for a machine that also runs the simulator.
            with axon.c4g.SimulatedController(server, program=axon.c4g.open_program(1), reply_window="period") as controller:
                report = server.run()
                seen = controller.wait(timeout_s=30)
    print(report.text(), end="")
    worst = app.max_following_error_turns
    ok = report.finished and report.stats.safety_fault == "none" and worst < BOUND_TURNS
    print(f"law ran {app.elapsed_s:.2f} s; worst following error {worst:.5f} motor turns (bound {BOUND_TURNS}); "
          f"{app.saturated_cycles} cycles with a saturated current")
    if seen is not None:
        back = float(np.max(np.abs(seen.joints_deg(1))))
        answered = report.stats.packets == seen.stats.packets_sent
        print(f"controller: {seen.outcome_text}, {seen.stats.packets_sent} packets sent, {report.stats.packets} answered, "
              f"{seen.stats.misses} late; the arm ends {back:.4f} deg from where it began")
        ok = ok and seen.exit_code == 0 and answered and back < 0.05
    print(f"check: following error within {BOUND_TURNS} turns, no safety fault, every cycle answered: "
          f"{'ok' if ok else 'FAILED'}")
    return 0 if ok else 1


if __name__ == "__main__":
    try:
        sys.exit(main(sys.argv))
    except axon.Error as e:  # what failed, with its category and code
        print(f"c4g_control_law: {e}", file=sys.stderr)
        sys.exit(1)
