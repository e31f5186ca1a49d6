#!/usr/bin/env python3
"""Takes the screenshots of the live pages that docs/dashboard.md shows, from the real programs in a
headless Chromium (Debian's chromium, chromium-driver, python3-selenium), so they are re-taken by
running this, not by hand:

  dashboard-fps.png   `axon sim fps --layout default --http`: 500 robots while `axon fps plane move`
                      turns every one of them, robot 42's details open
  dashboard-fps-replay.png  the same page replaying a plan of `axon fps plan --layout default --to
                      random` half-way through, robot 42's details open
  dashboard-blmc.png  `axon blmc ... --http pd` against `axon sim blmc`: the scopes of a PD sine
  dashboard-c4g.png   `axon c4g serve --app stream --mode 4 --http` answering `axon sim c4g`: arm 1 in
                      mode 4 while the stream plays, the timing histograms

usage: /usr/bin/python3 scripts/screenshots.py [--axon build/release/axon] [--out docs/images]
Prints one line per file written; exits 1 when a page did not come up.
"""
import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), '..'))
sys.path.insert(0, os.path.join(ROOT, 'tests', 'integration', 'helpers'))
from browser import http_url, page, start_chromium, start_program, wait_until  # noqa: E402


def parse():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument('--axon', default=os.path.join(ROOT, 'build', 'release', 'axon'))
    p.add_argument('--out', default=os.path.join(ROOT, 'docs', 'images'))
    return p.parse_args()


class Programs:
    """The programs a screenshot needs, ended (SIGTERM, then SIGKILL) on the way out."""

    def __init__(self, tmp):
        self.tmp, self.procs = tmp, []

    def start(self, name, args, until):
        """Starts `args`, logging to TMP/NAME.log; returns the stdout lines up to one starting with `until`."""
        log = open(os.path.join(self.tmp, name + '.err'), 'w')
        try:
            p, lines = start_program(args, until, stderr=log)
        except AssertionError as e:
            raise AssertionError('%s; its log: %s' % (e, log.name))
        self.procs.append(p)
        return lines

    def stop(self):
        for p in reversed(self.procs):
            if p.poll() is None:
                p.terminate()
                try:
                    p.wait(timeout=20)
                except subprocess.TimeoutExpired:
                    p.kill()
                    p.wait()
        self.procs = []


