"""`axon actor fps` on a real RabbitMQ broker, driven by an independent AMQP client written here
from the SDSS actor convention (docs/actor.md) with Debian's python3-pika, not from axon's code:
status, goto (replies ending in ':'), a body that is not JSON and an unknown command (each 'f' with
a reason), a second move refused while one runs, a flood (garbage, oversized bodies, status requests
by the hundred), a collision alert every listener sees, `axon tell`
(human and --json), the broker stopped and started again with the actor rejoining by itself.
Every reply is checked against docs/schema/fps.json with python3-jsonschema. The broker is a
private rabbitmq-server (own node name, ports, data directory, epmd) started once and stopped at the
end, also on failure; the test is skipped only when no broker can start at all."""
import json
import statistics
import sys
import tempfile
import time

from amqp_support import Actor, free_port, restart_broker, run_with_broker

AXON = sys.argv[1]


def check_commands(c, actor, port, actor_proc):
    status = c.command('status')
    assert status[-1][0] == ':', status
    robots = status[-1][1]['robots']
    assert len(robots) == 6 and status[-1][1]['ready'] == 6, status[-1][1]
    ids = [r['id'] for r in robots]

    move = c.command('goto %d 30 170' % ids[0])
    assert move[0] == ('>', {}), move[0]  # the convention: '>' first, then the command's keywords
    assert move[1][0] == '>' and 'move_started' in move[1][1], move[1]
    assert move[-1][0] == ':', move[-1]
    reached = move[-1][1]['move_result']['robots'][0]
    assert abs(reached['alpha'] - 30) < 0.2 and abs(reached['beta'] - 170) < 0.2, reached

    for body, reason in ((b'status, please', 'not JSON'), (b'{"command": "status"}', 'command_string')):
        r = c.command(body=body)
        assert r[-1][0] == 'f' and reason in r[-1][1]['error'], r
    r = c.command('get_schema')  # clu's built-in: the keyword schema as JSON text, the one shipped in docs/
    assert r[-1][0] == ':' and json.loads(r[-1][1]['schema']) == actor.validator.schema, r[-1][1].keys()
    r = c.command('fly 3')
    assert r[-1][0] == 'f' and 'unknown command' in r[-1][1]['error'], r
    r = c.command('goto %d ninety 170' % ids[0])
    assert r[-1][0] == 'f' and r[-1][1]['error'], r

    # A long move, then a second one while it runs: refused at once with a reason, not queued.
    first = c.send('goto all 300 150')
    assert c.pump(lambda: any('move_started' in kw for _, kw in c.replies[first]), 10), c.replies[first]
    second = c.command('goto %d 10 170' % ids[1])
    assert second[-1][0] == 'f' and 'is running' in second[-1][1]['error'], second
    during = c.command('status')
    assert during[-1][0] == ':' and during[-1][1]['moving'] is True, during[-1][1]
    assert c.wait(first)[-1][0] == ':', c.replies[first][-1]
    assert any('move_progress' in kw for code, kw in c.replies[first] if code == '>'), c.replies[first]

    # stop: idle it only aborts; during a move it cuts the move, which fails, and locks until unlock.
    r = c.command('stop')
    assert r[-1][0] == ':' and r[-1][1]['stopped']['while_moving'] is False, r
    moving = c.send('goto %d 30 170' % ids[0])
    assert c.pump(lambda: any('move_started' in kw for _, kw in c.replies[moving]), 10), c.replies[moving]
    r = c.command('abort')
    assert r[-1][0] == ':' and r[-1][1]['stopped']['while_moving'] is True, r
    assert c.wait(moving)[-1][0] == 'f', c.replies[moving][-1]
    assert c.command('unlock')[-1][0] == ':'

    # axon tell: human and --json, exit status from the final code.
    p = actor.tell(port, 'status')
    assert p.returncode == 0 and 'fps :' in p.stdout and 'robots=' in p.stdout, (p.returncode, p.stdout, p.stderr)
    p = actor.tell(port, 'goto', str(ids[2]), '45', '160', json_out=True)
    lines = [json.loads(l) for l in p.stdout.splitlines()]
    assert p.returncode == 0 and lines[-1]['message_code'] == ':', (p.returncode, p.stdout, p.stderr)
    for l in lines:
        assert not list(actor.validator.iter_errors(l['keywords'])), l
    p = actor.tell(port, 'fly')
    assert p.returncode == 1 and 'unknown command' in p.stdout, (p.returncode, p.stdout, p.stderr)
    p = actor.tell(port, 'goto', str(ids[2]), '-45', '160')  # everything after the actor is the command
    assert p.returncode == 1 and 'fps f' in p.stdout, (p.returncode, p.stdout, p.stderr)
    p = actor.tell(port, 'status', actor='nobody')
    assert p.returncode == 1 and 'no actor "nobody"' in p.stdout, (p.returncode, p.stdout, p.stderr)

    # A collision: the alert reaches every listener (this client is one), moves are refused until unlock.
    c.broadcasts.clear()
    t0 = time.perf_counter()
    r = c.command('sim-collision %d' % ids[3])
    assert r[-1][0] == ':', r
    assert c.pump(lambda: any('collision_alert' in kw for _, kw in c.broadcasts), 5), c.broadcasts
    print('collision alert seen %.0f ms after the sim-collision command was sent' % ((time.perf_counter() - t0) * 1e3))
    assert c.command('goto %d 20 170' % ids[0])[-1][0] == 'f'
    r = c.command('unlock')
    assert r[-1][0] == ':' and r[-1][1]['locked'] is False, r
    r = c.command('backoff %d' % ids[3])  # the document's move away after a collision
    assert r[-1][0] == ':' and r[-1][1]['back_off']['ok'] is True, r
    assert r[-1][1]['back_off']['moves'][0]['moved'] is True, r
    # Planned, collision-free moves (the robots not named fold), and discovery again.
    r = c.command('plan %d 40 160' % ids[1])
    assert r[-1][0] == ':' and r[-1][1]['plan_result']['verified'] is True, r
    r = c.command('discover')
    assert r[-1][0] == ':' and len(r[-1][1]['robots']) == len(ids), r
    r = c.command('check')
    assert r[-1][0] == ':' and r[-1][1]['layout_check']['ok'] is True, r
    r = c.command('cold')  # the embedded plane's PLC emulator
    assert r[-1][0] == ':' and sorted(r[-1][1]['cold']['applied']) == sorted(ids), r
    # Troubleshooting (interface document 9.4.3): the hall test of a healthy robot, one arm.
    r = c.command('halltest %d beta' % ids[2])
    assert r[-1][0] == ':' and r[-1][1]['hall_test']['ok'] is True, r
    assert [a['arm'] for a in r[-1][1]['hall_test']['arms']] == ['beta'], r
    assert c.command('halltest %d gamma' % ids[2])[-1][0] == 'f'
    # Firmware of every robot through the embedded plane's PLC, with progress keywords on the way.
    with tempfile.NamedTemporaryFile(suffix='.bin') as image:
        image.write(b'AXON-FPS-FW:04.02.00' + bytes(3000))
        image.flush()
        r = c.command('upgrade %s 04.02.00' % image.name, timeout=60)
    assert r[-1][0] == ':' and r[-1][1]['upgrade_result']['ok'] is True, r
    assert {x['after'] for x in r[-1][1]['upgrade_result']['robots']} == {'04.02.00'}, r
    assert any('upgrade_progress' in kw and kw['upgrade_progress']['finished'] for code, kw in r if code == '>'), r
    # The PLC of the embedded plane: relays and sensors, a sextant's power off and on, the sync line.
    r = c.command('plc')
    assert r[-1][0] == ':' and r[-1][1]['plc']['positioner_power'][0] is True, r
    r = c.command('power 1 off')
    assert r[-1][0] == ':' and r[-1][1]['relay'] == {'name': 'positioner power 1', 'on': False}, r
    r = c.command('power 1 on')
    assert r[-1][0] == ':' and r[-1][1]['relay']['on'] is True, r
    r = c.command('sync pulse 0.1')
    assert r[-1][0] == ':' and r[-1][1]['relay'] == {'name': 'sync line', 'on': False}, r
    assert c.command('power 9 on')[-1][0] == 'f'
    assert any('robots' in kw for _, kw in c.broadcasts), 'no periodic status broadcast'


