"""The fps page in headless Chromium (Debian's chromium, chromium-driver and python3-selenium) against
`axon sim fps --layout default --http 127.0.0.1:0`, driven by the axon CLI as a user would:
  1. the page draws all 500 robots and gets state updates at 5 Hz or more;
  2. a click on a robot shows its decoded status bits;
  3. an injected collision (the scenario's collide_on_move, set off by a go-to of that robot) turns
     the lock indicator on within a second of the simulator's state showing it, naming the robot;
     `axon fps unlock` turns it off;
  4. a move of every robot (`axon fps plane move`) animates on the page (angles between start and
     target seen while it runs) and the page's angles end at the targets.
Skips only when Chromium cannot start at all."""
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import urllib.request

from selenium.webdriver.common.by import By

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), 'helpers'))
from browser import click_robot, http_url, page, start_chromium, start_program, wait_until  # noqa: E402

AXON = sys.argv[1]
COLLIDER = 100          # robot that reports a collision the first time it moves
TARGET = (20.0, 170.0)  # where the move takes every robot
TOLERANCE_DEG = 0.5     # page angles (the simulator's physical ones) against the commanded target


def start_sim(tmp):
    scenario = os.path.join(tmp, 'scenario.yaml')
    with open(scenario, 'w') as f:
        f.write('collide_on_move: [%d]\n' % COLLIDER)
    err = open(os.path.join(tmp, 'sim.err'), 'w')
    sim, lines = start_program([AXON, 'sim', 'fps', '--layout', 'default', '--folded', '--http', '127.0.0.1:0', '--scenario', scenario,
                                '--write-layout', os.path.join(tmp, 'live.yaml')], 'ready', stderr=err)
    return sim, http_url(lines)


def gateway_of(layout_file, robot):
    """The --gateway HOST:PORT and --channels of `robot` in the written layout."""
    text = open(layout_file).read()
    r = re.search(r'- \{id: %d, [^}]*gateway: (\d+), bus: (\d+)' % robot, text)
    g = re.search(r'- \{id: %s, address: "([^"]+)"' % r.group(1), text)
    return ['--gateway', g.group(1), '--channels', r.group(2)]


def api_state(url):
    with urllib.request.urlopen(url + '/api/fps/state', timeout=5) as r:
        return json.load(r)


def check_draws_every_robot(driver):
    wait_until('500 robots drawn', lambda: page(driver, 'window.axonFps && window.axonFps.drawn.robots') == 500)
    assert driver.find_element(By.ID, 'robot-count').text == '500'
    before = page(driver, 'window.axonFps.messages')
    time.sleep(2.0)
    rate = (page(driver, 'window.axonFps.messages') - before) / 2.0
    print('page: %.1f state updates/s for 500 robots' % rate)
    assert rate >= 5, 'only %.1f updates/s' % rate


def check_click_shows_status(driver):
    click_robot(driver, 42)
    bits = page(driver, "document.getElementById('status-bits').textContent")
    for name in ('SYSTEM_INITIALIZATION', 'DATUM_ALPHA_INITIALIZED', 'DATUM_BETA_INITIALIZED', 'DISPLACEMENT_COMPLETED'):
        assert name in bits, (name, bits)
    assert '04.01.13' in page(driver, "document.getElementById('details').textContent")


def check_collision_lock(driver, url, tmp):
    bus = gateway_of(os.path.join(tmp, 'live.yaml'), COLLIDER)
    lock = driver.find_element(By.ID, 'lock')
    assert lock.get_attribute('data-locked') == 'false'
    goto = subprocess.Popen([AXON, 'fps'] + bus + ['goto', str(COLLIDER), '60', '150'],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    seen_by_sim = wait_until('the simulator to lock', lambda: api_state(url)['lock']['locked'] and time.monotonic())
    seen_by_page = wait_until('the page to lock', lambda: lock.get_attribute('data-locked') == 'true' and time.monotonic(),
                              seconds=5.0)
    print('page: lock shown %.0f ms after the simulator had it' % (1000 * (seen_by_page - seen_by_sim)))
    assert seen_by_page - seen_by_sim < 1.0
    assert lock.get_attribute('data-robot') == str(COLLIDER)
    assert 'robot %d' % COLLIDER in lock.text, lock.text
    goto.wait(timeout=30)
    subprocess.run([AXON, 'fps'] + bus + ['unlock'], check=True, capture_output=True, timeout=30)
    wait_until('the lock to go off', lambda: lock.get_attribute('data-locked') == 'false', seconds=5.0)


def check_move_animates(driver, tmp):
    starts = {r['id']: r['a'] for r in page(driver, 'window.axonFps.state.robots')}
    # A robot whose alpha has far to go shows the motion best.
    watched = max(starts, key=lambda i: abs(starts[i] - TARGET[0]))
    move = subprocess.Popen([AXON, 'fps', 'plane', '--layout', os.path.join(tmp, 'live.yaml'), 'move',
                             '--alpha', str(TARGET[0]), '--beta', str(TARGET[1]), '--duration', '3'],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    seen = set()
    drawn = set()
    while move.poll() is None:
        robot = page(driver, 'window.axonFps.state.robots.find((r) => r.id === %d)' % watched)
        seen.add(round(robot['a'], 1))
        drawn.add(page(driver, 'window.axonFps.drawn.seq'))
        time.sleep(0.05)
    out, err = move.communicate()
    assert move.returncode == 0, (move.returncode, out, err)
    lo, hi = sorted((starts[watched], TARGET[0]))
    between = [a for a in seen if lo + 1 < a < hi - 1]
    print('page: robot %d alpha %.1f -> %.1f, %d values between seen, %d frames drawn' %
          (watched, starts[watched], TARGET[0], len(between), len(drawn)))
    assert len(between) >= 3, sorted(seen)

    def at_targets():
        robots = page(driver, 'window.axonFps.state.robots')
        off = [r for r in robots if abs(r['a'] - TARGET[0]) > TOLERANCE_DEG or abs(r['b'] - TARGET[1]) > TOLERANCE_DEG]
        return len(robots) == 500 and not off
    wait_until('every robot at its target on the page', at_targets, seconds=10.0)


def main():
    tmp = tempfile.mkdtemp()
    driver = start_chromium()
    sim = None
    try:
        sim, url = start_sim(tmp)
        driver.get(url + '/fps.html')
        check_draws_every_robot(driver)
        check_click_shows_status(driver)
        check_collision_lock(driver, url, tmp)
        check_move_animates(driver, tmp)
        print('PASS')
    finally:
        driver.quit()
        if sim:
            sim.terminate()
            sim.wait(timeout=10)
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == '__main__':
    main()
