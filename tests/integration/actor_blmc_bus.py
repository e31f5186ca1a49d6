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

from amqp_support import Actor, restart_broker, run_with_broker

AXON = sys.argv[1]


def check_refusals(c):
    kw = c.expect_done('status')
    assert len(kw['board']['motors']) == 2 and kw['loop']['running'] is False, kw
    assert kw['board_error'] == {'code': 0, 'name': 'NONE', 'meaning': 'no error'}, kw['board_error']
    assert 'no control loop runs' in c.expect_failed('currents 0.1 0')
    assert 'not enabled' in c.expect_failed('start')
    assert 'not JSON' in c.expect_failed(body=b'currents, please')
    assert 'unknown command' in c.expect_failed('spin 3')
    c.expect_failed('currents "0.1 0')  # an open quote: malformed
    assert 'not a number' in c.expect_failed('pd one 0')


def check_session(c):
    kw = c.expect_done('enable')
    assert kw['board']['enabled'] is True and all(m['ready'] for m in kw['board']['motors']), kw['board']
    kw = c.expect_done('home 1')
    assert kw['homing']['all_found'] is True, kw
    kw = c.expect_done('start --max-current 1.5')
    assert kw['loop']['running'] is True and kw['limits']['max_current_a'] == 1.5, kw
    assert 'already runs' in c.expect_failed('start')
    assert 'beyond the current limit' in c.expect_failed('currents 1.8 0')
    kw = c.expect_done('currents 0.2 -0.1')
    assert [m['mode'] for m in kw['action']['motors']] == ['current', 'current'], kw['action']
    kw = c.expect_done('current 2 0.05')
    assert kw['action']['motors'][0]['current_a'] == 0.2 and kw['action']['motors'][1]['current_a'] == 0.05, kw
    here = [m['position_rev'] for m in c.expect_done('status')['board']['motors']]
    kw = c.expect_done('pd %.4f %.4f 4 0.05' % (here[0], here[1]))
    assert kw['action']['motors'][1]['mode'] == 'pd' and kw['action']['motors'][1]['kp'] == 4, kw['action']
    time.sleep(0.5)
    kw = c.expect_done('status')
    assert kw['loop']['running'] is True and kw['loop']['back_end']['cycles'] > 0, kw['loop']
    assert kw['action']['applied'] == 'action', kw['action']
    kw = c.expect_done('stop')
    assert kw['stopped']['end'] == 'requested' and kw['stopped']['cycles'] > 0, kw
    print('loop of %.1f s: %d cycles, %d overruns, jitter p99 %.0f us, max %.0f us; back end %s'
          % (kw['stopped']['duration_s'], kw['stopped']['cycles'], kw['stopped']['overruns'],
             kw['stopped']['jitter_p99_us'], kw['stopped']['jitter_max_us'], kw['stopped']['back_end']))


def check_fault(c, actor, port):
    listener = actor.commander(port)  # hears the broadcasts only
    try:
        c.expect_done('start')
        c.expect_done('currents 0.1 0')
        t0 = time.perf_counter()
        c.expect_done('sim-fault encoder')
        stop = lambda: [kw for code, kw in listener.broadcasts if code == 'e' and 'safety_stop' in kw]
        assert listener.pump(lambda: stop(), 10), listener.broadcasts
        print('safety stop heard by a listener %.0f ms after sim-fault was sent' % ((time.perf_counter() - t0) * 1e3))
        text = stop()[0]['safety_stop']['text']
        assert stop()[0]['safety_stop']['end'] == 'fault' and 'ENCODER' in text, stop()[0]
        assert listener.pump(lambda: any('board_error' in kw and kw['board_error']['code'] == 1
                                         for _, kw in listener.broadcasts), 5), listener.broadcasts
    finally:
        listener.close()
    assert 'the last run ended' in c.expect_failed('currents 0.1 0')
    kw = c.expect_done('errors')
    assert kw['last_run']['end'] == 'fault' and any(f['source'] == 'safety_stop' for f in kw['faults']), kw
    assert 'sim-fault takes' in c.expect_failed('sim-fault melt')
    kw = c.expect_done('recover')
    assert kw['board_error']['code'] == 0 and kw['board']['enabled'] is True, kw


def check_tell(actor, port):
    p = actor.tell(port, 'status')
    assert p.returncode == 0 and 'blmc :' in p.stdout and 'board=' in p.stdout, (p.returncode, p.stdout, p.stderr)
    p = actor.tell(port, 'errors', json_out=True)
    lines = [json.loads(l) for l in p.stdout.splitlines()]
    assert p.returncode == 0 and lines[-1]['message_code'] == ':', (p.returncode, p.stdout, p.stderr)
    for l in lines:
        assert not list(actor.validator.iter_errors(l['keywords'])), l
    p = actor.tell(port, 'currents', '-0.1', '0')  # no loop runs: exit 1
    assert p.returncode == 1 and 'blmc f' in p.stdout, (p.returncode, p.stdout, p.stderr)


def check_broker_loss(c, broker, actor):
    """The broker goes while a current flows: the actor sets the idle action, keeps the loop (zero
    current) and answers again once the broker is back."""
    c.expect_done('start')
    c.expect_done('currents 0.15 0.15')
    c.close()
    c, _ = restart_broker(broker, actor, 1.0)
    kw = c.expect_done('status')
    assert kw['loop']['running'] is True, kw['loop']
    assert kw['action']['by'] == 'broker lost' and [m['mode'] for m in kw['action']['motors']] == ['idle', 'idle'], kw
    kw = c.expect_done('errors')
    assert any(f['source'] == 'broker' and 'idle action' in f['text'] for f in kw['faults']), kw['faults']
    kw = c.expect_done('disable')
    assert kw['stopped']['end'] == 'requested' and kw['board']['enabled'] is False, kw
    return c


def main(run):
    t0 = time.monotonic()
    broker, actor = run.broker, Actor(AXON, 'blmc')
    run.start_actor(actor.args('blmc', broker.port, '--status-period', '1', '--no-realtime'))
    c = actor.wait(broker.port)
    check_refusals(c)
    check_session(c)
    check_fault(c, actor, broker.port)
    check_tell(actor, broker.port)
    assert any('limits' in kw for code, kw in c.broadcasts if code == 'i'), 'no periodic status broadcast'
    checked = c.checked
    c = check_broker_loss(c, broker, actor)
    checked += c.checked
    c.close()

    rc, err = run.stop_actor()
    assert rc == 0, (rc, err[-2000:])
    assert 'motors disabled' in err and 'broker connection was lost' in err, err[-2000:]
    print('ok: %d replies valid against docs/schema/blmc.json, %.1f s in all' % (checked, time.monotonic() - t0))
    return 0


if __name__ == '__main__':
    sys.exit(run_with_broker('axon-actor-blmc-', main))
