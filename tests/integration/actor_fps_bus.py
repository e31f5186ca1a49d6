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
import os
import shutil
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import time
import uuid

AXON = sys.argv[1]
SOURCE = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
RABBITMQ_SERVER = '/usr/lib/rabbitmq/bin/rabbitmq-server'
EXCHANGE = 'axon_test_exchange'
ACTOR = 'fps'
FINAL = {':', 'f', '!'}

try:
    import jsonschema
    import pika
except ImportError as e:
    print('SKIP: python3-pika and python3-jsonschema are needed (%s)' % e)
    sys.exit(0)

with open(os.path.join(SOURCE, 'docs', 'schema', 'fps.json')) as f:
    SCHEMA = json.load(f)
VALIDATOR = jsonschema.Draft7Validator(SCHEMA)


def free_port():
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


class Broker:
    """A private rabbitmq-server on loopback."""

    def __init__(self, tmp):
        self.tmp = tmp
        self.port, self.dist_port, self.epmd_port = free_port(), free_port(), free_port()
        with open(os.path.join(tmp, 'enabled_plugins'), 'w') as f:
            f.write('[].\n')
        self.env = dict(os.environ, HOME=tmp, RABBITMQ_NODENAME='axon%d@localhost' % os.getpid(),
                        RABBITMQ_NODE_IP_ADDRESS='127.0.0.1', RABBITMQ_NODE_PORT=str(self.port),
                        RABBITMQ_DIST_PORT=str(self.dist_port), ERL_EPMD_PORT=str(self.epmd_port),
                        ERL_EPMD_ADDRESS='127.0.0.1',
                        RABBITMQ_MNESIA_BASE=os.path.join(tmp, 'mnesia'), RABBITMQ_LOG_BASE=os.path.join(tmp, 'log'),
                        RABBITMQ_ENABLED_PLUGINS_FILE=os.path.join(tmp, 'enabled_plugins'),
                        RABBITMQ_CONFIG_FILE=os.path.join(tmp, 'rabbitmq'),
                        RABBITMQ_PID_FILE=os.path.join(tmp, 'rabbitmq.pid'),
                        # Schedulers that sleep instead of spinning: the machine's other tests keep their CPU.
                        RABBITMQ_SERVER_ADDITIONAL_ERL_ARGS='+sbwt none +sbwtdcpu none +sbwtdio none')
        self.proc = None

    def start(self, limit_s=120):
        t0 = time.monotonic()
        out = open(os.path.join(self.tmp, 'server.out'), 'a')
        self.proc = subprocess.Popen([RABBITMQ_SERVER], env=self.env, stdout=out, stderr=subprocess.STDOUT,
                                     start_new_session=True, cwd=self.tmp)
        while time.monotonic() - t0 < limit_s:
            if self.proc.poll() is not None:
                return None
            try:
                pika.BlockingConnection(pika.ConnectionParameters('127.0.0.1', self.port, connection_attempts=1,
                                                                  socket_timeout=1)).close()
                return time.monotonic() - t0
            except pika.exceptions.AMQPError:
                time.sleep(0.2)
        raise AssertionError('the broker did not answer within %d s (log in %s)' % (limit_s, self.tmp))

    def stop(self):
        if self.proc is None or self.proc.poll() is not None:
            return
        os.killpg(self.proc.pid, signal.SIGTERM)
        try:
            self.proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            os.killpg(self.proc.pid, signal.SIGKILL)
            self.proc.wait()

    def stop_epmd(self):
        subprocess.run(['epmd', '-port', str(self.epmd_port), '-kill'], env=self.env, capture_output=True, timeout=10)


