#!/usr/bin/python3
"""candump log files between axon and python-can, both ways.

argv[1] is the axon binary. The test-only tool axon_candump_tool (tests/tools/candump_roundtrip.cpp)
comes from $AXON_CANDUMP_TOOL (set by tests/integration/CMakeLists.txt), else from tests/ next to
the axon binary.

1. axon writes its fixed set of frames; python-can's CanutilsLogReader must read every one exactly.
2. python-can's CanutilsLogWriter writes frames; axon must read every one exactly.
3. python-can writes a CAN FD frame; axon must refuse it with an error rather than misread it.

Exits non-zero on the first mismatch.
"""

import os
import subprocess
import sys
import tempfile

import can
from can.io.canutils import CanutilsLogReader, CanutilsLogWriter

# The tool's fixed set, written down independently here:
# (timestamp in microseconds, iface, id, extended, remote, dlc, data, error frame)
AXON_FRAMES = [
    (1436509052249713, "vcan0", 0x12345678, True, False, 4, bytes([1, 2, 3, 4]), False),
    (1436509052249714, "vcan0", 0x123, False, False, 4, bytes.fromhex("DEADBEEF"), False),
    (1436509052250000, "vcan0", 0x7FF, False, True, 0, b"", False),
    (1436509052300001, "can1", 0x42, True, True, 4, b"", False),
    (1436509053000000, "can1", 0x000, False, False, 0, b"", False),
    (1436509053999999, "vcan0", 0x1FFFFFFF, True, False, 8, bytes.fromhex("0011223344556677"), False),
    (1700000000123456, "vcan0", 0x555, False, False, 1, b"\xff", False),
    (1700000001000000, "can0", 0x080, True, False, 8, bytes(8), True),
]

failures = []


def check(cond, what):
    if not cond:
        failures.append(what)
        print("MISMATCH:", what, file=sys.stderr)


def find_tool(axon):
    tool = os.environ.get("AXON_CANDUMP_TOOL")
    if tool:
        return tool
    return os.path.join(os.path.dirname(os.path.abspath(axon)), "tests", "axon_candump_tool")


def micros(timestamp):
    return round(timestamp * 1e6)


def axon_writes_python_reads(tool, workdir):
    path = os.path.join(workdir, "axon.log")
    subprocess.run([tool, "write", path], check=True)
    with open(path) as f:
        print("axon wrote:\n" + f.read())
    messages = list(CanutilsLogReader(path))
    check(len(messages) == len(AXON_FRAMES), f"python-can read {len(messages)} frames, expected {len(AXON_FRAMES)}")
    for msg, (us, iface, can_id, ext, remote, dlc, data, error) in zip(messages, AXON_FRAMES):
        where = f"axon->python frame {can_id:X} at {us}"
        check(micros(msg.timestamp) == us, f"{where}: timestamp {msg.timestamp!r}")
        check(msg.is_error_frame == error, f"{where}: error frame {msg.is_error_frame}")
        if error:
            continue  # python-can keeps neither id nor data of error frames
        check(msg.channel == iface, f"{where}: channel {msg.channel!r}")
        check(msg.arbitration_id == can_id, f"{where}: id {msg.arbitration_id:X}")
        check(msg.is_extended_id == ext, f"{where}: extended {msg.is_extended_id}")
        check(msg.is_remote_frame == remote, f"{where}: remote {msg.is_remote_frame}")
        check(msg.dlc == dlc, f"{where}: dlc {msg.dlc}")
        check(bytes(msg.data) == data, f"{where}: data {bytes(msg.data).hex()}")


def parse_tool_line(line):
    fields = line.split()
    if len(fields) not in (3, 4):
        raise ValueError(f"tool printed {line!r}")
    ns, iface, frame = int(fields[0]), fields[1], fields[2]
    flag = fields[3] if len(fields) == 4 else ""
    return ns, iface, frame, flag


def frame_text(can_id, ext, remote, dlc, data, error):
    if error:
        return f"{0x20000000 | can_id:08X}#{data.hex().upper()}"
    text = f"{can_id:08X}#" if ext else f"{can_id:03X}#"
    if remote:
        return text + ("R" + str(dlc) if dlc else "R")
    return text + data.hex().upper()


