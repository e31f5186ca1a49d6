#!/usr/bin/env python3
"""blmc_pd_control: PD position control of both motors of a motor driver board from Python, as
examples/blmc_pd_control.cpp does from C++: each motor moves from where it stands by its own
distance (+0.5 and -0.25 motor revolutions) along a smooth 1 s ramp, then holds. The PD law runs at
1 kHz on the library's real-time thread; this program is its front end at 100 Hz: it sets the next
target (with its velocity) and reads the latest measurements, and never runs inside the cycle. It
checks that the following error stayed under 0.05 rev, that no safety stop happened and that each
motor ends within 0.02 rev of its target; it exits 0 only then.
    python3 blmc_pd_control.py                   an in-process simulated board
    python3 blmc_pd_control.py socketcan:can0    a real board (any bus spec: socketcand://HOST:29536/can0 ...)
From the build tree: PYTHONPATH=build/release/python /usr/bin/python3 examples/python/blmc_pd_control.py
"""

import sys
import time

import numpy as np

import axon

MOVE_REV = np.array([0.5, -0.25])
RAMP_S, HOLD_S, KP, KD = 1.0, 1.5, 8.0, 0.1  # s, s, A/rev, A/(rev/s)
FOLLOWING_BOUND_REV, FINAL_BOUND_REV = 0.05, 0.02


def ramp(t):
    """Smoothstep from 0 to 1 over RAMP_S: (shape, its rate per second)."""
    f = min(1.0, max(0.0, t / RAMP_S))
    return f * f * (3 - 2 * f), 6 * f * (1 - f) / RAMP_S


def main(argv):
    simulated = axon.blmc.SimulatedBoard() if len(argv) < 2 else None
    bus = simulated.bus_spec if simulated else argv[1]
    # A simulator shares this machine's cores with the loop: its timing checks get slack that a
    # real board's (10 ms stale data, 50 ms receive timeout) do not.
    slack = dict(stale_data_s=0.2) if simulated else {}
    with axon.blmc.MotorBoard(bus, recv_timeout_ms=250 if simulated else 50) as board:
        board.enable()  # aligns the motors on the first enable after power-up
        print(f"board on {bus} enabled")
        board.start(max_current_a=1.5, max_velocity_krpm=0.5, stale_after_s=0.1, **slack)
        start = board.state.position_rev
        worst = np.zeros(2)
        t0 = time.monotonic()
        while time.monotonic() - t0 < RAMP_S + HOLD_S:
            state = board.state  # the latest cycle's measurements
            shape, rate = ramp(time.monotonic() - t0)
            target = start + MOVE_REV * shape
            if board.applied.action:  # the error against the target the loop is tracking
                tracked = np.array([c.position_rev for c in board.applied.command])
                worst = np.maximum(worst, np.abs(tracked - state.position_rev))
            board.set_pd(target, (KP, KD), velocities_rev_s=MOVE_REV * rate)
            time.sleep(0.01)
        end = board.state.position_rev
        report = board.stop()

    ok = report.fault is None
    print(f"loop: {report.cycles} cycles, jitter p99 {report.stats.jitter_p99_s * 1e6:.0f} us, {report.overruns} overruns; "
          f"front end: {report.actions.actions} actions, {report.actions.stale_cycles} stale cycles; "
          f"safety: {report.fault_text or 'no fault'}")
    for k in range(2):
        goal = start[k] + MOVE_REV[k]
        miss = abs(end[k] - goal)
        good = worst[k] < FOLLOWING_BOUND_REV and miss < FINAL_BOUND_REV
        print(f"check: motor {k + 1}: {start[k]:+.4f} -> {end[k]:+.4f} rev (target {goal:+.4f}): following error max "
              f"{worst[k]:.4f} rev (< {FOLLOWING_BOUND_REV}), final error {miss:.4f} rev (< {FINAL_BOUND_REV}): "
              f"{'ok' if good else 'FAILED'}")
        ok = ok and good
    if simulated:
        simulated.stop()
    print("PASS" if ok else "FAIL")
    return 0 if ok else 1


if __name__ == "__main__":
    try:
        sys.exit(main(sys.argv))
    except axon.Error as e:  # what failed, with its category and code
        print(f"blmc_pd_control: {e}", file=sys.stderr)
        sys.exit(1)
