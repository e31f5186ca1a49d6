"""Several machines behind one broker (issue 18, item 5), on this machine: the broker and the three
actors (`axon actor fps`, `blmc`, `c4g`, each with its own embedded simulators) each in a network
namespace of its own, joined by a bridge as hosts on one subnet are joined by a switch; a fifth
namespace plays the operators' machine. From there `axon tell` commands all three actors; two
listeners (one in the operators' namespace, one outside every namespace) each see the collision
alert that follows a collision on the fps actor. Every reply is checked against the actor's schema
(docs/schema/<actor>.json). Where namespaces cannot be made (not root, no `ip`), the same runs on
separate loopback addresses, and says so. Skipped only when no broker can start at all."""
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

AXON = sys.argv[1]
HERE = os.path.dirname(os.path.abspath(__file__))

import amqp_support
from amqp_support import EXCHANGE, Broker, broker_missing, validator

ACTORS = ('fps', 'blmc', 'c4g')
# Each actor's own options: the c4g simulator's reply window is the lenient one (a loaded machine
# runs three simulators and a broker here), its server on any free port.
EXTRA = {'fps': [], 'blmc': [], 'c4g': ['--listen', '127.0.0.1:0', '--lenient-timing']}
ROLES = ('broker',) + ACTORS + ('ops',)

# Runs in the operators' namespace: binds to the broadcasts, says so, and waits for the alert.
LISTENER = r'''
import sys
sys.path.insert(0, sys.argv[3])
from amqp_support import Commander, validator
c = Commander(int(sys.argv[2]), 'fps', validator('fps'), host=sys.argv[1])
print('listening', flush=True)
ok = c.pump(lambda: any('collision_alert' in kw for _, kw in c.broadcasts), 60)
print('alert' if ok else 'no alert', flush=True)
sys.exit(0 if ok else 1)
'''


def sh(*args):
    subprocess.run(list(args), check=True, capture_output=True, timeout=30)


class Network:
    """One namespace per role on a bridge, 10.213.S.1 the bridge and 10.213.S.(k+2) role k; or, where
    namespaces cannot be made, one loopback address per role (127.0.S.(k+2)) in this namespace."""

    def __init__(self):
        self.tag = os.getpid() % 10000
        self.subnet = self.tag % 250
        self.bridge = 'axb%d' % self.tag
        self.namespaces = []
        self.isolated = False

    def up(self):
        try:
            sh('ip', 'link', 'add', self.bridge, 'type', 'bridge')
        except (OSError, subprocess.CalledProcessError) as e:
            print('network namespaces cannot be made here (%s): separate loopback addresses instead' %
                  (getattr(e, 'stderr', b'') or str(e).encode()).decode().strip())
            return
        self.isolated = True
        sh('ip', 'addr', 'add', '10.213.%d.1/24' % self.subnet, 'dev', self.bridge)
        sh('ip', 'link', 'set', self.bridge, 'up')
        for k, role in enumerate(ROLES):
            ns, veth, peer = 'axon%d-%s' % (self.tag, role), 'axv%d%d' % (self.tag, k), 'axp%d%d' % (self.tag, k)
            sh('ip', 'netns', 'add', ns)
            self.namespaces.append(ns)
            sh('ip', 'link', 'add', veth, 'type', 'veth', 'peer', 'name', peer)
            sh('ip', 'link', 'set', peer, 'netns', ns)
            sh('ip', 'link', 'set', veth, 'master', self.bridge, 'up')
            sh('ip', 'netns', 'exec', ns, 'ip', 'addr', 'add', '%s/24' % self.address(role), 'dev', peer)
            sh('ip', 'netns', 'exec', ns, 'ip', 'link', 'set', peer, 'up')
            sh('ip', 'netns', 'exec', ns, 'ip', 'link', 'set', 'lo', 'up')

    def address(self, role):
        k = ROLES.index(role) + 2
        return '10.213.%d.%d' % (self.subnet, k) if self.isolated else '127.0.%d.%d' % (self.subnet, k)

    def netns(self, role):
        return 'axon%d-%s' % (self.tag, role) if self.isolated else None

    def prefix(self, role):
        return ['ip', 'netns', 'exec', self.netns(role)] if self.isolated else []

    def down(self):
        for ns in self.namespaces:
            subprocess.run(['ip', 'netns', 'del', ns], capture_output=True, timeout=30)
        if self.isolated:
            subprocess.run(['ip', 'link', 'del', self.bridge], capture_output=True, timeout=30)