def python_writes_axon_reads(tool, workdir):
    path = os.path.join(workdir, "python.log")
    # (message, expected text as axon prints it, expected flag)
    cases = [
        (can.Message(timestamp=1436509052.249713, arbitration_id=0x12345678, is_extended_id=True,
                     data=[1, 2, 3, 4], channel="vcan0"),
         frame_text(0x12345678, True, False, 4, bytes([1, 2, 3, 4]), False), "rx"),
        (can.Message(timestamp=1436509052.249714, arbitration_id=0x123, is_extended_id=False,
                     data=bytes.fromhex("DEADBEEF"), channel="vcan0", is_rx=False),
         frame_text(0x123, False, False, 4, bytes.fromhex("DEADBEEF"), False), "tx"),
        # python-can writes remote frames as plain `R`: the DLC does not survive its writer.
        (can.Message(timestamp=1436509052.300001, arbitration_id=0x42, is_extended_id=True,
                     is_remote_frame=True, dlc=4, channel="can1"),
         frame_text(0x42, True, True, 0, b"", False), "rx"),
        (can.Message(timestamp=1436509053.0, arbitration_id=0x0, is_extended_id=False, data=b"", channel="can1"),
         frame_text(0, False, False, 0, b"", False), "rx"),
        (can.Message(timestamp=1436509053.999999, arbitration_id=0x1FFFFFFF, is_extended_id=True,
                     data=bytes.fromhex("0011223344556677"), channel="vcan0"),
         frame_text(0x1FFFFFFF, True, False, 8, bytes.fromhex("0011223344556677"), False), "rx"),
        # An integer channel is written as canN.
        (can.Message(timestamp=1700000000.123456, arbitration_id=0x555, is_extended_id=False, data=b"\xff",
                     channel=2),
         frame_text(0x555, False, False, 1, b"\xff", False), "rx"),
        (can.Message(timestamp=1700000001.0, is_error_frame=True, channel="can0"),
         frame_text(0x80, True, False, 0, b"", True), "error"),
    ]
    writer = CanutilsLogWriter(path)
    for msg, _, _ in cases:
        writer.on_message_received(msg)
    writer.stop()
    with open(path) as f:
        print("python-can wrote:\n" + f.read())

    out = subprocess.run([tool, "read", path], check=True, capture_output=True, text=True).stdout
    lines = out.splitlines()
    check(len(lines) == len(cases), f"axon read {len(lines)} frames, expected {len(cases)}: {out!r}")
    for line, (msg, text, flag) in zip(lines, cases):
        ns, iface, frame, got_flag = parse_tool_line(line)
        where = f"python->axon {text}"
        expected_us = micros(msg.timestamp)
        check(ns == expected_us * 1000, f"{where}: timestamp {ns} ns, expected {expected_us} us")
        channel = msg.channel if isinstance(msg.channel, str) else f"can{msg.channel}"
        check(iface == channel, f"{where}: iface {iface}")
        check(frame == text, f"{where}: frame {frame}")
        check(got_flag == flag, f"{where}: flag {got_flag!r}")


def python_fd_is_refused(tool, workdir):
    path = os.path.join(workdir, "fd.log")
    writer = CanutilsLogWriter(path)
    writer.on_message_received(can.Message(timestamp=1.0, arbitration_id=0x123, is_extended_id=False, is_fd=True,
                                           data=bytes(12), channel="can0"))
    writer.stop()
    result = subprocess.run([tool, "read", path], capture_output=True, text=True)
    check(result.returncode == 2, f"reading a CAN FD log exited {result.returncode}")
    check("CAN FD" in result.stderr and "fd.log:1" in result.stderr, f"CAN FD refusal message: {result.stderr!r}")
    check(result.stdout == "", f"CAN FD log produced output {result.stdout!r}")


def main():
    if len(sys.argv) < 2:
        print("usage: python_can_log.py AXON_BINARY", file=sys.stderr)
        return 2
    tool = find_tool(sys.argv[1])
    if not os.access(tool, os.X_OK):
        print(f"cannot run {tool}; build the axon_candump_tool target", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory(prefix="axon-candump-") as workdir:
        axon_writes_python_reads(tool, workdir)
        python_writes_axon_reads(tool, workdir)
        python_fd_is_refused(tool, workdir)
    if failures:
        print(f"{len(failures)} mismatch(es)", file=sys.stderr)
        return 1
    print("python-can and axon agree on every frame")
    return 0


if __name__ == "__main__":
    sys.exit(main())
