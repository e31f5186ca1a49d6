#!/usr/bin/env python3
"""What the fps actor costs on top of the broker (issue 18), measured in one run on one machine.

A private rabbitmq-server on loopback (tests/integration/amqp_support.py), three responders on it
and one python3-pika commander that sends a command and waits for its final reply, one at a time:

  echo    a plain AMQP echo in its own process (python3-pika): it answers every command at once with
          a final reply carrying the command's body. The baseline: the broker's two hops and the
          client, nothing else.
  ping    `axon actor fps` answering ping: the actor's own path (the JSON body parsed, the command
          line split, the command run on its thread, the reply's headers and keywords).
  status  the same actor answering status for the default layout's 500 simulated robots: every
          robot read over CAN@net on loopback, and a reply of about 70 kB of keywords.

The three alternate round by round, so the machine's load falls on all of them alike. Then the
status rate while a move runs: all 500 robots turn their alpha arms 60 degrees (beta folded, so
no arm can touch another) and the commander keeps `--window` status commands in flight until the
move ends; status then answers from the last read (`stale`), which is what an operator's screen
polls during a move.

usage: /usr/bin/python3 bench/actor_roundtrip.py [BUILD_DIR] [--rounds N] [--window W]
Ends with one line: BENCH actor_roundtrip ... status_ratio=... ping_ratio=... ratio=...
"""
import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), '..'))
sys.path.insert(0, os.path.join(ROOT, 'tests', 'integration'))

ECHO = r'''
import sys, pika
port, exchange = int(sys.argv[1]), sys.argv[2]
conn = pika.BlockingConnection(pika.ConnectionParameters('127.0.0.1', port))
ch = conn.channel()
ch.exchange_declare(exchange, exchange_type='topic', auto_delete=True)
q = ch.queue_declare('echo_commands', exclusive=True).method.queue
ch.queue_bind(q, exchange, routing_key='command.echo.#')

def answer(ch, method, props, body):
    h = props.headers or {}
    headers = {'message_code': ':', 'commander_id': h.get('commander_id'), 'command_id': h.get('command_id'),
               'sender': 'echo', 'internal': False}
    ch.basic_publish(exchange, 'reply.%s' % h.get('commander_id'), body,
                     pika.BasicProperties(headers=headers, correlation_id=props.correlation_id, content_type='text/json'))

ch.basic_consume(q, answer, auto_ack=True)
print('ready', flush=True)
ch.start_consuming()
'''


def parse():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument('build', nargs='?', default=os.path.join(ROOT, 'build', 'release'))
    p.add_argument('--rounds', type=int, default=200, help='round trips of each kind (default 200)')
    p.add_argument('--window', type=int, default=4, help='status commands in flight during the move (default 4)')
    return p.parse_args()


def percentile(values, q):
    s = sorted(values)
    return s[min(len(s) - 1, int(round(q * (len(s) - 1))))]


def round_trip_ms(c, text):
    t0 = time.perf_counter()
    r = c.command(text, timeout=60)
    assert r[-1][0] == ':', r[-1]
    return (time.perf_counter() - t0) * 1e3


def round_trips(echo, actor, rounds):
    times = {'echo': [], 'ping': [], 'status': []}
    for kind in times:  # one unmeasured of each: connections and caches warm
        round_trip_ms(echo if kind == 'echo' else actor, 'ping' if kind != 'status' else 'status')
    for _ in range(rounds):
        times['echo'].append(round_trip_ms(echo, 'ping'))
        times['ping'].append(round_trip_ms(actor, 'ping'))
        times['status'].append(round_trip_ms(actor, 'status'))
    return times


