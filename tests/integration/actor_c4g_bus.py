"""`axon actor c4g` on a real RabbitMQ broker, driven by the independent python3-pika commander of
amqp_support.py (written from the SDSS actor convention, docs/actor.md, not from axon's code). The
actor serves its embedded simulated controller, whose program gives the PC open phases in modes 4
and 7 again and again. Checked: status (server, each axis's mode and label, drives, the monitor),
an app started by command (handover) with the mode changes seen by a second listener, a second
start refused while it is in force, stats, stop leaving the open mode cleanly, a malformed and an
unknown command, `axon tell c4g status` (human and --json), and the broker stopped and started
again while the server goes on answering the controller. Every reply is checked against
docs/schema/c4g.json with python3-jsonschema. Skipped only when no broker can start at all."""
import json
import sys
import time

from amqp_support import Actor, restart_broker, run_with_broker

AXON = sys.argv[1]


def final(replies):
    return replies[-1]


def wait_for_modes(c, label, timeout=30):
    """Polls status until every open axis shows `label`; returns the last status keywords."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        code, kw = final(c.command('status'))
        assert code == ':', kw
        if kw['axes'] and all(a['label'] == label for a in kw['axes']):
            return kw
        time.sleep(0.1)
    raise AssertionError('the axes never all showed mode %s: %s' % (label, kw['axes']))


def changed(broadcasts, frm, to):
    """The mode_changes broadcasts so far move every axis from `frm` to `to` (the six changes of one
    packet may come in two broadcasts: the actor's watcher drains while they are queued)."""
    moves = {m['axis'] for _, kw in broadcasts for m in kw.get('mode_changes', [])
             if m['from_label'] == frm and m['to_label'] == to}
    return len(moves) == 6


def check_commands(c, listener, actor, port):
    kw = wait_for_modes(c, '4')  # the program's first open phase, held by the monitor
    assert kw['server']['state'] == 'running' and kw['server']['period_ms'] == 2, kw['server']
    assert kw['app'] == dict(kw['app'], name='monitor', installed=False), kw['app']
    assert kw['drives'][0] == {'arm': 1, 'on': True} and kw['safety']['fault'] == 'none', kw
    assert [a['arm_axis'] for a in kw['axes']] == [1, 2, 3, 4, 5, 6], kw['axes']

    # An app by command: handover serves each open phase (a hold in 4, a zero correction in 7).
    code, kw = final(c.command('start handover --open-time 0.3'))
    assert code == ':' and kw['app']['name'] == 'handover' and kw['app']['installed'], kw
    code, kw = final(c.command('start echo'))
    assert code == 'f' and 'handover is in force: stop it first' in kw['error'], kw
    assert listener.pump(lambda: changed(listener.broadcasts, '4', "4'") and changed(listener.broadcasts, '0', '7'), 30), \
        [kw for _, kw in listener.broadcasts if 'mode_changes' in kw][-3:]
    print('mode changes seen by a second listener: 4 -> 4\' -> 0 -> 7')

    code, kw = final(c.command('stats'))
    s = kw['stats']
    assert code == ':' and s['cyclic_packets'] > 0 and s['init_packets'] == 1 and s['timing']['nominal_period_s'] == 0.002, s
    print('stats: %d cycles, receive to send p50 %.0f us p99 %.0f us max %.0f us, period [%.2f, %.2f] ms, '
          '%d late (over %.0f us)' % (s['timing']['cycles'], s['timing']['cycle_time_p50_s'] * 1e6,
                                      s['timing']['cycle_time_p99_s'] * 1e6, s['timing']['cycle_time_max_s'] * 1e6,
                                      s['timing']['inter_packet_period_s'][0] * 1e3,
                                      s['timing']['inter_packet_period_s'][1] * 1e3, s['timing']['missed_deadlines'],
                                      s['timing']['deadline_s'] * 1e6))

    code, kw = final(c.command('stop', timeout=30))
    assert code == ':' and 'app_ended' in kw, (code, kw)
    ended = kw['app_ended']
    assert code == ':' and ended['name'] == 'handover' and ended['reason'] == 'stopped', kw
    assert ended['left_cleanly'] and not ended['drive_off'] and not kw['safety']['latched'], kw
    assert c.pump(lambda: any(k.get('app_ended', {}).get('name') == 'handover' for _, k in c.broadcasts), 5)
    code, kw = final(c.command('status'))
    assert kw['app']['name'] == 'monitor' and kw['last_app']['name'] == 'handover', kw

    # What a commander gets wrong: failures with a reason, counted; the actor goes on.
    code, kw = final(c.command(body=b'start handover, please'))
    assert code == 'f' and 'not JSON' in kw['error'], kw
    code, kw = final(c.command('fly 3'))
    assert code == 'f' and 'unknown command' in kw['error'], kw
    code, kw = final(c.command('start correct --amplitude big'))
    assert code == 'f' and '--amplitude takes a number' in kw['error'], kw
    code, kw = final(c.command('status'))
    assert kw['commands']['not_json'] == 1 and kw['commands']['unknown'] == 1, kw['commands']

    # axon tell: human and --json.
    p = actor.tell(port, 'status')
    assert p.returncode == 0 and 'c4g :' in p.stdout and 'axes=' in p.stdout, (p.returncode, p.stdout, p.stderr)
    p = actor.tell(port, 'stats', json_out=True)
    lines = [json.loads(l) for l in p.stdout.splitlines()]
    assert p.returncode == 0 and lines[-1]['message_code'] == ':', (p.returncode, p.stdout, p.stderr)
    for l in lines:
        assert not list(actor.validator.iter_errors(l['keywords'])), l
    p = actor.tell(port, 'start', 'nothing')
    assert p.returncode == 1 and 'c4g f' in p.stdout, (p.returncode, p.stdout, p.stderr)
    assert listener.pump(lambda: any('server' in kw and 'axes' in kw for _, kw in listener.broadcasts), 5), \
        'no periodic status broadcast'


def check_broker_loss(c, broker, actor):
    """The broker goes away for a while: the server answers the controller all along."""
    before = final(c.command('status'))[1]['server']['cycles']
    c.close()
    c, away = restart_broker(broker, actor, 2.0)
    kw = final(c.command('status'))[1]
    answered = kw['server']['cycles'] - before
    assert kw['server']['state'] == 'running', kw['server']
    assert answered >= 0.5 * away / 0.002, (answered, away)
    print('broker away %.1f s: %d cycles answered meanwhile (%.0f per s)' % (away, answered, answered / away))
    return c


def main(run):
    t0 = time.monotonic()
    broker, actor = run.broker, Actor(AXON, 'c4g')
    # The cycle thread at SCHED_FIFO, as on a robot's PC: on this 2-core machine the broker's own
    # restart (Erlang booting) starved a normal thread for over 20 ms, ten unanswered packets in a
    # row, and the simulated controller raised its communication error. Refused without the rights
    # (a warning): the test then runs at normal priority.
    run.start_actor(actor.args('c4g', broker.port, '--listen', '127.0.0.1:0', '--lenient-timing', '--status-period', '1',
                               '--rt-priority', '10', '--stop-timeout', '3'))
    c = actor.wait(broker.port)
    listener = actor.commander(broker.port)
    check_commands(c, listener, actor, broker.port)
    checked = c.checked + listener.checked
    listener.close()
    c = check_broker_loss(c, broker, actor)
    checked += c.checked
    c.close()

    rc, err = run.stop_actor()
    assert rc == 0, (rc, err[-2000:])
    assert 'simulated controller:' in err and 'communication error' not in err, err[-2000:]
    print(next(l for l in err.splitlines() if 'simulated controller:' in l))
    print('ok: %d replies valid against docs/schema/c4g.json, %.1f s in all' % (checked, time.monotonic() - t0))
    return 0


if __name__ == '__main__':
    sys.exit(run_with_broker('axon-actor-c4g-', main))
