#!/usr/bin/env python3
"""A host that moves a subset of the plane the way the host software in service does, over the
CAN@net ASCII protocol, against `axon sim fps` (or real gateways).

usage: field_host_subset_move.py MOVER DELTA_DEG HOST:PORT [HOST:PORT ...]

Every gateway is set up (each of channels 1..4 that has a bus), every robot found with a GET_ID broadcast (0.5 s window,
as in service). Robot MOVER gets a one-point trajectory (alpha + DELTA_DEG in 1 s), then
START_TRAJECTORY is broadcast on every bus and, like the field software, the host waits for every
robot's COMMAND_ACCEPTED: any other answer (or none) fails the move (exit 1, robots stopped).
Afterwards MOVER must be at its target and every other robot where it was (exit 1 otherwise).
Prints one line per step on stdout."""
import socket
import struct
import sys
import time

STEPS_PER_DEG = 2**30 / 360.0
GET_ID, START, STOP = 1, 14, 15
NEW_TRAJ, TRAJ_DATA, TRAJ_END, GET_POS = 10, 11, 12, 32


def ident(pid, cmd, uid, code=0):
    return (pid << 18) | (cmd << 10) | (uid << 4) | code


def split(identifier):
    return identifier >> 18, (identifier >> 10) & 0xFF, (identifier >> 4) & 0x3F, identifier & 0xF


class Gateway:
    def __init__(self, endpoint):
        host, port = endpoint.rsplit(":", 1)
        self.name = endpoint
        self.sock = socket.create_connection((host, int(port)), timeout=5)
        self.buf = b""
        self.pending = []  # frame lines read while waiting for a command's reply

    def line(self, timeout):
        self.sock.settimeout(max(timeout, 0.001))
        while b"\n" not in self.buf:
            try:
                data = self.sock.recv(65536)
            except socket.timeout:
                return None
            if not data:
                raise SystemExit(f"FAIL: gateway {self.name} closed the connection")
            self.buf += data
        text, self.buf = self.buf.split(b"\n", 1)
        return text.decode().strip()

    def command(self, text):
        self.sock.sendall((text + "\n").encode())
        while True:
            reply = self.line(2.0)
            if reply is None:
                raise SystemExit(f"FAIL: {self.name}: no reply to '{text}'")
            if reply.startswith("R "):
                return reply
            self.pending.append(reply)

    def send(self, bus, identifier, payload=b""):
        data = " ".join(f"{b:02X}" for b in payload)
        self.sock.sendall(f"M {bus} CED {identifier:08X} {data}".rstrip().encode() + b"\n")

    def frames(self, window):
        """Every frame that arrives within `window` seconds: (bus, identifier, payload)."""
        end = time.monotonic() + window
        out = []
        while (left := end - time.monotonic()) > 0:
            text = self.pending.pop(0) if self.pending else self.line(left)
            if text is None:
                break
            parts = text.split()
            if len(parts) >= 4 and parts[0] == "M":
                out.append((int(parts[1]), int(parts[3], 16), bytes(int(b, 16) for b in parts[4:])))
        return out


def ask(gw, bus, pid, cmd, uid, payload=b""):
    gw.send(bus, ident(pid, cmd, uid), payload)
    end = time.monotonic() + 2.0
    while time.monotonic() < end:
        for b, i, data in gw.frames(0.05):
            p, c, u, code = split(i)
            if (b, p, c, u) == (bus, pid, cmd, uid):
                return code, data
    raise SystemExit(f"FAIL: robot {pid} did not answer command {cmd}")


def position(gw, bus, pid):
    code, data = ask(gw, bus, pid, GET_POS, 3)
    alpha, beta = struct.unpack("<ii", data)
    return alpha / STEPS_PER_DEG, beta / STEPS_PER_DEG


def main():
    mover, delta, endpoints = int(sys.argv[1]), float(sys.argv[2]), sys.argv[3:]
    gateways = [Gateway(e) for e in endpoints]
    robots = {}  # id -> (gateway, bus)
    for gw in gateways:
        gw.buses = []
        for bus in range(1, 5):
            if gw.command(f"CAN {bus} STOP") != "R ok":
                continue  # a channel without a bus behind it
            for cmd in ("INIT STD 1000", "FILTER CLEAR", "FILTER ADD EXT 00000000 00000000", "START"):
                reply = gw.command(f"CAN {bus} {cmd}")
                if reply != "R ok":
                    raise SystemExit(f"FAIL: {gw.name}: CAN {bus} {cmd}: {reply}")
            gw.buses.append(bus)
            gw.send(bus, ident(0, GET_ID, 0))
        for bus, i, _ in gw.frames(0.5):
            pid, cmd, _, code = split(i)
            if cmd == GET_ID and code == 0:
                robots[pid] = (gw, bus)
    print("found robots", ",".join(str(r) for r in sorted(robots)), "on", len(gateways), "gateways")
    if mover not in robots:
        raise SystemExit(f"FAIL: robot {mover} not found")
    before = {pid: position(gw, bus, pid) for pid, (gw, bus) in robots.items()}
    gw, bus = robots[mover]
    target = before[mover][0] + delta
    point = struct.pack("<iI", round(target * STEPS_PER_DEG), 2000)  # 1 s in 0.5 ms units
    for cmd, uid, payload in ((NEW_TRAJ, 1, struct.pack("<II", 1, 0)), (TRAJ_DATA, 2, point), (TRAJ_END, 3, b"")):
        code, _ = ask(gw, bus, mover, cmd, uid, payload)
        if code != 0:
            raise SystemExit(f"FAIL: robot {mover} refused command {cmd} with code {code}")
    print("loaded robot", mover)
    for g in gateways:
        for b in g.buses:
            g.send(b, ident(0, START, 0))
    codes = {}
    for g in gateways:
        for _, i, _ in g.frames(0.5):
            pid, cmd, _, code = split(i)
            if cmd == START:
                codes[pid] = code
    refused = {pid: codes.get(pid) for pid in robots if codes.get(pid) != 0}
    if refused:
        for g in gateways:
            for b in g.buses:
                g.send(b, ident(0, STOP, 0))
        detail = ", ".join(f"{pid}: {'no answer' if c is None else f'code {c}'}" for pid, c in sorted(refused.items()))
        print(f"FAIL: START_TRAJECTORY not accepted by every robot ({detail}); robots stopped")
        return 1
    print("started: every robot accepted START_TRAJECTORY")
    time.sleep(1.5)
    bad = []
    for pid, (g, b) in robots.items():
        alpha, beta = position(g, b, pid)
        want = (target, before[pid][1]) if pid == mover else before[pid]
        if abs(alpha - want[0]) > 0.1 or abs(beta - want[1]) > 0.1:
            bad.append(f"robot {pid} at {alpha:.3f}/{beta:.3f}, expected {want[0]:.3f}/{want[1]:.3f}")
    if bad:
        print("FAIL: " + "; ".join(bad))
        return 1
    print(f"done: robot {mover} at alpha {target:.3f}, the others where they were")
    return 0


if __name__ == "__main__":
    sys.exit(main())