def status_rate_during_move(c, window):
    """Status commands answered per second (and their bytes) while a move of every robot runs."""
    status = c.command('status', timeout=60)[-1][1]
    alpha = [r['alpha'] for r in status['robots'] if r['alpha'] is not None]
    target = 60.0 if statistics.median(alpha) < 180 else -60.0
    target += statistics.median(alpha)
    move = c.send('goto all %.1f 180' % target)
    assert c.pump(lambda: any('move_started' in kw for _, kw in c.replies[move]), 30), c.replies[move]
    t0, answered, stale, in_flight, sizes = time.perf_counter(), 0, 0, [], []
    while not c.done(move):
        while len(in_flight) < window:
            in_flight.append(c.send('status'))
        c.pump(lambda: c.done(move) or any(c.done(i) for i in in_flight), 10)
        for i in [i for i in in_flight if c.done(i)]:
            in_flight.remove(i)
            code, kw = c.replies[i][-1]
            assert code == ':', kw
            answered += 1
            stale += kw['stale']
            sizes.append(len(json.dumps(kw)))
    elapsed = time.perf_counter() - t0
    assert c.replies[move][-1][0] == ':', c.replies[move][-1]
    for i in in_flight:
        c.wait(i, 60)
    return answered / elapsed, elapsed, answered, stale, statistics.median(sizes) if sizes else 0


def main():
    a = parse()
    import amqp_support
    from amqp_support import Broker, Commander, broker_missing
    if broker_missing():
        print('actor_roundtrip: ' + broker_missing(), file=sys.stderr)
        return 1
    tmp = tempfile.mkdtemp(prefix='axon-bench-actor-')
    broker, procs = Broker(tmp), []
    try:
        assert broker.start() is not None, 'rabbitmq-server cannot start here (%s/server.out)' % tmp
        port, exchange = broker.port, amqp_support.EXCHANGE
        echo = subprocess.Popen([sys.executable, '-c', ECHO, str(port), exchange], stdout=subprocess.PIPE, text=True)
        procs.append(echo)
        assert echo.stdout.readline().strip() == 'ready'
        log = open(os.path.join(tmp, 'actor.log'), 'w')
        procs.append(subprocess.Popen([os.path.join(a.build, 'axon'), 'actor', 'fps', '--broker', '127.0.0.1:%d' % port,
                                       '--exchange', exchange, '--layout', 'default', '--time-scale', '1',
                                       '--status-period', '0'], stdout=log, stderr=log))
        actor = amqp_support.wait_for_actor(port, 120, 'fps', None)
        echo_client = Commander(port, 'echo', None)
        times = round_trips(echo_client, actor, a.rounds)
        for kind, t in times.items():
            print('%-6s round trip over the broker: median %.2f ms, p99 %.2f ms (%d)' % (kind, statistics.median(t),
                                                                                          percentile(t, 0.99), len(t)))
        rate, seconds, answered, stale, size = status_rate_during_move(actor, a.window)
        print('status during a move of 500 robots: %.0f answered per s over %.1f s (%d, %d from the last read), '
              'about %d kB each' % (rate, seconds, answered, stale, size / 1000))
        med = {k: statistics.median(t) for k, t in times.items()}
        p99 = {k: percentile(t, 0.99) for k, t in times.items()}
        status_ratio, ping_ratio = med['status'] / med['echo'], med['ping'] / med['echo']
        print('BENCH actor_roundtrip echo_ms=%.2f echo_p99_ms=%.2f ping_ms=%.2f ping_p99_ms=%.2f status_ms=%.2f '
              'status_p99_ms=%.2f status_per_s_moving=%.0f ping_ratio=%.2f status_ratio=%.2f ratio=%.2f'
              % (med['echo'], p99['echo'], med['ping'], p99['ping'], med['status'], p99['status'], rate, ping_ratio,
                 status_ratio, status_ratio))
        return 0
    finally:
        for p in procs:
            p.terminate()
            try:
                p.wait(timeout=30)
            except subprocess.TimeoutExpired:
                p.kill()
        broker.stop()
        broker.stop_epmd()
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == '__main__':
    sys.exit(main())
