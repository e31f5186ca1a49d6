"""`axon c4g serve` in its own process against a scripted controller written here in Python (no
axon code on the controller side): the echo app in mode 0', NUM + 1 numbering, the capture file
(read back with tcpdump when installed and with `axon c4g init-info --from-pcap`), a CSV moni view,
and a clean stop on SIGINT with the timing report."""
import os
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import time

AXON = sys.argv[1]
tmp = tempfile.mkdtemp()
procs = []


def fail(msg):
    for p in procs:
        p.kill()
    print("FAIL:", msg, file=sys.stderr)
    for name in os.listdir(tmp):
        if name.endswith((".out", ".err")):
            print("---", name, file=sys.stderr)
            print(open(os.path.join(tmp, name)).read(), file=sys.stderr)
    sys.exit(1)


def wait_line(path, prefix, seconds=20):
    end = time.time() + seconds
    while time.time() < end:
        if os.path.exists(path):
            for line in open(path):
                if line.startswith(prefix):
                    return line.strip()
        time.sleep(0.05)
    fail(f"no line starting {prefix!r} in {path}")


def init_packet(axes=6, number=10):
    """The 300 fields in struct order: ints 0..96 (counts, modes, field types, period, open-axis
    lists) and 177..179 (versions); floats elsewhere (calibration 97.., limits 137.., influence
    180.., ratios 220.., following errors 260..)."""
    f = [0] * 300
    f[0], f[1], f[2], f[3] = number, 3, 9, axes
    f[44:47] = [1, 2, 3]
    f[47:56] = [1, 2, 2, 2, 2, 2, 3, 3, 3]
    f[56] = 2
    for i in range(axes):
        f[57 + i] = i + 1
        f[220 + i] = 100.0
    ints = set(range(0, 97)) | {177, 178, 179}
    out = b"".join(struct.pack("<i", v) if i in ints else struct.pack("<f", float(v)) for i, v in enumerate(f))
    assert len(out) == 1200
    return out


def cyclic(num, mode, axes=6, d1=0.0, d2=0.0):
    out = struct.pack("<iii", num, 5, 0)
    for i in range(axes):
        out += struct.pack("<i8f", mode, d1 + i, d2 - i, 7.0, 0, 0, 0, 0, 0)
    return out


def decode(data):
    num, infpar, cmd = struct.unpack_from("<iii", data)
    axes = []
    for i in range((len(data) - 12) // 36):
        axes.append(struct.unpack_from("<i8f", data, 12 + 36 * i))
    return num, infpar, cmd, axes


pcap = os.path.join(tmp, "run.pcap")
csv = os.path.join(tmp, "moni.csv")
out = open(os.path.join(tmp, "serve.out"), "w")
err = open(os.path.join(tmp, "serve.err"), "w")
serve = subprocess.Popen([AXON, "c4g", "serve", "--listen", "127.0.0.1:0", "--app", "echo", "--numbering", "next",
                          "--pcap", pcap, "--csv", csv, "--moni", "19", "--status-interval", "0.2"],
                         stdout=out, stderr=err)
procs.append(serve)
port = int(wait_line(os.path.join(tmp, "serve.out"), "listening c4g ").rsplit(":", 1)[1])

sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
sock.settimeout(2.0)
server = ("127.0.0.1", port)

# Plain packets before the initialization packet are answered too.
sock.sendto(cyclic(3, 0), server)
num, _, _, axes = decode(sock.recv(2048))
if num != 4 or len(axes) != 6:
    fail(f"sync packet answered with num {num}, {len(axes)} axes")
sock.sendto(init_packet(), server)
num, _, _, axes = decode(sock.recv(2048))
if num != 11 or len(axes) != 6:
    fail(f"init packet answered with num {num}, {len(axes)} axes")
for k in range(200):
    sock.sendto(cyclic(100 + k, 10, d1=0.5 * k, d2=0.25), server)
    num, _, _, axes = decode(sock.recv(2048))
    if num != 101 + k:
        fail(f"reply number {num} for {100 + k} (next numbering)")
    for i, a in enumerate(axes):
        if a[0] != 10 or abs(a[1] - (0.5 * k + i)) > 1e-6 or abs(a[2] - (0.25 - i)) > 1e-6 or a[3] != 0:
            fail(f"mode 0' not echoed on axis {i}: {a}")
# Mode 0: nothing to do, zeros.
sock.sendto(cyclic(400, 0, d1=3), server)
_, _, _, axes = decode(sock.recv(2048))
if axes[0][1] != 0:
    fail("mode 0 reply not zero")
time.sleep(0.5)
wait_line(os.path.join(tmp, "serve.out"), "status echo cycles ")
serve.send_signal(signal.SIGINT)
try:
    rc = serve.wait(20)
except subprocess.TimeoutExpired:
    fail("serve did not stop on SIGINT")
out.close()
text = open(os.path.join(tmp, "serve.out")).read()
if rc != 0:
    fail(f"serve exit code {rc}")
for needle in ["stopped: signal", "Worst cycle time", "p99.9", "echo: 200 cycles echoed in mode 0'",
               "axis 1: mode 10 -> 0 (mode0)", "initialization packet: 6 open axes, period 2 ms"]:
    if needle not in text:
        fail(f"missing {needle!r} in the output")

rows = open(csv).read().splitlines()
if not rows[0].startswith("cycle,time_s,a1_pc_d1,a1_pc_d2,a1_pc_d3,a1_pc_d4,a1_pc_d5,a1_mode,a2_pc_d1"):
    fail(f"moni 19 header: {rows[0]}")
if len(rows) != 1 + 202:  # the sync packet and the 201 cycles after the initialization packet
    fail(f"{len(rows) - 1} CSV rows")
last_echo = rows[201].split(",")
if float(last_echo[2]) != 0.5 * 199 or last_echo[7] != "10":
    fail(f"moni row {rows[201]}")

info = subprocess.run([AXON, "c4g", "init-info", "--from-pcap", pcap], capture_output=True, text=True)
if info.returncode != 0 or "open axis 6 = arm 1 axis 6" not in info.stdout:
    fail(f"init-info --from-pcap: {info.returncode} {info.stdout} {info.stderr}")
if shutil.which("tcpdump"):
    dump = subprocess.run(["tcpdump", "-nn", "-r", pcap], capture_output=True, text=True)
    lines = [l for l in dump.stdout.splitlines() if "UDP" in l]
    # 203 requests and 203 answers.
    if dump.returncode != 0 or len(lines) != 406 or "length 1200" not in dump.stdout:
        fail(f"tcpdump: rc {dump.returncode}, {len(lines)} UDP lines")
print("ok")
