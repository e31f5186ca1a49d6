"""`axon actor blmc|c4g --http 127.0.0.1:0` on one private RabbitMQ broker: the actor prints
`listening http HOST:PORT` on stderr, /api/state and /metrics answer (the metrics pass
`promtool check metrics` when promtool is installed), a command over the bus shows on the page
(blmc: a current command in the board's traces; c4g: the app started by command), and the actor
still ends cleanly on SIGINT. Skipped without pika/jsonschema or a broker."""
import json
import re
import shutil
import subprocess
import sys
import time
import urllib.request

from amqp_support import Actor, run_with_broker

AXON = sys.argv[1]


def listening(run, timeout=30):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        run.log.seek(0)
        m = re.search(r'listening http (\S+)', run.log.read())
        if m:
            return m.group(1)
        time.sleep(0.1)
    raise AssertionError('no listening http line')


def get(address, path):
    with urllib.request.urlopen('http://%s%s' % (address, path), timeout=10) as r:
        return r.read().decode()


def check_metrics(address):
    text = get(address, '/metrics')
    assert text.strip(), 'empty /metrics'
    if shutil.which('promtool'):
        p = subprocess.run(['promtool', 'check', 'metrics'], input=text, capture_output=True, text=True)
        assert p.returncode == 0, p.stdout + p.stderr
    return len(text)


def state(address, family):
    return json.loads(get(address, '/api/state'))[family]


def blmc(run):
    actor = Actor(AXON, 'blmc')
    run.start_actor(actor.args('blmc', run.broker.port, '--http', '127.0.0.1:0'))
    address = listening(run)
    c = actor.wait(run.broker.port)
    print('blmc metrics: %d bytes' % check_metrics(address))
    c.expect_done('enable')
    c.expect_done('start')
    c.expect_done('currents 0.5 0')
    end = time.monotonic() + 10
    while time.monotonic() < end:
        i1 = state(address, 'blmc')['boards'][0]['samples']['i1']
        if i1 and abs(i1[-1] - 0.5) < 0.2:
            break
        time.sleep(0.2)
    else:
        raise AssertionError('the page did not show the current: %s' % i1[-5:])
    c.close()
    code, log = run.stop_actor()
    assert code == 0 and 'motors disabled' in log, log


def c4g(run):
    actor = Actor(AXON, 'c4g')
    run.start_actor(actor.args('c4g', run.broker.port, '--listen', '127.0.0.1:0', '--lenient-timing', '--http', '127.0.0.1:0'))
    address = listening(run)
    c = actor.wait(run.broker.port)
    print('c4g metrics: %d bytes' % check_metrics(address))
    c.expect_done('start echo')
    end = time.monotonic() + 10
    while time.monotonic() < end:
        app = state(address, 'c4g')['app']
        if 'echo' in json.dumps(app):
            break
        time.sleep(0.2)
    else:
        raise AssertionError('the page did not show the app: %s' % app)
    c.close()
    code, log = run.stop_actor()
    assert code == 0, log


def main(run):
    blmc(run)
    run.log.seek(0)
    run.log.truncate()
    c4g(run)
    print('OK')
    return 0


if __name__ == '__main__':
    sys.exit(run_with_broker('axon-actor-http-', main))
