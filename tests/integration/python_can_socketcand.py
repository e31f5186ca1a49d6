#!/usr/bin/python3
"""python-can (Debian's python3-can, a client nobody here wrote) against axon's socketcand server.

Usage:
    python_can_socketcand.py AXON_BINARY          starts `AXON_BINARY can bridge --listen 127.0.0.1:0`
    python_can_socketcand.py --connect HOST:PORT  uses a server that is already running

Connects two python-can socketcand buses to channel vcan0, sends standard and extended frames of
every length from one and checks that the other receives exactly those frames, in order, with
wall-clock timestamps; then a burst in the other direction. Exits 0 on success, 1 with a message
on the first failure. Every wait is bounded.
"""

import logging
import os
import select
import signal
import subprocess
import sys
import time

import can

OVERALL_LIMIT_S = 90
BRIDGE_START_LIMIT_S = 20
RECV_LIMIT_S = 5.0
CHANNEL = "vcan0"


class Failure(Exception):
    pass


def check(condition, message):
    if not condition:
        raise Failure(message)


def quiet_cut_reads():
    """python-can 4.1 warns each time a TCP read ends inside a message, which bursts always do."""
    logging.getLogger("can.interfaces.socketcand.socketcand").addFilter(
        lambda record: "incomplete message" not in record.getMessage()
    )


def start_bridge(axon):
    """Starts the bridge on an ephemeral port; returns (process, host, port)."""
    check(os.access(axon, os.X_OK), f"{axon} is not an executable")
    proc = subprocess.Popen(
        [axon, "can", "bridge", "--listen", "127.0.0.1:0"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    deadline = time.monotonic() + BRIDGE_START_LIMIT_S
    seen = b""
    while True:
        remaining = deadline - time.monotonic()
        if remaining <= 0:
            stop_bridge(proc)
            raise Failure(
                f"the bridge printed no 'listening socketcand HOST:PORT' line within "
                f"{BRIDGE_START_LIMIT_S} s; stdout so far: {seen!r}"
            )
        ready, _, _ = select.select([proc.stdout], [], [], remaining)
        if not ready:
            continue
        line = proc.stdout.readline()
        if not line:
            err = proc.stderr.read().decode(errors="replace") if proc.poll() is not None else ""
            stop_bridge(proc)
            raise Failure(f"the bridge exited (status {proc.returncode}) before listening: {err.strip()}")
        seen += line
        words = line.decode(errors="replace").split()
        if len(words) == 3 and words[0] == "listening" and words[1] == "socketcand":
            host, _, port = words[2].rpartition(":")
            check(host and port.isdigit() and int(port) > 0, f"bad address in bridge output: {line!r}")
            return proc, host.strip("[]"), int(port)


def stop_bridge(proc):
    if proc is None or proc.poll() is not None:
        return
    proc.terminate()
    try:
        proc.wait(timeout=5)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(timeout=5)


def frames_to_send():
    """Standard and extended frames of every length 0..8.

    python-can 4.1 writes ids without zero padding, so the server can only tell an extended id
    from a standard one when it is above 0x7FF: all extended ids here are.
    """
    out = []
    for n in range(9):
        data = bytes((0x11 * (i + 1) + n) & 0xFF for i in range(n))
        out.append(can.Message(arbitration_id=0x100 + n, is_extended_id=False, data=data))
        out.append(can.Message(arbitration_id=0x7FF - n, is_extended_id=False, data=data[::-1]))
        out.append(can.Message(arbitration_id=0x1ABCDE00 + n, is_extended_id=True, data=data))
        out.append(can.Message(arbitration_id=0x800 + n, is_extended_id=True, data=bytes(n)))
    out.append(can.Message(arbitration_id=0x000, is_extended_id=False, data=b"\x00"))
    out.append(can.Message(arbitration_id=0x1FFFFFFF, is_extended_id=True, data=b"\xff" * 8))
    return out


def describe(msg):
    kind = "ext" if msg.is_extended_id else "std"
    return f"{kind} 0x{msg.arbitration_id:X} [{msg.dlc}] {bytes(msg.data).hex()}"


def expect_frames(receiver, sent, label):
    # python-can 4.1 marks every received frame as extended; later versions use the id's digit count.
    check_format = tuple(int(x) for x in can.__version__.split(".")[:2]) >= (4, 2)
    now = time.time()
    for i, want in enumerate(sent):
        got = receiver.recv(timeout=RECV_LIMIT_S)
        check(got is not None, f"{label}: frame {i} ({describe(want)}) not received within {RECV_LIMIT_S} s")
        check(
            got.arbitration_id == want.arbitration_id and bytes(got.data) == bytes(want.data) and got.dlc == want.dlc,
            f"{label}: frame {i}: expected {describe(want)}, got {describe(got)}",
        )
        if check_format:
            check(got.is_extended_id == want.is_extended_id, f"{label}: frame {i}: id format differs: {describe(got)}")
        check(
            abs(got.timestamp - now) < 120,
            f"{label}: frame {i}: timestamp {got.timestamp} is not wall-clock time (now {now})",
        )
    extra = receiver.recv(timeout=0.2)
    if extra is not None:
        raise Failure(f"{label}: unexpected extra frame {describe(extra)}")


def exchange(host, port):
    a = b = None
    try:
        a = can.Bus(interface="socketcand", host=host, port=port, channel=CHANNEL)
        b = can.Bus(interface="socketcand", host=host, port=port, channel=CHANNEL)

        sent = frames_to_send()
        for msg in sent:
            a.send(msg)
        expect_frames(b, sent, "a -> b")

        # A burst the other way: many messages per TCP read, reads cut in the middle of messages.
        burst = [
            can.Message(arbitration_id=0x12345 + (i % 3), is_extended_id=True, data=i.to_bytes(2, "big") * 4)
            for i in range(300)
        ]
        for msg in burst:
            b.send(msg)
        expect_frames(a, burst, "b -> a burst")
        print(f"ok: {len(sent)} frames a -> b and {len(burst)} frames b -> a, exact and in order")
    finally:
        for bus in (a, b):
            if bus is not None:
                bus.shutdown()


def on_alarm(signum, frame):
    raise Failure(f"the whole run took longer than {OVERALL_LIMIT_S} s")


def main(argv):
    signal.signal(signal.SIGALRM, on_alarm)
    signal.alarm(OVERALL_LIMIT_S)  # a hard bound on the whole run
    quiet_cut_reads()
    if len(argv) == 3 and argv[1] == "--connect":
        host, _, port = argv[2].rpartition(":")
        exchange(host, int(port))
        return 0
    if len(argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    proc = None
    try:
        proc, host, port = start_bridge(argv[1])
        exchange(host, port)
    finally:
        stop_bridge(proc)
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main(sys.argv))
    except Failure as e:
        print(f"FAIL: {e}", file=sys.stderr)
        sys.exit(1)
    except Exception as e:  # python-can errors, connection refused, ...
        print(f"FAIL: {type(e).__name__}: {e}", file=sys.stderr)
        sys.exit(1)