class Commander:
    """A client of the convention: commands to command.<actor>, replies on reply.<commander_id>,
    broadcasts on reply.broadcast."""

    def __init__(self, port):
        self.commander = 'pytest.%s' % uuid.uuid4().hex[:8]
        self.conn = pika.BlockingConnection(pika.ConnectionParameters('127.0.0.1', port))
        self.ch = self.conn.channel()
        self.ch.exchange_declare(EXCHANGE, exchange_type='topic', auto_delete=True)
        self.queue = self.ch.queue_declare('', exclusive=True).method.queue
        for key in ('reply.%s' % self.commander, 'reply.broadcast'):
            self.ch.queue_bind(self.queue, EXCHANGE, routing_key=key)
        self.replies = {}    # command id -> [(code, keywords)]
        self.broadcasts = []  # (code, keywords)
        self.checked = 0
        self.ch.basic_consume(self.queue, lambda ch, method, props, body: self.take(props, body, method.routing_key),
                              auto_ack=True)

    def send(self, text=None, body=None):
        command_id = uuid.uuid4().hex
        body = json.dumps({'command_string': text}).encode() if body is None else body
        props = pika.BasicProperties(headers={'commander_id': self.commander, 'command_id': command_id},
                                     correlation_id=command_id, content_type='text/json', reply_to=self.queue)
        self.ch.basic_publish(EXCHANGE, 'command.%s' % ACTOR, body, props)
        self.replies[command_id] = []
        return command_id

    def take(self, props, body, key):
        h = props.headers or {}
        code = h.get('message_code')
        assert code in ('>', ':', 'f', 'e', '!', 'i', 'w', 'd'), h
        assert h.get('sender') == ACTOR, h
        assert props.content_type == 'text/json', props.content_type
        keywords = json.loads(body)
        errors = sorted(VALIDATOR.iter_errors(keywords), key=str)
        assert not errors, 'reply not valid against docs/schema/fps.json: %s\n%s' % (errors[0].message, body[:500])
        self.checked += 1
        if key == 'reply.broadcast':
            self.broadcasts.append((code, keywords))
            return
        assert key == 'reply.%s' % self.commander, key
        assert props.correlation_id == h.get('command_id'), (props.correlation_id, h)
        self.replies.setdefault(h.get('command_id'), []).append((code, keywords))

    def pump(self, until, timeout):
        end = time.monotonic() + timeout
        while not until() and time.monotonic() < end:
            self.conn.process_data_events(time_limit=min(0.05, max(0.0, end - time.monotonic())))
        return until()

    def done(self, command_id):
        r = self.replies.get(command_id, [])
        return bool(r) and r[-1][0] in FINAL

    def wait(self, command_id, timeout=30):
        assert self.pump(lambda: self.done(command_id), timeout), ('no final reply', self.replies.get(command_id))
        return self.replies[command_id]

    def command(self, text=None, body=None, timeout=30):
        return self.wait(self.send(text, body), timeout)

    def close(self):
        try:
            self.conn.close()
        except pika.exceptions.AMQPError:
            pass