def check_tells(net, port, robots):
    """`axon tell` from the operators' namespace to each actor: status answered, exit 0."""
    for actor in ACTORS:
        p = amqp_support.tell(AXON, port, actor, 'status', json_out=True, host=net.address('broker'),
                              netns=net.netns('ops'), timeout_s=30)
        assert p.returncode == 0, (actor, p.returncode, p.stdout[-2000:], p.stderr[-2000:])
        last = json.loads(p.stdout.splitlines()[-1])
        assert last['sender'] == actor and last['message_code'] == ':', last
        assert not list(validator(actor).iter_errors(last['keywords'])), last
        print('tell %s status from the operators\' namespace: %s' % (actor, ', '.join(sorted(last['keywords']))[:120]))
    t0 = time.monotonic()
    p = amqp_support.tell(AXON, port, 'fps', 'sim-collision', str(robots[0]), host=net.address('broker'),
                          netns=net.netns('ops'))
    assert p.returncode == 0, (p.returncode, p.stdout, p.stderr)
    return t0


def run(net, tmp, procs):
    broker = Broker(tmp, host=net.address('broker'), netns=net.netns('broker'))
    procs.append(broker)
    up = broker.start()
    if up is None:
        print('SKIP: rabbitmq-server cannot start here (see %s/server.out)' % tmp)
        return 0
    print('broker up in %.1f s on %s:%d%s' % (up, net.address('broker'), broker.port,
                                             ' in namespace %s' % net.netns('broker') if net.isolated else ''))
    logs = {}
    for actor in ACTORS:
        logs[actor] = open(os.path.join(tmp, '%s.log' % actor), 'w+')
        procs.append(subprocess.Popen(net.prefix(actor) + [AXON, 'actor', actor, '--broker', '%s:%d' % (
            net.address('broker'), broker.port), '--exchange', EXCHANGE, '--name', actor, '--status-period', '0'] + EXTRA[actor],
            stdout=logs[actor], stderr=logs[actor]))
    host = net.address('broker')
    commanders = {a: amqp_support.wait_for_actor(broker.port, 60, a, validator(a), host=host) for a in ACTORS}
    status = commanders['fps'].command('status')
    assert status[-1][0] == ':', status
    robots = [r['id'] for r in status[-1][1]['robots']]
    for actor in ACTORS[1:]:
        r = commanders[actor].command('status')
        assert r[-1][0] == ':', (actor, r)
    listener = subprocess.Popen(net.prefix('ops') + [sys.executable, '-c', LISTENER, host, str(broker.port), HERE],
                                stdout=subprocess.PIPE, text=True)
    procs.append(listener)
    assert listener.stdout.readline().strip() == 'listening'
    fps = commanders['fps']
    fps.broadcasts.clear()
    t0 = check_tells(net, broker.port, robots)
    assert fps.pump(lambda: any('collision_alert' in kw for _, kw in fps.broadcasts), 30), fps.broadcasts
    alert_ms = (time.monotonic() - t0) * 1e3
    seen = listener.stdout.readline().split()
    assert listener.wait(timeout=60) == 0 and seen[0] == 'alert', seen
    print('collision alert seen by the listener outside the namespaces %.0f ms after `axon tell fps sim-collision` '
          'started (a process start included), and by the one in the operators\' namespace' % alert_ms)
    for c in commanders.values():
        c.close()
    for p in procs[1:1 + len(ACTORS)]:
        p.send_signal(signal.SIGINT)
    for actor, p in zip(ACTORS, procs[1:1 + len(ACTORS)]):
        p.wait(timeout=60)
        logs[actor].seek(0)
        assert p.returncode == 0, (actor, p.returncode, logs[actor].read()[-2000:])
    print('ok: three actors in %s behind one broker' % ('their own namespaces' if net.isolated else
                                                       'one namespace on separate addresses'))
    return 0


def main():
    why = amqp_support.MISSING_LIBRARIES or broker_missing()
    if why:
        print('SKIP: ' + why)
        return 0
    tmp = tempfile.mkdtemp(prefix='axon-netns-')
    net, procs = Network(), []
    try:
        net.up()
        return run(net, tmp, procs)
    except BaseException:
        for name in ACTORS:
            path = os.path.join(tmp, '%s.log' % name)
            if os.path.exists(path):
                with open(path) as f:
                    print('%s actor log (end):\n%s' % (name, ''.join(f.readlines()[-15:])))
        if os.path.exists(os.path.join(tmp, 'server.out')):
            with open(os.path.join(tmp, 'server.out')) as f:
                print('broker output (end):\n' + ''.join(f.readlines()[-15:]))
        raise
    finally:
        for p in procs[1:]:
            if p.poll() is None:
                p.kill()
                p.wait()
        if procs:
            procs[0].stop()
            procs[0].stop_epmd()
        net.down()
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == '__main__':
    sys.exit(main())