def resident_kb(pid):
    with open('/proc/%d/status' % pid) as f:
        for line in f:
            if line.startswith('VmRSS:'):
                return int(line.split()[1])
    return 0


def check_flood(c, actor_proc):
    """A commander floods the actor: garbage, bodies too large to be a command, many status requests
    at once. Every message gets one final reply, the actor stays up and small, the refusals are
    counted in status and logged on the first and every 100th only."""
    rss_before = resident_kb(actor_proc.pid)
    t0 = time.perf_counter()
    garbage = [c.send(body=b'garbage' if i % 2 else json.dumps({'command_string': 'fly %d' % i}).encode())
               for i in range(3000)]
    big = [c.send(body=b'{' + b' ' * (100 * 1024) + b'"command_string": "status"}') for _ in range(100)]
    statuses = [c.send('status') for _ in range(300)]
    everything = garbage + big + statuses
    assert c.pump(lambda: all(c.done(i) for i in everything), 120), \
        '%d of %d without a final reply' % (sum(not c.done(i) for i in everything), len(everything))
    elapsed = time.perf_counter() - t0
    for i in garbage:
        assert c.replies[i][-1][0] == 'f', c.replies[i]
    for i in big:
        assert c.replies[i][-1][0] == 'f' and 'a command may have' in c.replies[i][-1][1]['error'], c.replies[i]
    busy = 0
    for i in statuses:
        code, kw = c.replies[i][-1]
        assert code == ':' or (code == 'f' and kw['error'].startswith('busy:')), c.replies[i]
        busy += code == 'f'
    r = c.command('status')
    assert r[-1][0] == ':', r
    counts = r[-1][1]['commands']
    assert counts['not_json'] >= 1500 and counts['unknown'] >= 1500 and counts['oversized'] == 100, counts
    assert counts['busy'] == busy, (counts, busy)
    rss_after = resident_kb(actor_proc.pid)
    print('flood: %d messages answered in %.1f s (%.0f per s); %d status answered busy; actor RSS %d -> %d kB'
          % (len(everything), elapsed, len(everything) / elapsed, busy, rss_before, rss_after))
    assert actor_proc.poll() is None, 'the actor ended under the flood'