def shoot_fps(axon, driver, progs, out):
    lines = progs.start('sim-fps', [axon, 'sim', 'fps', '--layout', 'default', '--folded', '--http', '127.0.0.1:0',
                                    '--write-layout', os.path.join(progs.tmp, 'live.yaml')], 'ready')
    driver.get(http_url(lines) + '/fps.html')
    wait_until('500 robots drawn', lambda: page(driver, 'window.axonFps && window.axonFps.drawn.robots') == 500)
    move = subprocess.Popen([axon, 'fps', 'plane', '--layout', os.path.join(progs.tmp, 'live.yaml'), 'move', '--alpha',
                             '60', '--beta', '150', '--duration', '8'], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    progs.procs.append(move)
    wait_until('robots moving on the page', lambda: page(
        driver, "window.axonFps.state.robots.filter((r) => r.a > 15 && r.a < 45).length") > 100, seconds=60)
    driver.execute_script('window.axonFps.selected = 42')  # the details panel follows at the next update
    wait_until("robot 42's details", lambda: page(driver, "document.getElementById('details').dataset.robot") == '42')
    path = os.path.join(out, 'dashboard-fps.png')
    driver.save_screenshot(path)
    return path


def shoot_fps_replay(axon, driver, progs, out):
    plan = os.path.join(progs.tmp, 'plan.json')
    subprocess.run([axon, 'fps', 'plan', '--layout', 'default', '--to', 'random', '--seed', '5', '-o', plan,
                    '--allow-partial'], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=120)
    lines = progs.start('sim-fps', [axon, 'sim', 'fps', '--layout', 'default', '--folded', '--http', '127.0.0.1:0'], 'ready')
    driver.get(http_url(lines) + '/fps.html')
    wait_until('500 robots drawn', lambda: page(driver, 'window.axonFps && window.axonFps.drawn.robots') == 500)
    driver.find_element('id', 'plan-file').send_keys(plan)
    wait_until('the plan replayed', lambda: page(driver, 'window.axonFps.drawn.source') == 'replay')
    driver.execute_script('const r = window.axonFps.replay; r.seek(0.45 * r.duration); window.axonFps.selected = 42')
    wait_until("robot 42's details", lambda: page(driver, "document.getElementById('details').dataset.robot") == '42')
    path = os.path.join(out, 'dashboard-fps-replay.png')
    driver.save_screenshot(path)
    return path


def shoot_blmc(axon, driver, progs, out):
    board = os.path.join(progs.tmp, 'board.yaml')
    with open(board, 'w') as f:
        f.write('alignment_s: 0.2\n')
    sim = progs.start('sim-blmc', [axon, 'sim', 'blmc', '--socketcand', '127.0.0.1:0', '--config', board, '--no-realtime'],
                      'listening socketcand ')
    port = sim[-1].rsplit(':', 1)[1]
    lines = progs.start('blmc', [axon, 'blmc', '--socketcand', '127.0.0.1:%s/can0' % port, '--no-realtime', '--stale-ms',
                                 '1000', '--recv-timeout-ms', '0', '--http', '127.0.0.1:0', '--http-linger', '30', 'pd',
                                 '--amplitude', '0.5', '--frequency', '0.5', '--duration', '20'], 'listening http ')
    driver.get(http_url(lines) + '/blmc.html')
    wait_until('scopes with 6 s of samples', lambda: (page(
        driver, "window.axonBlmc && window.axonBlmc.state && window.axonBlmc.state.boards[0].samples.n") or 0) >= 300,
        seconds=60)
    path = os.path.join(out, 'dashboard-blmc.png')
    driver.save_screenshot(path)
    return path


# The c4g screenshot's robot program and trajectory: drives on, mode 4 on arm 1 for the 6 s trajectory.
C4G_PROGRAM = """name: screenshot, mode 4
steps:
  - drive_on
  - delay: 1.0
  - go_open: {type: A, mode: 4, arms: [1]}
  - wait_for_pc: {timeout: 30}
  - exit_open
"""
C4G_TRAJECTORY = "# units: deg\nt,j1,j2,j3,j4,j5,j6\n0,0,0,0,0,0,0\n3,10,-5,4,0,6,0\n6,0,0,0,0,0,0\n"


def shoot_c4g(axon, driver, progs, out):
    traj, program = os.path.join(progs.tmp, 'traj.csv'), os.path.join(progs.tmp, 'program.yaml')
    with open(traj, 'w') as f:
        f.write(C4G_TRAJECTORY)
    with open(program, 'w') as f:
        f.write(C4G_PROGRAM)
    lines = progs.start('c4g-serve', [axon, 'c4g', 'serve', '--listen', '127.0.0.1:0', '--app', 'stream', '--file', traj,
                                      '--mode', '4', '--relative', '--status-interval', '0', '--rt-priority', '10',
                                      '--http', '127.0.0.1:0', '--http-linger', '30'], 'listening http ')
    port = next(l for l in lines if l.startswith('listening c4g ')).rsplit(':', 1)[1]
    driver.get(http_url(lines) + '/c4g.html')
    wait_until('the page connected', lambda: page(driver, "document.getElementById('conn').className") == 'live')
    # The lenient reply window of one period: a loaded machine must not end the program early.
    sim = subprocess.Popen([axon, 'sim', 'c4g', '--robot', 'six-axis', '--server', '127.0.0.1:' + port, '--scenario', program,
                            '--lenient-timing'], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    progs.procs.append(sim)
    wait_until('arm 1 in mode 4 for 2 s', lambda: page(
        driver, "(window.axonC4g.state?.axes || []).filter((a) => a.mode === 4 && a.in_mode_s > 2).length") == 6,
        seconds=60)
    path = os.path.join(out, 'dashboard-c4g.png')
    driver.save_screenshot(path)
    return path


def main():
    a = parse()
    os.makedirs(a.out, exist_ok=True)
    tmp = tempfile.mkdtemp(prefix='axon-screenshots-')
    progs = Programs(tmp)
    driver = start_chromium()
    try:
        for shoot in (shoot_fps, shoot_fps_replay, shoot_blmc, shoot_c4g):
            print(shoot(a.axon, driver, progs, a.out), flush=True)
            progs.stop()
        return 0
    finally:
        driver.quit()
        progs.stop()
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == '__main__':
    sys.exit(main())
