"""The c4g simulator's page (`axon sim c4g --http 127.0.0.1:0`) and the server page's live following
error, in headless Chromium (Debian's chromium, chromium-driver and python3-selenium), with
`axon c4g serve --app stream --mode 4 --http 127.0.0.1:0` answering the simulator, as a user would
run them:
  1. the simulator prints `listening http HOST:PORT`; its page is labelled simulator and lists the
     robot program's steps;
  2. when the program's GO OPEN switches arm 1 to mode 4, the simulator page shows the arm asked for
     mode 4, every axis in mode 4 with the PC asking for 4, the step wait_for_pc under way, as the
     simulator's own /api/state has it and as the server's state has it too;
  3. the arm moves on the page: joint 1 changes by more than a degree while the PC streams;
  4. the server's c4g page (a second tab) shows a following error on axis 1 that is nonzero while it
     streams, its peak at least as large, and of the size the simulator's own target - position
     has; the server's /metrics has it per axis;
  5. once the program ended, the simulator page shows the program completed and the exchange over,
     its /metrics passes `promtool check metrics` and has the axon_c4g_sim_* families, and the
     cyclic packets it counts are those the server counted. The program waits 0.3 s in mode 0 after
     the PC's part before it exits open: the server answers it to its end (--until-controller-ends);
     a server that stopped when its app finished would leave those packets unanswered.
The simulator takes the lenient reply window of one period (--lenient-timing): the subject is the
pages, not the latency of a loaded test machine. Skips only when Chromium cannot start at all."""
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
from browser import http_url, page, start_chromium, start_program, wait_until  # noqa: E402

AXON = sys.argv[1]
PROGRAM = """name: simulator page test, mode 4
steps:
  - drive_on
  - delay: 1.5
  - go_open: {type: A, mode: 4, arms: [1]}
  - wait_for_pc: {timeout: 40}
  - delay: 0.3
  - exit_open
"""
# A relative trajectory of 8 s: joint 1 out by 12 degrees and back, long enough to watch it move.
TRAJECTORY = "# units: deg\nt,j1,j2,j3,j4,j5,j6\n0,0,0,0,0,0,0\n4,12,-3,2,0,4,0\n8,0,0,0,0,0,0\n"
SIM_FAMILIES = ('axon_c4g_sim_cycles_total', 'axon_c4g_sim_packets_sent_total', 'axon_c4g_sim_replies_ok_total',
                'axon_c4g_sim_missed_replies_total', 'axon_c4g_sim_late_replies_total', 'axon_c4g_sim_bad_replies_total',
                'axon_c4g_sim_communication_error', 'axon_c4g_sim_axis_mode', 'axon_c4g_sim_axis_requested_mode',
                'axon_c4g_sim_joint_position_degrees', 'axon_c4g_sim_joint_target_degrees', 'axon_c4g_sim_drives_on',
                'axon_c4g_sim_program_mode', 'axon_c4g_sim_program_step', 'axon_c4g_sim_events_total')


def drain(proc):
    """Reads a program's stdout as it comes, so that a full pipe never blocks it."""
    threading.Thread(target=lambda: [None for _ in proc.stdout], daemon=True).start()


def start_server(tmp):
    with open(os.path.join(tmp, 'traj.csv'), 'w') as f:
        f.write(TRAJECTORY)
    serve, lines = start_program([AXON, 'c4g', 'serve', '--listen', '127.0.0.1:0', '--app', 'stream', '--file',
                                  os.path.join(tmp, 'traj.csv'), '--mode', '4', '--relative', '--until-controller-ends', '--status-interval', '0',
                                  '--rt-priority', '10', '--http', '127.0.0.1:0', '--http-linger', '60'],
                                 'listening http ', stderr=open(os.path.join(tmp, 'serve.err'), 'w'))
    drain(serve)
    c4g_port = [l for l in lines if l.startswith('listening c4g ')][0].strip().rsplit(':', 1)[1]
    return serve, c4g_port, http_url(lines)


def start_simulator(tmp, c4g_port):
    with open(os.path.join(tmp, 'program.yaml'), 'w') as f:
        f.write(PROGRAM)
    sim, lines = start_program([AXON, 'sim', 'c4g', '--robot', 'six-axis', '--server', '127.0.0.1:' + c4g_port, '--scenario',
                                os.path.join(tmp, 'program.yaml'), '--lenient-timing', '--http', '127.0.0.1:0',
                                '--http-linger', '60'],
                               'listening http ', stderr=open(os.path.join(tmp, 'sim.err'), 'w'))
    drain(sim)
    return sim, http_url(lines)


def get(url, path):
    with urllib.request.urlopen(url + path, timeout=5) as r:
        return r.read().decode()


def sim_state(url):
    return json.loads(get(url, '/api/c4g-sim/state'))


def server_state(url):
    return json.loads(get(url, '/api/c4g/state'))


def page_modes(driver):
    return page(driver, "Array.from(document.querySelectorAll('#axes tbody tr')).map((r) => Number(r.dataset.mode))")


def page_joint1(driver):
    return page(driver, "Number(document.querySelector('#joints tr[data-arm=\"1\"][data-joint=\"1\"]')?.dataset.deg)")


def check_label_and_program(driver):
    assert page(driver, "document.getElementById('sim-banner').textContent") == 'simulator'
    steps = page(driver, "Array.from(document.querySelectorAll('#program li')).map((li) => li.textContent)")
    assert len(steps) == 6 and steps[2].startswith('go_open'), steps
    print('page: labelled simulator, %d program steps' % len(steps))


