#!/usr/bin/env python3
"""fps_status: find every fiber positioner on the buses and print its status table (state, firmware,
arm angles) from Python, as examples/fps_status.cpp does from C++. With no argument it starts the
six-robot benchtop plane simulated in this process and checks that every robot of it answered,
ready to move; it exits 0 only then. Against real robots, give your gateways' buses:
    python3 fps_status.py cannet://10.25.1.11:19228/1 cannet://10.25.1.11:19228/2
From the build tree: PYTHONPATH=build/release/python /usr/bin/python3 examples/python/fps_status.py
"""

import sys

import axon


def main(argv):
    simulated = axon.fps.SimulatedPlane("benchtop") if len(argv) < 2 else None
    buses = simulated.bus_specs if simulated else argv[1:]

    with axon.fps.Client() as fps:  # its own event loop, on its own thread
        fps.open(buses)
        robots = fps.discover()  # GET_ID on every bus, then firmware and status of each robot
        print(f"{'robot':>5}  {'state':<11}  {'firmware':<9}  {'alpha':>8}  {'beta':>8}  bus")
        for r in robots:
            angles = f"{r.position[0]:8.3f}  {r.position[1]:8.3f}" if r.position else f"{'-':>8}  {'-':>8}"
            print(f"{r.id:5d}  {r.state:<11}  {r.firmware:<9}  {angles}  {r.bus}  {r.error}")
        ready = sum(r.ready for r in robots)
        print(f"{len(robots)} robots, {ready} ready")

    expected = len(simulated.layout.ids) if simulated else len(robots)
    ok = bool(robots) and len(robots) == expected and ready == len(robots)
    print(f"check: {expected} robots expected, every one found and ready: {'yes' if ok else 'NO'}")
    return 0 if ok else 1


if __name__ == "__main__":
    try:
        sys.exit(main(sys.argv))
    except axon.Error as e:  # what failed, with its category and code
        print(f"fps_status: {e}", file=sys.stderr)
        sys.exit(1)
