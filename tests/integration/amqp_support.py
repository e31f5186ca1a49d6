"""What the actor tests over a real broker share (not a test: the glob of tests/integration skips
files named *_support.py): a private rabbitmq-server on loopback (own node name, ports, data
directory and epmd, schedulers that sleep), and a commander written from the SDSS actor convention
(docs/actor.md) with Debian's python3-pika, not from axon's code. Every reply a commander takes is
checked against the actor's JSON schema (docs/schema/<actor>.json)."""
import json
import os
import shutil
import signal
import socket
import subprocess
import tempfile
import time
import uuid

try:
    import jsonschema  # noqa: F401 (validator() uses it)
    import pika
    MISSING_LIBRARIES = None
except ImportError as e:  # run_with_broker() says so and skips
    pika = None
    MISSING_LIBRARIES = 'python3-pika and python3-jsonschema are needed (%s)' % e

SOURCE = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
RABBITMQ_SERVER = '/usr/lib/rabbitmq/bin/rabbitmq-server'
EXCHANGE = 'axon_test_exchange'
FINAL = {':', 'f', '!'}


def validator(actor):
    """The JSON-schema validator of an actor's keywords (docs/schema/<actor>.json)."""
    import jsonschema
    with open(os.path.join(SOURCE, 'docs', 'schema', '%s.json' % actor)) as f:
        return jsonschema.Draft7Validator(json.load(f))


def broker_missing():
    """Why no broker can run here, or None."""
    import shutil
    if not os.path.exists(RABBITMQ_SERVER) or shutil.which('epmd') is None:
        return 'rabbitmq-server is not installed (scripts/install-deps.sh installs it)'
    return None


def free_port():
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


