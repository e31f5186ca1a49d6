#!/usr/bin/env python3
"""blmc_homing: homing on the encoder index from Python, as examples/blmc_homing.cpp does from C++.
Each motor turns slowly under a soft, current-limited PD on the library's 1 kHz loop until the board
reports its encoder's index mark; the mark's position is the motor's offset. With the simulated board
the marks sit at 0.3 and 0.7 rev and the program checks that homing found them within 0.001 rev; on
a real board, that each motor found its mark within a revolution of where it started. It exits 0
only then.
    python3 blmc_homing.py                   an in-process simulated board
    python3 blmc_homing.py socketcan:can0    a real board (any bus spec: socketcand://HOST:29536/can0 ...)
From the build tree: PYTHONPATH=build/release/python /usr/bin/python3 examples/python/blmc_homing.py
"""

import sys

import axon

SIMULATED_INDEX_REV = (0.3, 0.7)
SIMULATED_TOLERANCE_REV = 0.001


def main(argv):
    simulated = axon.blmc.SimulatedBoard(index_offset_rev=SIMULATED_INDEX_REV) if len(argv) < 2 else None
    bus = simulated.bus_spec if simulated else argv[1]
    # A simulator shares this machine's cores with the loop: its timing checks get slack that a
    # real board's (10 ms stale data, 50 ms receive timeout) do not.
    slack = dict(stale_data_s=0.2) if simulated else {}
    with axon.blmc.MotorBoard(bus, recv_timeout_ms=250 if simulated else 50) as board:
        board.enable()
        print(f"board on {bus} enabled")
        # Half a turn a second in the positive direction, never pushing harder than 0.5 A; a mark
        # comes once a revolution.
        report = board.home(speed_rev_s=0.5, max_current_a=0.5, max_travel_rev=1.2, timeout_s=10, **slack)
        board.disable()

    ok = report.control.fault is None and report.all_found
    if report.control.fault:
        print(f"safety stop: {report.control.fault_text}")
    for k, m in enumerate(report.motors):
        found = m.state == "found"
        if simulated:
            good = found and abs(m.index_rev - SIMULATED_INDEX_REV[k]) < SIMULATED_TOLERANCE_REV
            where = f" (simulated mark at {SIMULATED_INDEX_REV[k]})"
        else:
            good = found and abs(m.index_rev - m.start_rev) <= 1.0
            where = ""
        print(f"check: motor {k + 1}: started at {m.start_rev:+.5f} rev, "
              + (f"index (offset) at {m.index_rev:+.5f} rev{where}" if found else f"no index ({m.state})")
              + f": {'ok' if good else 'FAILED'}")
        ok = ok and good
    if simulated:
        simulated.stop()
    print("PASS" if ok else "FAIL")
    return 0 if ok else 1


if __name__ == "__main__":
    try:
        sys.exit(main(sys.argv))
    except axon.Error as e:  # what failed, with its category and code
        print(f"blmc_homing: {e}", file=sys.stderr)
        sys.exit(1)
