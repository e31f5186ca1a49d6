"""axon.can: CAN frames, buses opened from a spec string, candump logs.

    bus = axon.can.Bus("socketcand://127.0.0.1:29536/vcan0")   # or virtual:NAME in this process
    bus.send(axon.can.Frame(0x123, b"\\xde\\xad"))
    frame = bus.recv(timeout_s=1.0)                              # None when nothing came
    for entry in axon.can.LogReader("dump.log"): print(entry.frame)
"""

from ._axon.can import (
    Bus,
    BusOff,
    BusStats,
    Closed,
    ConnectFailed,
    Error,
    Frame,
    InvalidFrame,
    LogEntry,
    LogReader,
    LogWriter,
    ParseError,
    Timeout,
)


def read_log(path, skip_bad=False):
    """The entries of a candump log file, one by one (an iterator of LogEntry)."""
    return LogReader(path, skip_bad=skip_bad)


__all__ = [
    "Bus",
    "BusOff",
    "BusStats",
    "Closed",
    "ConnectFailed",
    "Error",
    "Frame",
    "InvalidFrame",
    "LogEntry",
    "LogReader",
    "LogWriter",
    "ParseError",
    "Timeout",
    "read_log",
]