class Broker:
    """A private rabbitmq-server on loopback, or on `host` inside the network namespace `netns`."""

    def __init__(self, tmp, host='127.0.0.1', netns=None):
        self.tmp, self.host = tmp, host
        self.prefix = ['ip', 'netns', 'exec', netns] if netns else []
        self.port, self.dist_port, self.epmd_port = free_port(), free_port(), free_port()
        with open(os.path.join(tmp, 'enabled_plugins'), 'w') as f:
            f.write('[].\n')
        # The broker lets the user `guest` in from loopback only; on another address (a network
        # namespace's) the test's clients come from other hosts.
        with open(os.path.join(tmp, 'rabbitmq.conf'), 'w') as f:
            f.write('' if host.startswith('127.') else 'loopback_users.guest = false\n')
        self.env = dict(os.environ, HOME=tmp, RABBITMQ_NODENAME='axon%d@localhost' % os.getpid(),
                        RABBITMQ_NODE_IP_ADDRESS=host, RABBITMQ_NODE_PORT=str(self.port),
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
        self.proc = subprocess.Popen(self.prefix + [RABBITMQ_SERVER], env=self.env, stdout=out, stderr=subprocess.STDOUT,
                                     start_new_session=True, cwd=self.tmp)
        while time.monotonic() - t0 < limit_s:
            if self.proc.poll() is not None:
                return None
            try:
                pika.BlockingConnection(pika.ConnectionParameters(self.host, self.port, connection_attempts=1,
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
        subprocess.run(self.prefix + ['epmd', '-port', str(self.epmd_port), '-kill'], env=self.env, capture_output=True, timeout=10)


class Commander:
    """A client of the convention: commands to command.<actor>, replies on reply.<commander_id>,
    broadcasts on reply.broadcast."""

    def __init__(self, port, actor, validator, exchange=EXCHANGE, host='127.0.0.1'):
        """validator: the actor's schema validator (validator(actor)), or None to take replies unchecked."""
        self.actor, self.validator, self.exchange = actor, validator, exchange
        self.commander = 'pytest.%s' % uuid.uuid4().hex[:8]
        self.conn = pika.BlockingConnection(pika.ConnectionParameters(host, port))
        self.ch = self.conn.channel()
        self.ch.exchange_declare(self.exchange, exchange_type='topic', auto_delete=True)
        self.queue = self.ch.queue_declare('', exclusive=True).method.queue
        for key in ('reply.%s' % self.commander, 'reply.broadcast'):
            self.ch.queue_bind(self.queue, self.exchange, routing_key=key)
        self.replies = {}    # command id -> [(code, keywords)]
        self.broadcasts = []  # (code, keywords)
        self.others = []      # (sender, code, keywords): broadcasts of the other actors on the exchange
        self.checked = 0
        self.ch.basic_consume(self.queue, lambda ch, method, props, body: self.take(props, body, method.routing_key),
                              auto_ack=True)

    def send(self, text=None, body=None):
        command_id = uuid.uuid4().hex
        body = json.dumps({'command_string': text}).encode() if body is None else body
        props = pika.BasicProperties(headers={'commander_id': self.commander, 'command_id': command_id},
                                     correlation_id=command_id, content_type='text/json', reply_to=self.queue)
        self.ch.basic_publish(self.exchange, 'command.%s' % self.actor, body, props)
        self.replies[command_id] = []
        return command_id

    def take(self, props, body, key):
        h = props.headers or {}
        code = h.get('message_code')
        assert code in ('>', ':', 'f', 'e', '!', 'i', 'w', 'd'), h
        assert props.content_type == 'text/json', props.content_type
        keywords = json.loads(body)
        if key == 'reply.broadcast' and h.get('sender') != self.actor:
            self.others.append((h.get('sender'), code, keywords))  # another actor on the exchange
            return
        assert h.get('sender') == self.actor, h
        errors = sorted(self.validator.iter_errors(keywords), key=str) if self.validator else []
        assert not errors, 'reply not valid against docs/schema/%s.json: %s\n%s' % (self.actor, errors[0].message, body[:500])
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

    def expect_done(self, text, timeout=30):
        """The command's keywords; asserts that it ended in ':'."""
        r = self.command(text, timeout=timeout)
        assert r[-1][0] == ':', (text, r)
        return r[-1][1]

    def expect_failed(self, text=None, body=None):
        """The reason of a command that must fail ('f' with an error)."""
        r = self.command(text, body=body)
        assert r[-1][0] == 'f' and r[-1][1]['error'], (text, body, r)
        return r[-1][1]['error']

    def close(self):
        try:
            self.conn.close()
        except pika.exceptions.AMQPError:
            pass


def wait_for_actor(port, timeout, actor, validator, exchange=EXCHANGE, host='127.0.0.1'):
    """Pings until the actor answers (its queue may not exist yet, or the broker just came back)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        try:
            c = Commander(port, actor, validator, exchange, host)
        except pika.exceptions.AMQPError:
            time.sleep(0.2)
            continue
        cid = c.send('ping')
        if c.pump(lambda: c.done(cid), 1.0):
            return c
        c.close()
    raise AssertionError('the actor did not answer ping within %d s' % timeout)


def tell(axon, port, actor, *words, json_out=False, timeout_s=20, exchange=EXCHANGE, host='127.0.0.1', netns=None):
    args = (['ip', 'netns', 'exec', netns] if netns else []) + [axon, 'tell', '--broker', '%s:%d' % (host, port), '--exchange', exchange, '--timeout', str(timeout_s)]
    args += ['--json'] if json_out else []
    return subprocess.run(args + [actor] + list(words), capture_output=True, text=True, timeout=60)


class Actor:
    """One actor under test: its name (its queue, its replies' sender) and its schema, for the calls
    that talk to it."""

    def __init__(self, axon, name, schema=None):
        self.axon, self.name = axon, name
        self.validator = validator(schema or name)

    def args(self, family, port, *more):
        """The `axon actor FAMILY` command line on the private broker's port."""
        return [self.axon, 'actor', family, '--broker', '127.0.0.1:%d' % port, '--exchange', EXCHANGE,
                '--name', self.name] + list(more)

    def wait(self, port, timeout=30, host='127.0.0.1'):
        """A commander, once the actor answers ping."""
        return wait_for_actor(port, timeout, self.name, self.validator, host=host)

    def commander(self, port):
        return Commander(port, self.name, self.validator)

    def tell(self, port, *words, json_out=False, timeout_s=20, actor=None):
        """`axon tell` (to this actor unless `actor` says another) as a finished process."""
        return tell(self.axon, port, actor or self.name, *words, json_out=json_out, timeout_s=timeout_s)


def restart_broker(broker, actor, pause_s):
    """The broker goes away for `pause_s` and comes back; returns (a commander once the actor
    answers again, seconds from the stop to that answer)."""
    broker.stop()
    t0 = time.monotonic()
    time.sleep(pause_s)
    up = broker.start()
    assert up is not None, 'the broker did not start again'
    print('broker restarted in %.1f s' % up)
    c = actor.wait(broker.port, 30)
    return c, time.monotonic() - t0


def run_with_broker(prefix, body):
    """The frame of every actor test: skip (exit 0, saying why) without the libraries or a broker
    that can start; else body(run) with run.broker up, in an ActorRun that always cleans up.
    Returns the exit code."""
    why = MISSING_LIBRARIES or broker_missing()
    if why:
        print('SKIP: ' + why)
        return 0
    with ActorRun(prefix) as run:
        up = run.broker.start()
        if up is None:
            print('SKIP: rabbitmq-server cannot start here (see %s/server.out)' % run.tmp)
            return 0
        print('broker up in %.1f s' % up)
        return body(run)


class ActorRun:
    """One actor test's processes: a private broker (`broker`) and one `axon actor` process on it.
    As a context manager it always cleans up: the actor killed if it still runs, the broker and its
    epmd stopped, the temporary folder removed; on an exception it first prints the end of the
    actor's log and of the broker's output."""

    def __init__(self, prefix):
        self.tmp = tempfile.mkdtemp(prefix=prefix)
        self.broker = Broker(self.tmp)
        self.actor = None
        self.log = open(os.path.join(self.tmp, 'actor.log'), 'w+')  # a file: a pipe nobody reads would block it

    def start_actor(self, args):
        """Starts `axon actor ...` (stdout a pipe, stderr the log) and returns its process."""
        self.actor = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=self.log, text=True)
        return self.actor

    def stop_actor(self, timeout=30):
        """SIGINT, the way a user ends it; returns (exit code, everything it logged)."""
        self.actor.send_signal(signal.SIGINT)
        self.actor.communicate(timeout=timeout)
        self.log.seek(0)
        return self.actor.returncode, self.log.read()

    def __enter__(self):
        return self

    def __exit__(self, kind, value, traceback):
        try:
            if kind is not None:
                self._report()
        finally:
            if self.actor is not None and self.actor.poll() is None:
                self.actor.kill()
                self.actor.wait()
            self.broker.stop()
            self.broker.stop_epmd()
            self.log.close()
            shutil.rmtree(self.tmp, ignore_errors=True)
        return False

    def _report(self):
        if self.actor is not None:
            if self.actor.poll() is None:
                self.actor.kill()
            self.actor.communicate()
            self.log.seek(0)
            print('actor stderr (end):\n' + ''.join(self.log.readlines()[-30:]))
        out = os.path.join(self.tmp, 'server.out')
        if os.path.exists(out):
            with open(out) as f:
                print('broker output (end):\n' + ''.join(f.readlines()[-20:]))
