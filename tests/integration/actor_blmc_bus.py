"""`axon actor blmc` on a real RabbitMQ broker, driven by the independent python3-pika commander of
amqp_support.py (written from the SDSS actor convention, not from axon's code), with its simulated
board in the actor's process: status, a current refused while no loop runs, malformed and
non-JSON commands, enable, home, start (and a second start refused), currents, current, pd, stop, a board
fault whose safety stop a second listener hears with its text, errors and recover, `axon tell blmc`
(human and --json), then the broker stopped and started again while the loop runs: the actor has set
the idle action (zero current), says so in errors, and answers again. Every reply is checked
against docs/schema/blmc.json with python3-jsonschema. Skipped only when no broker can start."""
import json
import sys
import time

AXON = sys.argv[1]
ACTOR = 'blmc'

try:
    import jsonschema  # noqa: F401 (amqp_support needs them; a clear skip without)
    import pika  # noqa: F401
    from amqp_support import EXCHANGE, ActorRun, Commander, broker_missing, validator
    import amqp_support
except ImportError as e:
    print('SKIP: python3-pika and python3-jsonschema are needed (%s)' % e)
    sys.exit(0)

VALIDATOR = validator(ACTOR)


def wait_for_actor(port, timeout):
    return amqp_support.wait_for_actor(port, timeout, ACTOR, VALIDATOR)


def tell(port, *words, json_out=False):
    return amqp_support.tell(AXON, port, ACTOR, *words, json_out=json_out)


def done(c, text, timeout=30):
    r = c.command(text, timeout=timeout)
    assert r[-1][0] == ':', (text, r)
    return r[-1][1]


def failed(c, text=None, body=None):
    r = c.command(text, body=body)
    assert r[-1][0] == 'f' and r[-1][1]['error'], (text, body, r)
    return r[-1][1]['error']


def check_refusals(c):
    kw = done(c, 'status')
    assert len(kw['board']['motors']) == 2 and kw['loop']['running'] is False, kw
    assert kw['board_error'] == {'code': 0, 'name': 'NONE', 'meaning': 'no error'}, kw['board_error']
    assert 'no control loop runs' in failed(c, 'currents 0.1 0')
    assert 'not enabled' in failed(c, 'start')
    assert 'not JSON' in failed(c, body=b'currents, please')
    assert 'unknown command' in failed(c, 'spin 3')
    failed(c, 'currents "0.1 0')  # an open quote: malformed
    assert 'not a number' in failed(c, 'pd one 0')


def check_session(c):
    kw = done(c, 'enable')
    assert kw['board']['enabled'] is True and all(m['ready'] for m in kw['board']['motors']), kw['board']
    kw = done(c, 'home 1')
    assert kw['homing']['all_found'] is True, kw
    kw = done(c, 'start --max-current 1.5')
    assert kw['loop']['running'] is True and kw['limits']['max_current_a'] == 1.5, kw
    assert 'already runs' in failed(c, 'start')
    assert 'beyond the current limit' in failed(c, 'currents 1.8 0')
    kw = done(c, 'currents 0.2 -0.1')
    assert [m['mode'] for m in kw['action']['motors']] == ['current', 'current'], kw['action']
    kw = done(c, 'current 2 0.05')
    assert kw['action']['motors'][0]['current_a'] == 0.2 and kw['action']['motors'][1]['current_a'] == 0.05, kw
    here = [m['position_rev'] for m in done(c, 'status')['board']['motors']]
    kw = done(c, 'pd %.4f %.4f 4 0.05' % (here[0], here[1]))
    assert kw['action']['motors'][1]['mode'] == 'pd' and kw['action']['motors'][1]['kp'] == 4, kw['action']
    time.sleep(0.5)
    kw = done(c, 'status')
    assert kw['loop']['running'] is True and kw['loop']['back_end']['cycles'] > 0, kw['loop']
    assert kw['action']['applied'] == 'action', kw['action']
    kw = done(c, 'stop')
    assert kw['stopped']['end'] == 'requested' and kw['stopped']['cycles'] > 0, kw
    print('loop of %.1f s: %d cycles, %d overruns, jitter p99 %.0f us, max %.0f us; back end %s'
          % (kw['stopped']['duration_s'], kw['stopped']['cycles'], kw['stopped']['overruns'],
             kw['stopped']['jitter_p99_us'], kw['stopped']['jitter_max_us'], kw['stopped']['back_end']))