def round_trip_ms(c, text, n=100):
    times = []
    for _ in range(n):
        t0 = time.perf_counter()
        r = c.command(text)
        times.append((time.perf_counter() - t0) * 1e3)
        assert r[-1][0] == ':', r
    return statistics.median(times)


def main(run):
    t0 = time.monotonic()
    broker, actor = run.broker, Actor(AXON, 'fps')
    p = actor.tell(free_port(), 'ping', timeout_s=1)  # no broker there: an error, exit 1
    assert p.returncode == 1 and 'cannot reach the broker' in p.stderr, (p.returncode, p.stdout, p.stderr)
    proc = run.start_actor(actor.args('fps', broker.port, '--status-period', '1', '--time-scale', '20'))
    c = actor.wait(broker.port)
    check_commands(c, actor, broker.port, proc)
    check_flood(c, proc)
    ping_ms, status_ms = round_trip_ms(c, 'ping'), round_trip_ms(c, 'status')
    print('round trip over the broker, median of 100: ping %.2f ms, status %.2f ms' % (ping_ms, status_ms))
    checked = c.checked
    c.close()

    # The broker goes away and comes back: the same actor process answers again.
    c, _ = restart_broker(broker, actor, 0.5)
    assert proc.poll() is None, 'the actor ended when the broker went away'
    r = c.command('status')
    assert r[-1][0] == ':' and len(r[-1][1]['robots']) == 6, r
    checked += c.checked
    c.close()

    rc, err = run.stop_actor()
    assert rc == 0, (rc, err[-2000:])
    assert 'refused' in err, err[-2000:]
    warnings = sum('command refused' in line for line in err.splitlines())
    assert warnings <= 40, '%d refusals logged (the first and every 100th expected)' % warnings
    print('ok: %d replies valid against docs/schema/fps.json, %.1f s in all' % (checked, time.monotonic() - t0))
    return 0


if __name__ == '__main__':
    sys.exit(run_with_broker('axon-actor-', main))
