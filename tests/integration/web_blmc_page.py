"""The blmc page in headless Chromium (Debian's chromium, chromium-driver and python3-selenium) against
`axon blmc pd --http 127.0.0.1:0` driving `axon sim blmc`, as a user would run them:
  1. the scopes are drawn with Chart.js and their last values track the board: motor 1's position
     follows the PD's sine around its start position (start + A sin(2 pi f t), the simulated motor
     within 0.1 rev of it), at the loop's own time, and the scope keeps up with the server's state;
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
AMPLITUDE, FREQUENCY = 0.5, 0.5  # rev, Hz: the PD's sine
TOLERANCE_REV = 0.1              # the simulated motor against the sine (tests/integration/cli_blmc.sh)
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
    pd = subprocess.Popen([AXON, 'blmc', '--socketcand', '127.0.0.1:%s/can0' % port, '--no-realtime', '--stale-ms', '200',
                           '--http', '127.0.0.1:0', '--http-linger', '60', 'pd', '--amplitude', str(AMPLITUDE),
                           '--frequency', str(FREQUENCY), '--duration', '60'],
                          stdout=subprocess.PIPE, stderr=open(os.path.join(tmp, 'pd.err'), 'w'), text=True)
    url = 'http://' + read_line(pd, 'listening http ').split()[2]
    # Its table rows (10 a second) are read away, so that a full pipe never blocks its bus thread.
    threading.Thread(target=pd.stdout.read, daemon=True).start()
    return sim, pd, url


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
        target = s['p0']['y'] + AMPLITUDE * math.sin(2 * math.pi * FREQUENCY * s['t'])
        assert abs(s['p'] - target) < TOLERANCE_REV, (s, target)
        server_t = api_board(url)['samples']['t'][-1]
        assert 0 <= server_t - s['t'] < 0.5, 'the scope at %.2f s, the server at %.2f s' % (s['t'], server_t)
        checked.append((s['t'], s['p'] - target))
        time.sleep(0.1)
    times = [t for t, _ in checked]
    assert times[-1] > times[0], 'the scope did not move: %s' % times
    rate = page(driver, 'window.axonBlmc.messages') / max(1e-3, times[-1])
    print('page: motor 1 position within %.3f rev of the sine over %.1f..%.1f s; about %.0f updates/s' %
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