def check_fault(c, port):
    listener = Commander(port, ACTOR, VALIDATOR)  # hears the broadcasts only
    try:
        done(c, 'start')
        done(c, 'currents 0.1 0')
        t0 = time.perf_counter()
        done(c, 'sim-fault encoder')
        stop = lambda: [kw for code, kw in listener.broadcasts if code == 'e' and 'safety_stop' in kw]
        assert listener.pump(lambda: stop(), 10), listener.broadcasts
        print('safety stop heard by a listener %.0f ms after sim-fault was sent' % ((time.perf_counter() - t0) * 1e3))
        text = stop()[0]['safety_stop']['text']
        assert stop()[0]['safety_stop']['end'] == 'fault' and 'ENCODER' in text, stop()[0]
        assert listener.pump(lambda: any('board_error' in kw and kw['board_error']['code'] == 1
                                         for _, kw in listener.broadcasts), 5), listener.broadcasts
    finally:
        listener.close()
    assert 'the last run ended' in failed(c, 'currents 0.1 0')
    kw = done(c, 'errors')
    assert kw['last_run']['end'] == 'fault' and any(f['source'] == 'safety_stop' for f in kw['faults']), kw
    assert 'sim-fault takes' in failed(c, 'sim-fault melt')
    kw = done(c, 'recover')
    assert kw['board_error']['code'] == 0 and kw['board']['enabled'] is True, kw


def check_tell(port):
    p = tell(port, 'status')
    assert p.returncode == 0 and 'blmc :' in p.stdout and 'board=' in p.stdout, (p.returncode, p.stdout, p.stderr)
    p = tell(port, 'errors', json_out=True)
    lines = [json.loads(l) for l in p.stdout.splitlines()]
    assert p.returncode == 0 and lines[-1]['message_code'] == ':', (p.returncode, p.stdout, p.stderr)
    for l in lines:
        assert not list(VALIDATOR.iter_errors(l['keywords'])), l
    p = tell(port, 'currents', '-0.1', '0')  # no loop runs: exit 1
    assert p.returncode == 1 and 'blmc f' in p.stdout, (p.returncode, p.stdout, p.stderr)


def check_broker_loss(c, broker):
    """The broker goes while a current flows: the actor sets the idle action, keeps the loop (zero
    current) and answers again once the broker is back."""
    done(c, 'start')
    done(c, 'currents 0.15 0.15')
    c.close()
    broker.stop()
    time.sleep(1.0)
    up = broker.start()
    assert up is not None, 'the broker did not start again'
    print('broker restarted in %.1f s' % up)
    c = wait_for_actor(broker.port, 30)
    kw = done(c, 'status')
    assert kw['loop']['running'] is True, kw['loop']
    assert kw['action']['by'] == 'broker lost' and [m['mode'] for m in kw['action']['motors']] == ['idle', 'idle'], kw
    kw = done(c, 'errors')
    assert any(f['source'] == 'broker' and 'idle action' in f['text'] for f in kw['faults']), kw['faults']
    kw = done(c, 'disable')
    assert kw['stopped']['end'] == 'requested' and kw['board']['enabled'] is False, kw
    return c


def main():
    if broker_missing():
        print('SKIP: ' + broker_missing())
        return 0
    with ActorRun('axon-actor-blmc-') as run:
        t0 = time.monotonic()
        broker = run.broker
        up = broker.start()
        if up is None:
            print('SKIP: rabbitmq-server cannot start here (see %s/server.out)' % run.tmp)
            return 0
        print('broker up in %.1f s' % up)
        run.start_actor([AXON, 'actor', 'blmc', '--broker', '127.0.0.1:%d' % broker.port, '--exchange', EXCHANGE,
                         '--name', ACTOR, '--status-period', '1', '--no-realtime'])
        c = wait_for_actor(broker.port, 30)
        check_refusals(c)
        check_session(c)
        check_fault(c, broker.port)
        check_tell(broker.port)
        assert any('limits' in kw for code, kw in c.broadcasts if code == 'i'), 'no periodic status broadcast'
        checked = c.checked
        c = check_broker_loss(c, broker)
        checked += c.checked
        c.close()

        rc, err = run.stop_actor()
        assert rc == 0, (rc, err[-2000:])
        assert 'motors disabled' in err and 'broker connection was lost' in err, err[-2000:]
        print('ok: %d replies valid against docs/schema/blmc.json, %.1f s in all' % (checked, time.monotonic() - t0))
        return 0


if __name__ == '__main__':
    sys.exit(main())
