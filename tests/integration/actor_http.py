"""`axon actor blmc|c4g|fps --http 127.0.0.1:0` on one private RabbitMQ broker: the actor prints
`listening http HOST:PORT` on stderr, /api/state and /metrics answer (the metrics pass
`promtool check metrics` when promtool is installed), a command over the bus shows on the page
(blmc: a current command in the board's traces; c4g: the app started by command; fps: every robot
ready, a goto's arms at their targets, a collision the lock naming the robot, and the page's reads
out of the way of a discovery), and the actor still ends cleanly on SIGINT. Skipped without
pika/jsonschema or a broker."""
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


def fps_robot(address, robot):
    return [r for r in state(address, 'fps')['robots'] if r['id'] == robot][0]


def wait_for(what, ok, seconds=15):
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        value = ok()
        if value:
            return value
        time.sleep(0.1)
    raise AssertionError('the page did not show %s' % what)


def fps(run):
    actor = Actor(AXON, 'fps')
    run.start_actor(actor.args('fps', run.broker.port, '--http', '127.0.0.1:0'))
    address = listening(run)
    c = actor.wait(run.broker.port)
    wait_for('six robots ready', lambda: state(address, 'fps').get('states', {}).get('ready') == 6)
    ids = [r['id'] for r in state(address, 'fps')['robots']]
    # A discovery is exclusive work: the page must not read beside it, and reads again after it.
    c.expect_done('discover')
    wait_for('fresh reads after the discovery', lambda: all(fps_robot(address, i)['ago'] is not None
                                                            and fps_robot(address, i)['ago'] < 1 for i in ids))
    c.expect_done('goto %d 30 170' % ids[0])
    wait_for('robot %d at 30 170' % ids[0],
             lambda: abs(fps_robot(address, ids[0])['a'] - 30) < 0.2 and abs(fps_robot(address, ids[0])['b'] - 170) < 0.2)
    c.expect_done('sim-collision %d' % ids[1])
    lock = wait_for('the lock', lambda: state(address, 'fps')['lock']['locked'] and state(address, 'fps')['lock'])
    assert lock['robot'] == ids[1], lock
    print('fps page: robot %d at its goto target, the lock names robot %d; metrics %d bytes'
          % (ids[0], lock['robot'], check_metrics(address)))
    c.close()
    code, log = run.stop_actor()
    assert code == 0, log


def main(run):
    blmc(run)
    run.log.seek(0)
    run.log.truncate()
    c4g(run)
    run.log.seek(0)
    run.log.truncate()
    fps(run)
    print('OK')
    return 0


if __name__ == '__main__':
    sys.exit(run_with_broker('axon-actor-http-', main))