def check_mode4_shown(driver, sim_url, serve_url):
    wait_until('mode 4 in the simulator state', lambda: sim_state(sim_url)['axes'][0]['mode'] == 4, seconds=20, step=0.05)
    wait_until('mode 4 on the simulator page', lambda: page_modes(driver) == [4] * 6, seconds=5, step=0.05)
    arm = page(driver, "document.querySelector('#arms li[data-arm=\"1\"]').dataset")
    assert arm['programMode'] == '4' and arm['drives'] == 'on', arm
    wait_until('the PC asking for mode 4', lambda: page(driver, "Array.from(document.querySelectorAll('#axes tbody tr'))"
                                                                ".every((r) => r.dataset.pcRequest === '4')"), seconds=5)
    assert page(driver, "document.getElementById('step').dataset.kind") == 'wait_for_pc'
    assert server_state(serve_url)['axes'][0]['mode'] == 4
    print('page: arm 1 asked for mode 4 by the program, six axes in mode 4, step %s'
          % page(driver, "document.getElementById('step').textContent"))


def check_the_arm_moves(driver):
    seen = [page_joint1(driver)]
    wait_until('joint 1 moving on the page', lambda: seen.append(page_joint1(driver)) or max(seen) - min(seen) > 1.0,
               seconds=6, step=0.1)
    print('page: joint 1 went from %.3f to %.3f deg' % (min(seen), max(seen)))


def check_server_following_error(driver, serve_url, sim_url):
    """The server's page in a second tab: axis 1's following error live and of the simulator's size."""
    sim_tab = driver.current_window_handle
    driver.switch_to.new_window('tab')
    driver.get(serve_url + '/c4g.html')
    wait_until('the server page connected', lambda: page(driver, "document.getElementById('conn').className") == 'live',
               seconds=10)
    fe_cell = "Number(document.querySelectorAll('#axes tbody tr')[0]?.cells[7].dataset.fe)"
    shown, truth = [], []
    end = time.monotonic() + 2.0
    while time.monotonic() < end:
        if page_modes(driver)[:1] == [4]:
            shown.append(page(driver, fe_cell))
            truth.append(abs(sim_state(sim_url)['axes'][0]['error']))
        time.sleep(0.1)
    assert shown and max(shown) > 0, shown
    peak = page(driver, "Number(document.querySelectorAll('#axes tbody tr')[0].cells[8].textContent)")
    served = server_state(serve_url)['axes'][0]
    assert served['following_error_peak'] >= served['following_error'] > 0, served
    # Both read a few times a second, not at the same cycle: of the same size.
    assert max(truth) / 3 < max(shown) < 3 * max(truth) + 1e-5, (shown, truth)
    metrics = get(serve_url, '/metrics')
    assert 'axon_c4g_following_error_revolutions{axis="1"} ' in metrics, 'no following error in the server\'s /metrics'
    print('server page: axis 1 following error up to %.5f turns (peak %.5f shown), the simulator\'s target - position up '
          'to %.5f' % (max(shown), peak, max(truth)))
    driver.close()
    driver.switch_to.window(sim_tab)


def check_the_end(driver, sim_url, serve_url, tmp):
    wait_until('the program completed on the page',
               lambda: page(driver, "document.getElementById('step').textContent") == 'program completed', seconds=30)
    wait_until('the run ended on the page', lambda: page(driver, "document.getElementById('phase').dataset.phase") == 'done',
               seconds=5)
    assert page(driver, "document.getElementById('comm').dataset.error") == 'false'
    metrics = get(sim_url, '/metrics')
    with open(os.path.join(tmp, 'sim_metrics.txt'), 'w') as f:
        f.write(metrics)
    promtool = shutil.which('promtool')
    assert promtool, 'promtool not found (Debian\'s prometheus package; scripts/install-deps.sh)'
    checked = subprocess.run([promtool, 'check', 'metrics'], input=metrics, capture_output=True, text=True)
    assert checked.returncode == 0, checked.stdout + checked.stderr
    for name in SIM_FAMILIES:
        assert '# TYPE %s ' % name in metrics, 'no %s in the simulator\'s /metrics' % name
    s = sim_state(sim_url)
    wait_until('the server done', lambda: server_state(serve_url)['server']['state'] == 'stopped', seconds=10)
    served = server_state(serve_url)['counters']['cyclic']
    assert s['counters']['cyclic_sent'] + s['counters']['sync_sent'] == served, (s['counters'], served)
    print('page: program completed; /metrics passes promtool, %d cyclic packets as the server counted them'
          % s['counters']['cyclic_sent'])


def main():
    tmp = tempfile.mkdtemp()
    driver = start_chromium()
    procs = []
    try:
        serve, c4g_port, serve_url = start_server(tmp)
        procs.append(serve)
        sim, sim_url = start_simulator(tmp, c4g_port)
        procs.append(sim)
        driver.get(sim_url + '/c4g-sim.html')
        wait_until('the page connected', lambda: page(driver, "document.getElementById('conn').className") == 'live', seconds=10)
        check_label_and_program(driver)
        check_mode4_shown(driver, sim_url, serve_url)
        check_the_arm_moves(driver)
        check_server_following_error(driver, serve_url, sim_url)
        check_the_end(driver, sim_url, serve_url, tmp)
        print('PASS')
    except BaseException:
        for name in ('serve.err', 'sim.err'):
            path = os.path.join(tmp, name)
            if os.path.exists(path):
                print('--- %s\n%s' % (name, open(path).read()[-3000:]))
        raise
    finally:
        driver.quit()
        for p in reversed(procs):  # the simulator first: the server then stops at once
            if p.poll() is None:
                p.terminate()
            p.wait(timeout=10)
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == '__main__':
    main()
