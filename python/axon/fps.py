"""axon.fps: fiber positioner arrays.

Layouts (Layout.load / Layout.generate, robots as a numpy table, neighbours), the collision-free
planner (plan: poses as (N, 2) arrays of degrees, the same result as `axon fps plan`), the
blocking array client (Client) and the whole focal plane simulated in this process
(SimulatedPlane). Angles are (alpha, beta) in degrees, times in seconds, positions in mm.
"""

import numpy as np

from ._axon.fps import (
    BadTarget,
    FrictionFinding,
    FrictionFit,
    FrictionPoint,
    FrictionReport,
    HallFinding,
    HallTestReport,
    Cancelled,
    Client,
    Closed,
    CollisionLocked,
    Error,
    InvalidArgument,
    Layout,
    MotionLocked,
    MoveOutcome,
    NotReady,
    Plan,
    PlanAndMoveOutcome,
    PlanCollision,
    PlanError,
    PlanOutcome,
    PlcConnectFailed,
    RobotMove,
    RobotStatus,
    RobotUpgrade,
    SimulatedPlane,
    StopOutcome,
    Timeout,
    UnknownPositioner,
    UnlockOutcome,
    FirmwareOutcome,
    SextantUpgrade,
    folded_poses,
    plan,
    random_poses,
    simulated_firmware_image,
)

_ROBOT_FIELDS = ["id", "x_mm", "y_mm", "sextant", "gateway", "bus", "disabled", "offline"]


def _robots(layout):
    """The layout's robots as a numpy record array (fields id, x_mm, y_mm, sextant, gateway, bus,
    disabled, offline), layout order."""
    columns = layout._robot_columns()
    return np.rec.fromarrays([columns[f] for f in _ROBOT_FIELDS], names=_ROBOT_FIELDS)


Layout.robots = property(_robots)
Layout.ids = property(lambda self: self._robot_columns()["id"])

_STATUS_DTYPE = [
    ("id", "u2"),
    ("state", "U16"),
    ("ready", "?"),
    ("firmware", "U16"),
    ("alpha", "f8"),
    ("beta", "f8"),
    ("bus", "U64"),
]


def status_records(rows):
    """[RobotStatus] as a numpy record array (id, state, ready, firmware, alpha, beta, bus);
    alpha and beta are NaN for a robot that did not give its position."""
    nan = float("nan")
    values = [
        (r.id, r.state, r.ready, r.firmware, *(r.position or (nan, nan)), r.bus) for r in rows
    ]
    return np.rec.array(np.array(values, dtype=_STATUS_DTYPE))


def _status_table(self):
    """status() as a numpy record array (see status_records)."""
    return status_records(self.status())


Client.status_table = _status_table


def _open_plane(self, plane):
    """Opens every gateway of a SimulatedPlane (or a Layout with reachable addresses)."""
    self.open(plane.layout if isinstance(plane, SimulatedPlane) else plane)


Client.open_plane = _open_plane


def plan_paths(p, ids=None):
    """A Plan's trajectories as Client.run_trajectories takes them: {id: (alpha, beta)}, without
    each arm's first point (the start, which the robot adds itself)."""
    wanted = set(int(i) for i in ids) if ids is not None else None
    paths = {}
    for robot_id in p.ids:
        if wanted is not None and int(robot_id) not in wanted:
            continue
        alpha, beta = p.trajectory(int(robot_id))
        paths[int(robot_id)] = (alpha[1:], beta[1:])
    return paths


__all__ = [name for name in dir() if not name.startswith("_") and name not in ("np",)]
