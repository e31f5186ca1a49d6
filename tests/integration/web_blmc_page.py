"""The blmc page in headless Chromium (Debian's chromium, chromium-driver and python3-selenium) against
`axon blmc pd --http 127.0.0.1:0` driving `axon sim blmc`, as a user would run them:
  1. the scopes are drawn with Chart.js and their last values track the board: motor 1's position
     on the scope at the loop's time t lies within 0.02 rev of what the command's own table printed
     for the board around t (its rows 0.1 s apart, taken from the same loop but not through the
     server), while the motor follows a sine; the scope keeps up with the server's state;
  2. an encoder fault injected into the simulated board (its fault plan) shows on the page: error
     code 1 ENCODER with its meaning, the system flag off, and the safety stop naming the error.
Skips only when Chromium cannot start at all."""
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), 'helpers'))
from browser import page, start_chromium, wait_until  # noqa: E402

AXON = sys.argv[1]
AMPLITUDE, FREQUENCY = 0.5, 0.25  # rev, Hz: the PD's sine
TOLERANCE_REV = 0.02             # the scope against the table rows around its time (plus half their step)
FAULT_AT_S = 8.0                 # the board's encoder fails this long after the simulator started


def read_line(proc, prefix):
    for line in proc.stdout:
        if line.startswith(prefix):
            return line
    raise AssertionError('no "%s" line' % prefix)


def start(tmp):
    """The simulated board with an encoder fault at FAULT_AT_S, and `axon blmc pd --http` on it."""
    config = os.path.join(tmp, 'board.yaml')
    plan = os.path.join(tmp, 'faults.yaml')
    with open(config, 'w') as f:
        f.write('alignment_s: 0.2\n')
    with open(plan, 'w') as f:
        f.write('events: [ { at_s: %g, kind: encoder } ]\n' % FAULT_AT_S)
    sim = subprocess.Popen([AXON, 'sim', 'blmc', '--socketcand', '127.0.0.1:0', '--config', config, '--fault-plan', plan,
                            '--no-realtime'], stdout=subprocess.PIPE, stderr=open(os.path.join(tmp, 'sim.err'), 'w'),
                           text=True)
    port = read_line(sim, 'listening socketcand ').strip().rsplit(':', 1)[1]
    # Generous stale and receive limits: a loaded machine must not end the run before the fault.
    pd = subprocess.Popen([AXON, 'blmc', '--socketcand', '127.0.0.1:%s/can0' % port, '--no-realtime', '--stale-ms', '5000',
                           '--recv-timeout-ms', '0',
                           '--http', '127.0.0.1:0', '--http-linger', '60', 'pd', '--kp', '1', '--kd', '0.02', '--amplitude', str(AMPLITUDE),
                           '--frequency', str(FREQUENCY), '--duration', '60'],
                          stdout=subprocess.PIPE, stderr=open(os.path.join(tmp, 'pd.err'), 'w'), text=True)
    url = 'http://' + read_line(pd, 'listening http ').split()[2]
    # Its table rows (10 a second) are read as they come, so that a full pipe never blocks its bus thread.
    threading.Thread(target=read_rows, args=(pd,), daemon=True).start()
    return sim, pd, url


ROWS = []  # (t, motor 1 position) of each row of the pd table


def read_rows(proc):
    for line in proc.stdout:
        fields = line.split('|')
        try:
            ROWS.append((float(fields[0]), float(fields[2].split()[0])))
        except (IndexError, ValueError):
            pass  # the header, the report


def table_around(t):
    """The positions the table printed just before and just after time t (the last one after the run)."""
    rows = list(ROWS)
    before = [r for r in rows if r[0] <= t]
    after = [r for r in rows if r[0] > t]
    if not before or not after:
        return None
    return before[-1], after[0]


def api_board(url):
    with urllib.request.urlopen(url + '/api/blmc/state', timeout=5) as r:
        return json.load(r)['boards'][0]


