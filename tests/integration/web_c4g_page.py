"""The c4g page in headless Chromium (Debian's chromium, chromium-driver and python3-selenium) against
`axon c4g serve --app stream --mode 4 --http 127.0.0.1:0` answering `axon sim c4g`, as a user would run
them:
  1. before the program opens the arm the page shows its six axes in mode 0 with the drives on;
  2. when the robot program switches arm 1 to mode 4 the page shows mode 4 on every axis of the arm
     (code, the manual's label "4", phase running) and the stream app running, as the server's own
     state has it (the page's latency behind the server is printed);
  3. the receive-to-send histogram is drawn with Chart.js, its bars count every cycle the server
     timed, and the 500 us deadline is marked on it; the period histogram has the controller's 2 ms
     marked;
  4. once the app has brought the arm back to mode 0 (the server then ends, as `axon c4g serve` does
     when its app finished, and --http-linger keeps the page up) the page shows the app done and
     the arm out of mode 4, with no safety fault.
The simulator takes the lenient reply window of one period (--lenient-timing): the subject is the
page, not the latency of a loaded test machine. Skips only when Chromium cannot start at all."""
import json
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
PROGRAM = """name: page test, mode 4
steps:
  - drive_on
  - delay: 1.5
  - go_open: {type: A, mode: 4, arms: [1]}
  - wait_for_pc: {timeout: 30}
  - exit_open
"""
# A relative trajectory of 3 s: long enough for the page to show the open mode a while.
TRAJECTORY = "# units: deg\nt,j1,j2,j3,j4,j5,j6\n0,0,0,0,0,0,0\n1.5,3,-2,1,0,2,0\n3,0,0,0,0,0,0\n"


def read_line(proc, prefix):
    for line in proc.stdout:
        if line.startswith(prefix):
            return line
    raise AssertionError('no "%s" line' % prefix)


def start_server(tmp):
    with open(os.path.join(tmp, 'traj.csv'), 'w') as f:
        f.write(TRAJECTORY)
    serve = subprocess.Popen([AXON, 'c4g', 'serve', '--listen', '127.0.0.1:0', '--app', 'stream', '--file',
                              os.path.join(tmp, 'traj.csv'), '--mode', '4', '--relative', '--status-interval', '0', '--rt-priority', '10',
                              '--http', '127.0.0.1:0', '--http-linger', '60'],
                             stdout=subprocess.PIPE, stderr=open(os.path.join(tmp, 'serve.err'), 'w'), text=True)
    c4g_port = read_line(serve, 'listening c4g ').strip().rsplit(':', 1)[1]
    url = 'http://' + read_line(serve, 'listening http ').split()[2]
    # Its event lines are read as they come, so that a full pipe never blocks run()'s thread.
    threading.Thread(target=lambda: [None for _ in serve.stdout], daemon=True).start()
    return serve, c4g_port, url


def start_controller(tmp, c4g_port):
    with open(os.path.join(tmp, 'program.yaml'), 'w') as f:
        f.write(PROGRAM)
    return subprocess.Popen([AXON, 'sim', 'c4g', '--robot', 'six-axis', '--server', '127.0.0.1:' + c4g_port, '--scenario',
                             os.path.join(tmp, 'program.yaml'), '--lenient-timing'],
                            stdout=open(os.path.join(tmp, 'sim.out'), 'w'), stderr=open(os.path.join(tmp, 'sim.err'), 'w'))


def api_state(url):
    with urllib.request.urlopen(url + '/api/c4g/state', timeout=5) as r:
        return json.load(r)


def page_modes(driver):
    return page(driver, "Array.from(document.querySelectorAll('#axes tbody tr')).map((r) => Number(r.dataset.mode))")


def check_mode0_before_the_program_opens(driver):
    # The drives come on first (501 on every axis while driving on), then mode 0.
    wait_until('six axes in mode 0 on the page', lambda: page_modes(driver) == [0] * 6, seconds=15)
    wait_until('the drives on', lambda: page(driver, "document.querySelector('#arms li[data-arm=\"1\"]')?.dataset.drives") == 'on',
               seconds=5)
    print('page: six axes in mode 0, arm 1 drives on')


