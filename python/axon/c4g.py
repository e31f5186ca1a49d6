"""axon.c4g: serving a C4G robot controller's open interface (one UDP packet per 1 or 2 ms cycle,
each answered before the next) with one of the built-in applications.

    positions = np.zeros((1000, 6)); positions[:, 0] = np.linspace(0, 5, 1000)   # degrees, a row a cycle
    with axon.c4g.Server(axon.c4g.Stream(positions, relative=True)) as server:      # 127.0.0.1, any free port
        with axon.c4g.SimulatedController(server, program=PROGRAM) as controller:
            report = server.run()            # until the trajectory was played and the arm is back in mode 0
            seen = controller.wait()
    print(report.stats, seen.joints_deg(1))

The application (Monitor, Echo, Stream, Correct, Pid, Contribute, Handover) is built whole before the server starts,
its trajectory copied into C++: Python never runs inside the cycle. Angles are degrees on the
link side, times seconds; motor-side figures are in motor turns.
"""

from ._axon.c4g import (
    App,
    ControllerEvent,
    Contribute,
    ControllerStats,
    Correct,
    Echo,
    Error,
    Handover,
    Monitor,
    OpenModeApp,
    Pid,
    ServeReport,
    ServeStats,
    ServeTiming,
    Server,
    SimulatedController,
    SimulatedControllerReport,
    Stream,
)


def open_program(mode, *, arm=1, wait_s=10.0, delay_s=0.2, type="A"):
    """A robot program for SimulatedController (YAML text): drive on, open mode `mode` on `arm`,
    wait for the PC to end it (at most wait_s), pause delay_s, end the exchange (504)."""
    delay = f"  - delay: {delay_s}\n" if delay_s > 0 else ""
    return (f"steps:\n  - drive_on\n  - go_open: {{type: {type}, mode: {mode}, arms: [{arm}]}}\n"
            f"  - wait_for_pc: {{timeout: {wait_s}}}\n{delay}  - exit_open\n")


__all__ = [name for name in dir() if not name.startswith("_")]