def wait_for_actor(port, timeout):
    """Pings until the actor answers (its queue may not exist yet, or the broker just came back)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        try:
            c = Commander(port)
        except pika.exceptions.AMQPError:
            time.sleep(0.2)
            continue
        cid = c.send('ping')
        if c.pump(lambda: c.done(cid), 1.0):
            return c
        c.close()
    raise AssertionError('the actor did not answer ping within %d s' % timeout)


def tell(port, *words, json_out=False, actor=ACTOR, timeout_s=20):
    args = [AXON, 'tell', '--broker', '127.0.0.1:%d' % port, '--exchange', EXCHANGE, '--timeout', str(timeout_s)]
    args += ['--json'] if json_out else []
    return subprocess.run(args + [actor] + list(words), capture_output=True, text=True, timeout=60)


def check_commands(c, port, actor_proc):
    status = c.command('status')
    assert status[-1][0] == ':', status
    robots = status[-1][1]['robots']
    assert len(robots) == 6 and status[-1][1]['ready'] == 6, status[-1][1]
    ids = [r['id'] for r in robots]

    move = c.command('goto %d 30 170' % ids[0])
    assert move[0][0] == '>' and 'move_started' in move[0][1], move[0]
    assert move[-1][0] == ':', move[-1]
    reached = move[-1][1]['move_result']['robots'][0]
    assert abs(reached['alpha'] - 30) < 0.2 and abs(reached['beta'] - 170) < 0.2, reached

    for body, reason in ((b'status, please', 'not JSON'), (b'{"command": "status"}', 'command_string')):
        r = c.command(body=body)
        assert r[-1][0] == 'f' and reason in r[-1][1]['error'], r
    r = c.command('fly 3')
    assert r[-1][0] == 'f' and 'unknown command' in r[-1][1]['error'], r
    r = c.command('goto %d ninety 170' % ids[0])
    assert r[-1][0] == 'f' and r[-1][1]['error'], r

    # A long move, then a second one while it runs: refused at once with a reason, not queued.
    first = c.send('goto all 300 150')
    assert c.pump(lambda: any(code == '>' for code, _ in c.replies[first]), 10), c.replies[first]
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
    assert c.pump(lambda: any(code == '>' for code, _ in c.replies[moving]), 10), c.replies[moving]
    r = c.command('abort')
    assert r[-1][0] == ':' and r[-1][1]['stopped']['while_moving'] is True, r
    assert c.wait(moving)[-1][0] == 'f', c.replies[moving][-1]
    assert c.command('unlock')[-1][0] == ':'

    # axon tell: human and --json, exit status from the final code.
    p = tell(port, 'status')
    assert p.returncode == 0 and 'fps :' in p.stdout and 'robots=' in p.stdout, (p.returncode, p.stdout, p.stderr)
    p = tell(port, 'goto', str(ids[2]), '45', '160', json_out=True)
    lines = [json.loads(l) for l in p.stdout.splitlines()]
    assert p.returncode == 0 and lines[-1]['message_code'] == ':', (p.returncode, p.stdout, p.stderr)
    for l in lines:
        assert not list(VALIDATOR.iter_errors(l['keywords'])), l
    p = tell(port, 'fly')
    assert p.returncode == 1 and 'unknown command' in p.stdout, (p.returncode, p.stdout, p.stderr)
    p = tell(port, 'goto', str(ids[2]), '-45', '160')  # everything after the actor is the command
    assert p.returncode == 1 and 'fps f' in p.stdout, (p.returncode, p.stdout, p.stderr)
    p = tell(port, 'status', actor='nobody')
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


def main():
    if not os.path.exists(RABBITMQ_SERVER) or shutil.which('epmd') is None:
        print('SKIP: rabbitmq-server is not installed (scripts/install-deps.sh installs it)')
        return 0
    tmp = tempfile.mkdtemp(prefix='axon-actor-')
    broker = Broker(tmp)
    actor = None
    actor_log = open(os.path.join(tmp, 'actor.log'), 'w+')  # a file: a pipe nobody reads would block it
    try:
        t0 = time.monotonic()
        up = broker.start()
        if up is None:
            print('SKIP: rabbitmq-server cannot start here (see %s/server.out)' % tmp)
            return 0
        print('broker up in %.1f s' % up)
        p = tell(free_port(), 'ping', timeout_s=1)  # no broker there: an error, exit 1
        assert p.returncode == 1 and 'cannot reach the broker' in p.stderr, (p.returncode, p.stdout, p.stderr)
        actor = subprocess.Popen([AXON, 'actor', 'fps', '--broker', '127.0.0.1:%d' % broker.port, '--exchange', EXCHANGE,
                                  '--name', ACTOR, '--status-period', '1', '--time-scale', '20'],
                                 stdout=subprocess.PIPE, stderr=actor_log, text=True)
        c = wait_for_actor(broker.port, 30)
        check_commands(c, broker.port, actor)
        check_flood(c, actor)
        ping_ms, status_ms = round_trip_ms(c, 'ping'), round_trip_ms(c, 'status')
        print('round trip over the broker, median of 100: ping %.2f ms, status %.2f ms' % (ping_ms, status_ms))
        checked = c.checked
        c.close()

        # The broker goes away and comes back: the same actor process answers again.
        broker.stop()
        time.sleep(0.5)
        assert actor.poll() is None, 'the actor ended when the broker went away'
        up = broker.start()
        assert up is not None, 'the broker did not start again'
        print('broker restarted in %.1f s' % up)
        c = wait_for_actor(broker.port, 30)
        r = c.command('status')
        assert r[-1][0] == ':' and len(r[-1][1]['robots']) == 6, r
        checked += c.checked
        c.close()

        actor.send_signal(signal.SIGINT)
        actor.communicate(timeout=30)
        actor_log.seek(0)
        err = actor_log.read()
        assert actor.returncode == 0, (actor.returncode, err[-2000:])
        assert 'refused' in err, err[-2000:]
        warnings = sum('command refused' in line for line in err.splitlines())
        assert warnings <= 40, '%d refusals logged (the first and every 100th expected)' % warnings
        print('ok: %d replies valid against docs/schema/fps.json, %.1f s in all' % (checked, time.monotonic() - t0))
        return 0
    except BaseException:
        if actor is not None and actor.poll() is None:
            actor.kill()
        if actor is not None:
            actor.communicate()
            actor_log.seek(0)
            print('actor stderr (end):\n' + ''.join(actor_log.readlines()[-20:]))
        with open(os.path.join(tmp, 'server.out')) as f:
            print('broker output (end):\n' + ''.join(f.readlines()[-20:]))
        raise
    finally:
        if actor is not None and actor.poll() is None:
            actor.kill()
            actor.wait()
        broker.stop()
        broker.stop_epmd()
        actor_log.close()
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == '__main__':
    sys.exit(main())
