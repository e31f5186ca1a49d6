"""axon from Python: fiber positioner arrays (axon.fps), motor driver boards (axon.blmc), robot
controllers' open interface (axon.c4g) and CAN buses (axon.can).

The work is done by axon's C++ libraries (the extension axon._axon); this package re-exports it
with Python names. Every blocking call releases the GIL and answers Ctrl-C (KeyboardInterrupt)
after stopping what it set moving. Errors are axon.Error and its subclasses (docs/python.md).
"""

from . import _axon
from ._axon import (
    Cancelled,
    ClosedError,
    ConnectionError,
    Error,
    InvalidArgument,
    TimeoutError,
)

__version__ = _axon.__version__

from . import blmc, c4g, can, fps  # noqa: E402  (after the names they use)

__all__ = [
    "Cancelled",
    "ClosedError",
    "ConnectionError",
    "Error",
    "InvalidArgument",
    "TimeoutError",
    "__version__",
    "blmc",
    "c4g",
    "can",
    "fps",
]
