"""Replaying a plan file on the fps page, in headless Chromium (Debian's chromium, chromium-driver and
python3-selenium) against `axon sim fps --layout default --http 127.0.0.1:0`:
  1. `axon fps plan --layout default ... -o plan.json` writes a 500-robot plan; the page's file
     input loads it and says it replays the file, not the live state;
  2. at the plan's end (the slider's End key) every robot is drawn at its arms' last points, and
     stays so while live state keeps arriving;
  3. half-way through, a robot in the middle of a turn is drawn at the linear interpolation between
     its points, computed here from the file;
  4. play at x10 advances the time about ten times as fast as the clock and stops at the end;
  5. "back to live" draws the simulator's angles again;
  6. a plan with a robot the layout does not have lists it; a file that is no plan is an error.
Skips only when Chromium cannot start at all."""
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

from selenium.webdriver.common.by import By
from selenium.webdriver.common.keys import Keys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), 'helpers'))
from browser import http_url, page, start_chromium, start_program, wait_until  # noqa: E402

AXON = sys.argv[1]
TOLERANCE_DEG = 0.01  # the page's drawn angles against the plan's points
EXTRA_ROBOT = 9001    # a robot id the default layout does not have


def make_plan(tmp):
    path = os.path.join(tmp, 'plan.json')
    run = subprocess.run([AXON, 'fps', 'plan', '--layout', 'default', '--to', 'random', '--seed', '5', '-o', path,
                          '--allow-partial'], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, (run.returncode, run.stderr)
    with open(path) as f:
        plan = json.load(f)
    assert len(plan['robots']) == 500
    return path, plan


def start_sim(tmp):
    err = open(os.path.join(tmp, 'sim.err'), 'w')
    sim, lines = start_program([AXON, 'sim', 'fps', '--layout', 'default', '--folded', '--http', '127.0.0.1:0'], 'ready',
                               stderr=err)
    return sim, http_url(lines)


def angle_at(points, t):
    """The angle of [deg, s] points at t: linear in between, held before the first and after the last."""
    if t <= points[0][1]:
        return points[0][0]
    if t >= points[-1][1]:
        return points[-1][0]
    for (d0, t0), (d1, t1) in zip(points, points[1:]):
        if t0 <= t < t1:
            return d0 + (d1 - d0) * (t - t0) / (t1 - t0)
    raise AssertionError('unreachable')


def duration_of(plan):
    return max([plan.get('duration_s', 0)] + [r[arm][-1][1] for r in plan['robots'] for arm in ('alpha', 'beta')])


def drawn(driver):
    return page(driver, 'window.axonFps.drawn')


def check_loads(driver, path, plan):
    driver.find_element(By.ID, 'plan-file').send_keys(path)
    wait_until('the plan replayed', lambda: drawn(driver)['source'] == 'replay')
    banner = driver.find_element(By.ID, 'replay-banner')
    assert banner.is_displayed() and banner.get_attribute('data-replaying') == 'true'
    assert banner.text == 'replaying plan plan.json (not live)', banner.text
    shown = float(driver.find_element(By.ID, 'replay-duration').text)
    assert abs(shown - duration_of(plan)) < 0.006, (shown, duration_of(plan))
    assert drawn(driver)['robots'] == 500
    assert page(driver, 'window.axonFps.replay.missing.length') == 0
    print('page: plan of %d robots loaded, %.2f s' % (len(plan['robots']), shown))


def check_end(driver, plan):
    driver.find_element(By.ID, 'replay-slider').send_keys(Keys.END)
    end = duration_of(plan)
    wait_until('the end drawn', lambda: drawn(driver)['t'] == end)
    last = {r['id']: (r['alpha'][-1][0], r['beta'][-1][0]) for r in plan['robots']}

    def off_of(angles):
        return [(i, a, b, last[i]) for i, a, b in angles
                if abs(a - last[i][0]) > TOLERANCE_DEG or abs(b - last[i][1]) > TOLERANCE_DEG]
    d = drawn(driver)
    assert len(d['angles']) == 500 and {a[0] for a in d['angles']} == set(last)
    off = off_of(d['angles'])
    assert not off, off[:5]
    assert float(driver.find_element(By.ID, 'replay-time').text) == round(end, 2)
    # Live state keeps arriving while replaying; the drawing stays the plan's.
    before = page(driver, 'window.axonFps.messages')
    wait_until('live updates', lambda: page(driver, 'window.axonFps.messages') >= before + 3)
    d = drawn(driver)
    assert d['source'] == 'replay' and d['seq'] > 0 and not off_of(d['angles'])
    print('page: at the end (%.2f s) all 500 robots drawn at their last points' % end)


def check_middle(driver, plan):
    mid = duration_of(plan) / 2
    # A robot whose alpha turns across the middle: its drawn angle is neither end of the segment.
    robot, arm = None, None
    for r in plan['robots']:
        for name in ('alpha', 'beta'):
            for (d0, t0), (d1, t1) in zip(r[name], r[name][1:]):
                if t0 + 1 < mid < t1 - 1 and abs(d1 - d0) > 5:
                    robot, arm = r, name
        if robot:
            break
    assert robot, 'no robot turns across the middle of the plan'
    page(driver, "(() => { const s = document.getElementById('replay-slider'); s.value = String(%r);"
                 " s.dispatchEvent(new Event('input')); })()" % mid)
    wait_until('the middle drawn', lambda: drawn(driver)['t'] is not None and abs(drawn(driver)['t'] - mid) < 1e-6)
    d = drawn(driver)
    t = d['t']
    got = {i: (a, b) for i, a, b in d['angles']}[robot['id']]
    want = (angle_at(robot['alpha'], t), angle_at(robot['beta'], t))
    assert abs(got[0] - want[0]) <= TOLERANCE_DEG and abs(got[1] - want[1]) <= TOLERANCE_DEG, (robot['id'], t, got, want)
    ends = [p[0] for p in robot[arm]]
    value = got[0] if arm == 'alpha' else got[1]
    assert all(abs(value - e) > 0.5 for e in ends), (value, ends)
    print('page: robot %d at %.3f s drawn at alpha %.3f beta %.3f, interpolated from the file %.3f %.3f' %
          (robot['id'], t, got[0], got[1], want[0], want[1]))


def check_play(driver, plan):
    slider = driver.find_element(By.ID, 'replay-slider')
    slider.send_keys(Keys.HOME)
    wait_until('time 0 drawn', lambda: drawn(driver)['t'] == 0)
    driver.find_element(By.CSS_SELECTOR, '#replay-speeds button[data-speed="10"]').click()
    assert page(driver, 'window.axonFps.replay.speed') == 10
    play = driver.find_element(By.ID, 'replay-play')
    play.click()
    start = time.monotonic()
    time.sleep(1.0)
    t = page(driver, 'window.axonFps.replay.t')
    wall = time.monotonic() - start
    rate = t / wall
    print('page: x10 play advanced %.2f s of plan in %.2f s' % (t, wall))
    assert page(driver, 'window.axonFps.replay.playing') is True and play.text == 'pause'
    assert 5 < rate < 12, rate
    wait_until('drawn while playing', lambda: (drawn(driver)['t'] or 0) > t)
    end = duration_of(plan)
    wait_until('play to stop at the end', lambda: not page(driver, 'window.axonFps.replay.playing'),
               seconds=end / 10 + 10)
    assert page(driver, 'window.axonFps.replay.t') == end and play.text == 'play'
    wait_until('the end drawn', lambda: drawn(driver)['t'] == end)
    # Pause holds the time.
    slider.send_keys(Keys.HOME)
    play.click()
    time.sleep(0.3)
    play.click()
    held = page(driver, 'window.axonFps.replay.t')
    time.sleep(0.3)
    assert 0 < held < end and page(driver, 'window.axonFps.replay.t') == held, held


def check_back_to_live(driver):
    driver.find_element(By.ID, 'replay-live').click()
    wait_until('live drawing', lambda: drawn(driver)['source'] == 'live')
    assert not driver.find_element(By.ID, 'replay-banner').is_displayed()
    before = page(driver, 'window.axonFps.seq')
    wait_until('a live frame drawn', lambda: drawn(driver)['seq'] > before)
    live = {r['id']: (r['a'], r['b']) for r in page(driver, 'window.axonFps.state.robots')}
    d = drawn(driver)
    assert d['robots'] == 500 and d['t'] is None
    # The folded simulator's arms (no plan angles) are what is drawn.
    off = [(i, a, b) for i, a, b in d['angles'] if abs(a - live[i][0]) > 0.5 or abs(b - live[i][1]) > 0.5]
    assert not off, off[:5]


def check_extra_robot_and_bad_file(driver, tmp, plan):
    extra = dict(plan)
    copy = dict(plan['robots'][0])
    copy['id'] = EXTRA_ROBOT
    extra['robots'] = plan['robots'] + [copy]
    path = os.path.join(tmp, 'plan-extra.json')
    with open(path, 'w') as f:
        json.dump(extra, f)
    driver.find_element(By.ID, 'plan-file').send_keys(path)
    wait_until('the extra robot listed', lambda: page(driver, 'window.axonFps.replay.missing').__eq__([EXTRA_ROBOT]))
    missing = driver.find_element(By.ID, 'replay-missing')
    assert missing.is_displayed() and str(EXTRA_ROBOT) in missing.text and 'not in this layout' in missing.text, missing.text
    assert 'replaying plan plan-extra.json' in driver.find_element(By.ID, 'replay-banner').text
    wait_until('500 robots drawn', lambda: drawn(driver)['robots'] == 500 and drawn(driver)['source'] == 'replay')
    bad = os.path.join(tmp, 'state.json')
    with open(bad, 'w') as f:
        json.dump({'robots': []}, f)
    driver.find_element(By.ID, 'plan-file').send_keys(bad)
    error = driver.find_element(By.ID, 'replay-error')
    wait_until('the bad file refused', lambda: error.is_displayed() and 'not an axon fps plan' in error.text)
    assert 'plan-extra.json' in driver.find_element(By.ID, 'replay-banner').text  # the last good plan stays


def main():
    tmp = tempfile.mkdtemp()
    driver = start_chromium()
    sim = None
    try:
        path, plan = make_plan(tmp)
        sim, url = start_sim(tmp)
        driver.get(url + '/fps.html')
        wait_until('500 robots drawn live', lambda: page(driver, 'window.axonFps && window.axonFps.drawn.robots') == 500)
        check_loads(driver, path, plan)
        check_end(driver, plan)
        check_middle(driver, plan)
        check_play(driver, plan)
        check_back_to_live(driver)
        check_extra_robot_and_bad_file(driver, tmp, plan)
        print('PASS')
    finally:
        driver.quit()
        if sim:
            sim.terminate()
            sim.wait(timeout=10)
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == '__main__':
    main()
