"""`axon sim c4g` against a minimal echo PC written here in Python (not axon's server): the default
scenario completes (exit 0, JSON summary), a PC that falls silent after the initialization packet
ends in ERR_C4GOPEN_UDP (exit 1), and a scenario file with an error is reported with its location."""
import json
import os
import socket
import struct
import subprocess
import sys
import tempfile
import threading

AXON = sys.argv[1]


def echo_pc(sock, stop, silent_after_init):
    sock.settimeout(0.1)
    silent = False
    while not stop.is_set():
        try:
            d, addr = sock.recvfrom(2048)
        except socket.timeout:
            continue
        num = struct.unpack_from('<i', d, 0)[0]
        if len(d) == 1200:
            n = struct.unpack_from('<i', d, 12)[0]
            modes = [0] * n
            silent = silent_after_init
        else:
            n = (len(d) - 12) // 36
            modes = [struct.unpack_from('<i', d, 12 + 36 * i)[0] for i in range(n)]
        out = struct.pack('<iii', num, 0, 0) + b''.join(struct.pack('<i', m) + b'\0' * 32 for m in modes)
        if not silent or len(d) == 1200:
            sock.sendto(out, addr)


def run(args, silent_after_init=False):
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(('127.0.0.1', 0))
    stop = threading.Event()
    t = threading.Thread(target=echo_pc, args=(sock, stop, silent_after_init))
    t.start()
    try:
        server = '127.0.0.1:%d' % sock.getsockname()[1]
        p = subprocess.run([AXON, 'sim', 'c4g', '--server', server, '--reply-deadline-us', '20000'] + args,
                           capture_output=True, text=True, timeout=60)
    finally:
        stop.set()
        t.join()
        sock.close()
    return p


p = run(['--duration', '4', '--json'])
assert p.returncode == 0, (p.returncode, p.stdout, p.stderr)
summary = json.loads(p.stdout)
assert summary['outcome'] == 'completed', summary['outcome']
assert summary['init_sent'] == 1 and summary['sync_sent'] == 3, summary
assert summary['rtt_us']['count'] > 100, summary['rtt_us']
assert any(e['name'] == 'DRIVES_ON' for e in summary['events']), summary['events']

p = run(['--duration', '10'], silent_after_init=True)
assert p.returncode == 4, (p.returncode, p.stdout, p.stderr)  # the controller's safety reaction (drives off)
assert 'ERR_C4GOPEN_UDP' in p.stderr, p.stderr
assert 'communication error' in p.stdout, p.stdout

with tempfile.NamedTemporaryFile('w', suffix='.yaml', delete=False) as f:
    f.write('steps:\n  - drive_on\n  - go_open: {type: A, mode: 3}\n')
try:
    p = run(['--scenario', f.name])
    assert p.returncode == 2, (p.returncode, p.stdout, p.stderr)  # a bad scenario file: usage error
    assert '%s:3:30' % f.name in p.stderr, p.stderr
finally:
    os.unlink(f.name)
print('ok')
