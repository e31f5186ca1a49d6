"""The fps page of the host's view in headless Chromium: `axon fps plane --http 127.0.0.1:0 move`
driving the 500 robots of `axon sim fps --layout default`, one of which collides when it moves:
  1. the page says "host view" and draws all 500 robots at 5 updates a second or more;
  2. a click on a robot shows its status bits and how long ago it last answered the host;
  3. the collision turns the lock indicator on, naming the robot (the array's lock, from its report);
  4. the page's angles are the host's: every other robot where the host's reads put it.
Skips only when Chromium cannot start at all."""
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

from selenium.webdriver.common.by import By

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), 'helpers'))
from browser import click_robot, http_url, page, start_chromium, start_program, wait_until  # noqa: E402

AXON = sys.argv[1]
COLLIDER = 100  # robot that reports a collision the first time it moves


def start(tmp):
    with open(os.path.join(tmp, 'scenario.yaml'), 'w') as f:
        f.write('collide_on_move: [%d]\n' % COLLIDER)
    sim, _ = start_program([AXON, 'sim', 'fps', '--layout', 'default', '--folded', '--scenario', os.path.join(tmp, 'scenario.yaml'),
                            '--write-layout', os.path.join(tmp, 'live.yaml')], 'ready', stderr=subprocess.DEVNULL)
    host, lines = start_program([AXON, 'fps', 'plane', '--layout', os.path.join(tmp, 'live.yaml'), '--http', '127.0.0.1:0',
                                 '--http-linger', '60', 'move', '--alpha', '20', '--beta', '170', '--duration', '3'],
                                'listening http ', stderr=open(os.path.join(tmp, 'host.err'), 'w'))
    return sim, host, http_url(lines)


def check_page(driver):
    wait_until('500 robots drawn', lambda: page(driver, 'window.axonFps && window.axonFps.drawn.robots') == 500)
    assert 'host view' in driver.find_element(By.ID, 'title').text, driver.find_element(By.ID, 'title').text
    before = page(driver, 'window.axonFps.messages')
    time.sleep(2.0)
    rate = (page(driver, 'window.axonFps.messages') - before) / 2.0
    print('page: %.1f state updates/s for 500 robots (host view)' % rate)
    assert rate >= 5, 'only %.1f updates/s' % rate


def check_details(driver):
    click_robot(driver, 42)
    wait_until('a last reply', lambda: 's ago' in page(driver, "document.getElementById('details').textContent"))
    bits = page(driver, "document.getElementById('status-bits').textContent")
    assert 'DATUM_ALPHA_INITIALIZED' in bits, bits


def check_lock(driver):
    lock = driver.find_element(By.ID, 'lock')
    wait_until('the lock', lambda: lock.get_attribute('data-locked') == 'true', seconds=60.0)
    assert lock.get_attribute('data-robot') == str(COLLIDER), lock.get_attribute('data-robot')
    assert 'robot %d' % COLLIDER in lock.text, lock.text
    state = page(driver, 'window.axonFps.state')
    collider = [r for r in state['robots'] if r['id'] == COLLIDER][0]
    assert collider['s'] == 'collided', collider
    assert all(r['a'] is not None for r in state['robots']), 'a robot without angles'


def main():
    tmp = tempfile.mkdtemp()
    driver = start_chromium()
    sim = host = None
    try:
        sim, host, url = start(tmp)
        driver.get(url + '/fps.html')
        check_page(driver)
        check_details(driver)
        check_lock(driver)
        print('PASS')
    finally:
        driver.quit()
        for p in (host, sim):
            if p:
                p.send_signal(signal.SIGINT) if p is host else p.terminate()
                try:
                    p.wait(timeout=15)
                except subprocess.TimeoutExpired:
                    p.kill()
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == '__main__':
    main()