def check_mode4_shown(driver, url):
    seen_by_server = wait_until('mode 4 in the server state',
                                lambda: api_state(url)['axes'][0]['mode'] == 4 and time.monotonic(), seconds=15, step=0.05)
    seen_by_page = wait_until('mode 4 on the page', lambda: page_modes(driver)[0] == 4 and time.monotonic(), seconds=5, step=0.05)
    print('page: mode 4 shown %.0f ms after the server state had it' % (1000 * (seen_by_page - seen_by_server)))
    wait_until('the stream running', lambda: page(driver, "document.getElementById('phase').dataset.phase") == 'running', seconds=5)
    assert page_modes(driver) == [4] * 6, page_modes(driver)
    first = page(driver, "Array.from(document.querySelectorAll('#axes tbody tr')[0].cells).map((c) => c.textContent)")
    assert first[2] == '4' and first[3] == '4' and first[4] == 'mode4' and first[5] == 'running', first
    print('page: axis 1 %s' % ' | '.join(first))


def check_histograms(driver, url):
    wait_until('the histograms drawn', lambda: page(driver, 'window.axonC4g.charts !== null'), seconds=5)
    assert page(driver, "document.getElementById('chart-missing').hidden"), 'Chart.js missing'
    drawn = page(driver, """(() => {
      const c = window.axonC4g.charts, s = window.axonC4g.state;
      const sum = (chart) => chart.data.datasets[0].data.reduce((a, v) => a + (v || 0), 0);
      return {cycle: sum(c.cycle), period: sum(c.period), cycles: s.timing.cycles, marks: window.axonC4g.marks,
              area: c.cycle.chartArea, bars: c.cycle.data.datasets[0].data.length};
    })()""")
    assert drawn['bars'] == 51, drawn
    # The state is read while the cycle thread counts on: the bars and the count may differ by a cycle or two.
    assert drawn['cycles'] > 100 and abs(drawn['cycle'] - drawn['cycles']) <= 5, drawn
    assert abs(drawn['period'] - (drawn['cycles'] - 1)) <= 5, drawn
    mark = drawn['marks']['cycle']
    assert mark['value_us'] == 500 and drawn['area']['left'] < mark['x'] < drawn['area']['right'], drawn
    assert drawn['marks']['period']['value_us'] == 2000, drawn
    late = page(driver, "document.querySelector('#counters').textContent")
    assert 'late replies' in late, late
    print('page: histogram of %d cycles, deadline drawn at x=%.0f px' % (drawn['cycle'], mark['x']))


def check_the_end_shown(driver):
    wait_until('the app done', lambda: page(driver, "document.getElementById('phase').dataset.phase") == 'done', seconds=20)
    wait_until('the arm out of mode 4', lambda: all(m in (0, 504) for m in page_modes(driver)), seconds=10)
    assert page(driver, "document.getElementById('safety').dataset.fault") == 'none'
    print('page: the stream done, the arm in mode %s' % page_modes(driver)[0])


def main():
    tmp = tempfile.mkdtemp()
    driver = start_chromium()
    procs = []
    try:
        serve, c4g_port, url = start_server(tmp)
        procs.append(serve)
        driver.get(url + '/c4g.html')
        wait_until('the page connected', lambda: page(driver, "document.getElementById('conn').className") == 'live', seconds=10)
        sim = start_controller(tmp, c4g_port)
        procs.append(sim)
        check_mode0_before_the_program_opens(driver)
        check_mode4_shown(driver, url)
        check_histograms(driver, url)
        check_the_end_shown(driver)
        assert sim.wait(timeout=30) == 0, 'the simulated controller failed'
        print('PASS')
    except BaseException:
        for name in ('serve.err', 'sim.out', 'sim.err'):
            path = os.path.join(tmp, name)
            if os.path.exists(path):
                print('--- %s\n%s' % (name, open(path).read()[-3000:]))
        raise
    finally:
        driver.quit()
        for p in reversed(procs):  # the controller first: the server then stops at once
            if p.poll() is None:
                p.terminate()
            p.wait(timeout=10)
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == '__main__':
    main()
