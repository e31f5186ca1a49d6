#!/usr/bin/env python3
"""What Python costs the C++ underneath it (issue 17), measured in one run on one machine.

1. The blmc 1 kHz loop with and without a Python front end. A simulated board in this process, the
   host's loop on its real-time thread; runs alternate between "no front end" (the loop applies its
   idle action, zero current) and "Python front end" (a Python thread calling set_pd() and reading
   the latest state at 1 kHz, as fast as Python does it). Per run: the loop's jitter (|period -
   1 ms|, p99 and max), overruns, missed deadlines, and how many actions the front end got through.
   jitter_ratio = median p99 with Python / median p99 without.
2. Planning from Python against the CLI: the same 500-robot problem (data/layouts/default.yaml,
   random to random, one seed) planned by axon.fps.plan() and by `axon fps plan`, alternating.
   plan_ratio = median Python wall time / median CLI wall time (the CLI's includes starting the
   process and writing plan.json; both plan with the same engine, so ~1 is expected).

usage: /usr/bin/python3 bench/python_front_end.py [BUILD_DIR] [--rounds N] [--seconds S]
       (Debian's python3 with python3-numpy; BUILD_DIR defaults to build/release)
Ends with one line: BENCH python_front_end jitter_ratio=... plan_ratio=... ratio=...
"""
import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))


def parse():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("build", nargs="?", default=os.path.join(ROOT, "build", "release"))
    p.add_argument("--rounds", type=int, default=3, help="runs of each kind (default 3)")
    p.add_argument("--seconds", type=float, default=3.0, help="length of one loop run (default 3 s)")
    return p.parse_args()


def loop_run(board, seconds, front_end):
    """One control run of `seconds`; with front_end, a Python thread drives it at 1 kHz."""
    stop = threading.Event()
    actions = [0]

    def drive():
        next_t = time.monotonic()
        while not stop.is_set():
            s = board.state
            board.set_pd([0.0, 0.0], (2.0, 0.02), velocities_rev_s=[0.0, 0.0])
            actions[0] += 1
            next_t += 0.001
            delay = next_t - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            del s

    board.start(max_current_a=0.5, max_velocity_krpm=100.0, stale_data_s=0.5, first_action_timeout_s=60.0,
                stale_after_s=0.5)
    t = threading.Thread(target=drive) if front_end else None
    if t:
        t.start()
    time.sleep(seconds)
    stop.set()
    if t:
        t.join()
    r = board.stop()
    return {"p99_us": r.stats.jitter_p99_s * 1e6, "max_us": r.stats.jitter_max_s * 1e6, "overruns": r.stats.overruns,
            "missed": r.stats.missed, "cycles": r.stats.cycles, "actions": actions[0], "fault": r.fault_text}


def bench_loop(axon, rounds, seconds):
    runs = {False: [], True: []}
    with axon.blmc.SimulatedBoard(alignment_time_s=0.2) as sim, \
            axon.blmc.MotorBoard(sim.bus_spec, recv_timeout_ms=500) as board:
        board.enable()
        for i in range(rounds):
            for front_end in (False, True):
                r = loop_run(board, seconds, front_end)
                runs[front_end].append(r)
                print(f"blmc loop {'with Python' if front_end else 'no front end'} run {i + 1}: jitter p99 "
                      f"{r['p99_us']:.0f} us max {r['max_us']:.0f} us, {r['cycles']} cycles, {r['overruns']} overruns, "
                      f"{r['missed']} missed, {r['actions']} Python actions ({r['actions'] / seconds:.0f}/s)"
                      f"{', fault: ' + r['fault'] if r['fault'] else ''}", flush=True)
    without = statistics.median(r["p99_us"] for r in runs[False])
    with_py = statistics.median(r["p99_us"] for r in runs[True])
    rate = statistics.median(r["actions"] / seconds for r in runs[True])
    return without, with_py, rate, sum(r["overruns"] for r in runs[True])


def bench_plan(axon, cli, rounds, seed=3):
    layout_file = os.path.join(ROOT, "data", "layouts", "default.yaml")
    layout = axon.fps.Layout.load(layout_file)
    times = {"python": [], "cli": []}
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(rounds):
            t0 = time.monotonic()
            p = axon.fps.plan(layout, "random", "random", seed=seed)
            times["python"].append(time.monotonic() - t0)
            t0 = time.monotonic()
            subprocess.run([cli, "fps", "plan", "--layout", layout_file, "--from", "random", "--to", "random",
                            "--seed", str(seed), "-o", os.path.join(tmp, "plan.json")], check=True, capture_output=True)
            times["cli"].append(time.monotonic() - t0)
            print(f"plan 500 robots run {i + 1}: Python {times['python'][-1]:.3f} s (verified {p.verified}), "
                  f"CLI {times['cli'][-1]:.3f} s", flush=True)
    return statistics.median(times["python"]), statistics.median(times["cli"])


def main():
    a = parse()
    sys.path.insert(0, os.path.join(a.build, "python"))
    import axon  # noqa: E402 (from the build tree)
    cli = os.path.join(a.build, "axon")
    without, with_py, rate, overruns = bench_loop(axon, a.rounds, a.seconds)
    py_s, cli_s = bench_plan(axon, cli, a.rounds)
    jitter_ratio = with_py / without if without > 0 else float("nan")
    plan_ratio = py_s / cli_s
    print(f"blmc loop jitter p99: {without:.0f} us without a front end, {with_py:.0f} us with a Python front end "
          f"at {rate:.0f} actions/s ({overruns} overruns with it)")
    print(f"planning 500 robots: Python {py_s:.3f} s, CLI {cli_s:.3f} s (medians of {a.rounds})")
    print(f"BENCH python_front_end jitter_p99_us={without:.0f} jitter_p99_us_python={with_py:.0f} python_actions_per_s={rate:.0f} "
          f"plan_s_python={py_s:.3f} plan_s_cli={cli_s:.3f} jitter_ratio={jitter_ratio:.2f} plan_ratio={plan_ratio:.2f} "
          f"ratio={max(jitter_ratio, plan_ratio):.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
