#!/usr/bin/python3
"""python-can (Debian's python3-can) drives `axon sim blmc` over socketcand with its own decoder.

Usage: python_can_blmc.py AXON_BINARY

The decoder below is written from the board specification alone (each 4-byte half of a message is
a big-endian two's-complement Q24 number; commands carry the value in bytes 0..3 and the command
code in bytes 4..7), not from axon's codec. It checks: the 1 Hz status byte; after ENABLE_SYS and
SEND_ALL the four data messages arrive in the order current, position, velocity, ADC with the
simulator's default ADC level 0.5; after ENABLE_MTR1 the motor aligns (status 0x03) then is ready
(0x07); a current reference of 0.3 A on motor 1 is measured back as 0.3 A and spins motor 1 forward
while motor 2 stays still. Exits 0 on success, 1 with a message on the first failure.
"""

import logging
import os
import select
import subprocess
import sys
import time

import can

START_LIMIT_S = 20
Q24 = float(1 << 24)

ID_COMMAND, ID_IQREF, ID_STATUS = 0x000, 0x005, 0x010
ID_CURRENT, ID_POSITION, ID_VELOCITY, ID_ADC = 0x020, 0x030, 0x040, 0x050
ENABLE_SYS, ENABLE_MTR1, SEND_ALL = 0x01, 0x02, 0x14


class Failure(Exception):
    pass


def check(condition, message):
    if not condition:
        raise Failure(message)


def q24_half(data, offset):
    return int.from_bytes(data[offset:offset + 4], "big", signed=True) / Q24


def pair(msg):
    check(len(msg.data) == 8, f"id {msg.arbitration_id:03X} carries {len(msg.data)} bytes, expected 8")
    return q24_half(msg.data, 0), q24_half(msg.data, 4)


def command(code, value=1):
    data = int(value).to_bytes(4, "big", signed=True) + int(code).to_bytes(4, "big")
    return can.Message(arbitration_id=ID_COMMAND, is_extended_id=False, data=data)


def iq_ref(amps1, amps2):
    data = round(amps1 * Q24).to_bytes(4, "big", signed=True) + round(amps2 * Q24).to_bytes(4, "big", signed=True)
    return can.Message(arbitration_id=ID_IQREF, is_extended_id=False, data=data)


def start_sim(axon):
    check(os.access(axon, os.X_OK), f"{axon} is not an executable")
    proc = subprocess.Popen([axon, "sim", "blmc", "--boards", "1", "--socketcand", "127.0.0.1:0"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    deadline = time.monotonic() + START_LIMIT_S
    while time.monotonic() < deadline:
        ready, _, _ = select.select([proc.stdout], [], [], 0.5)
        if not ready:
            continue
        words = proc.stdout.readline().decode(errors="replace").split()
        if not words and proc.poll() is not None:
            break
        if len(words) == 3 and words[:2] == ["listening", "socketcand"]:
            host, _, port = words[2].rpartition(":")
            return proc, host, int(port)
    stop(proc)
    raise Failure("`axon sim blmc` printed no 'listening socketcand HOST:PORT' line")


def stop(proc):
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            proc.kill()


def wait_for(bus, predicate, limit_s, what):
    deadline = time.monotonic() + limit_s
    while time.monotonic() < deadline:
        msg = bus.recv(timeout=max(0.0, deadline - time.monotonic()))
        if msg is not None and predicate(msg):
            return msg
    raise Failure(f"no {what} within {limit_s} s")


def run(axon):
    proc, host, port = start_sim(axon)
    bus = None
    try:
        bus = can.Bus(interface="socketcand", host=host, port=port, channel="can0")
        status = wait_for(bus, lambda m: m.arbitration_id == ID_STATUS, 3, "status frame")
        check(len(status.data) == 1 and status.data[0] == 0x00, f"status at power-up: {bytes(status.data).hex()}")

        bus.send(command(ENABLE_SYS))
        bus.send(command(SEND_ALL))
        order = []
        first = wait_for(bus, lambda m: m.arbitration_id == ID_CURRENT, 3, "current frame")
        order.append(first.arbitration_id)
        while len(order) < 8:
            msg = wait_for(bus, lambda m: ID_CURRENT <= m.arbitration_id <= ID_ADC, 2, "data frame")
            order.append(msg.arbitration_id)
            if msg.arbitration_id == ID_ADC:
                a, b = pair(msg)
                check(abs(a - 0.5) < 1e-6 and abs(b - 0.5) < 1e-6, f"ADC readings {a}, {b}, expected 0.5")
        check(order == [ID_CURRENT, ID_POSITION, ID_VELOCITY, ID_ADC] * 2,
              f"data order {[hex(i) for i in order]}")

        bus.send(command(ENABLE_MTR1))
        wait_for(bus, lambda m: m.arbitration_id == ID_STATUS and m.data[0] == 0x03, 3, "status 0x03 (aligning)")
        wait_for(bus, lambda m: m.arbitration_id == ID_STATUS and m.data[0] == 0x07, 8, "status 0x07 (ready)")

        start = pair(wait_for(bus, lambda m: m.arbitration_id == ID_POSITION, 1, "position frame"))
        measured = None
        velocity = None
        until = time.monotonic() + 0.5
        while time.monotonic() < until:
            bus.send(iq_ref(0.3, 0.0))
            msg = bus.recv(timeout=0.005)
            if msg is None:
                continue
            if msg.arbitration_id == ID_CURRENT:
                measured = pair(msg)
            elif msg.arbitration_id == ID_VELOCITY:
                velocity = pair(msg)
        bus.send(iq_ref(0.0, 0.0))
        end = pair(wait_for(bus, lambda m: m.arbitration_id == ID_POSITION, 1, "position frame"))
        check(measured is not None and abs(measured[0] - 0.3) < 1e-3 and measured[1] == 0.0,
              f"measured currents {measured}, expected (0.3, 0)")
        check(velocity is not None and velocity[0] > 0 and velocity[1] == 0.0, f"velocities {velocity} (krpm)")
        check(end[0] > start[0] and end[1] == start[1], f"positions went from {start} to {end} (rev)")
        print(f"PASS: current {measured[0]:.4f} A, velocity {velocity[0]:.3f} krpm, "
              f"motor 1 moved {end[0] - start[0]:.3f} rev")
    finally:
        if bus is not None:
            bus.shutdown()
        stop(proc)


def main():
    logging.getLogger("can.interfaces.socketcand.socketcand").addFilter(
        lambda record: "incomplete message" not in record.getMessage())
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    try:
        run(sys.argv[1])
    except Failure as e:
        print(f"FAIL: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
