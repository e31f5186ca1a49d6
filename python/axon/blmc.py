"""axon.blmc: motor driver boards (two brushless motors each) and their 1 kHz current loop.

The loop runs in C++ on its real-time thread; Python is its front end, at its own rate:

    with axon.blmc.SimulatedBoard() as sim, axon.blmc.MotorBoard(sim.bus_spec) as board:
        board.enable()                        # aligned and ready
        board.start(max_current_a=1.0)        # the loop runs, zero current until the first action
        board.set_currents([0.3, 0.0])        # amperes, one per motor; or set_pd(targets, gains)
        print(board.applied, board.state)     # what the last cycle applied and measured
        report = board.stop()                 # ControlReport: cycles, overruns, end, actions

Until the first action and whenever the latest is older than stale_after_s, the motors get zero
current (counted in report.actions); no first action within first_action_timeout_s ends the run
with the motors disabled (report.end == "no_first_action"). Units: amperes, motor revolutions,
seconds (the on-board controller: the spec's A/rev, A/krpm, krpm).
"""

from ._axon.blmc import (
    ActionStats,
    AppliedAction,
    BoardError,
    Closed,
    ControlReport,
    ControlRunning,
    ControlState,
    Error,
    HomingFailed,
    HomingReport,
    Interrupted,
    InvalidArgument,
    LoopFigures,
    LoopStats,
    Measurements,
    MotorBoard,
    MotorCommand,
    MotorHoming,
    NotEnabled,
    NotReady,
    NotRunning,
    SafetyFault,
    SimulatedBoard,
    SimulatedBoardReport,
    Status,
    Timeout,
)


def _run_control(self, duration_s, **settings):
    """start(**settings), wait duration_s (or until the run ends by itself), stop(): the
    ControlReport. Another Python thread is the front end meanwhile (the GIL is released); Ctrl-C
    disables the motors and raises KeyboardInterrupt."""
    self.start(**settings)
    self._wait_control(duration_s)
    return self.stop()


MotorBoard.run_control = _run_control

__all__ = [name for name in dir() if not name.startswith("_")]