def scope_last(driver):
    """The last point of each scope's motor 1 trace, and the trace's first position (t = 0)."""
    return page(driver, """(() => {
      const c = window.axonBlmc.charts;
      const last = (key) => c[key].data.datasets[0].data.at(-1);
      return {t: last('position').x, p: last('position').y, i: last('current').y, v: last('velocity').y,
              p0: c.position.data.datasets[0].data[0], seq: window.axonBlmc.shown.seq};
    })()""")


def check_scope_tracks_the_board(driver, url):
    wait_until('the scopes drawn', lambda: page(driver, 'window.axonBlmc && window.axonBlmc.charts !== null'), seconds=10)
    assert page(driver, "document.getElementById('chart-missing').hidden"), 'Chart.js missing'
    wait_until('1.5 s of samples', lambda: (page(driver, 'window.axonBlmc.shown.t') or 0) >= 1.5, seconds=15)
    checked = []
    for _ in range(10):
        s = scope_last(driver)
        assert s['p0']['x'] == 0, s['p0']
        server_t = api_board(url)['samples']['t'][-1]
        assert 0 <= server_t - s['t'] < 0.5, 'the scope at %.2f s, the server at %.2f s' % (s['t'], server_t)
        (ta, pa), (tb, pb) = wait_until('the table row after %.2f s' % s['t'], lambda: table_around(s['t']), seconds=5)
        slack = TOLERANCE_REV + 0.5 * abs(pb - pa)  # the motion between two rows need not be straight
        lo, hi = min(pa, pb) - slack, max(pa, pb) + slack
        assert lo <= s['p'] <= hi, 'scope %.4f rev at %.3f s; table %.4f at %.3f s, %.4f at %.3f s' % (s['p'], s['t'], pa, ta, pb, tb)
        sine = s['p0']['y'] + AMPLITUDE * math.sin(2 * math.pi * FREQUENCY * s['t'])
        checked.append((s['t'], s['p'] - sine))
        time.sleep(0.1)
    times = [t for t, _ in checked]
    wait_until('the scope to move on', lambda: scope_last(driver)['t'] > times[0] + 0.5, seconds=10)
    rate = page(driver, 'window.axonBlmc.messages') / max(1e-3, times[-1])
    print('page: motor 1 position on the table, within %.3f rev of the sine over %.1f..%.1f s; about %.0f updates/s' %
          (max(abs(e) for _, e in checked), times[0], times[-1], rate))


def check_fault_shown(driver, url):
    seen_by_server = wait_until('the board error in the state', lambda: api_board(url)['error']['code'] == 1 and time.monotonic(),
                                seconds=FAULT_AT_S + 10, step=0.05)
    seen_by_page = wait_until('the board error on the page',
                              lambda: page(driver, "document.getElementById('error').dataset.code") == '1' and time.monotonic(),
                              seconds=5)
    print('page: error shown %.0f ms after the server had it' % (1000 * (seen_by_page - seen_by_server)))
    error = page(driver, "document.getElementById('error').textContent")
    assert 'ENCODER' in error and 'encoder error' in error, error
    assert page(driver, "document.getElementById('error').className") == 'bad'
    assert page(driver, "document.querySelector('#flags li[data-flag=system_enabled]').className") == ''
    wait_until('the safety stop', lambda: page(driver, "document.getElementById('fault').dataset.kind") != '', seconds=10)
    fault = page(driver, "document.getElementById('fault').textContent")
    assert not page(driver, "document.getElementById('fault').hidden")
    assert 'ENCODER' in fault, fault
    print('page: %s' % fault)


def main():
    tmp = tempfile.mkdtemp()
    driver = start_chromium()
    procs = []
    try:
        sim, pd, url = start(tmp)
        procs = [pd, sim]
        driver.get(url + '/blmc.html')
        check_scope_tracks_the_board(driver, url)
        check_fault_shown(driver, url)
        print('PASS')
    except BaseException:
        for name in ('sim.err', 'pd.err'):
            print('--- %s\n%s' % (name, open(os.path.join(tmp, name)).read()[-3000:]))
        raise
    finally:
        driver.quit()
        for p in procs:
            p.terminate()
            p.wait(timeout=10)
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == '__main__':
    main()
