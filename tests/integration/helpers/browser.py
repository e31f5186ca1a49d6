"""What the browser tests (tests/integration/web_*.py) and scripts/screenshots.py share: headless
Chromium through Selenium (Debian's chromium, chromium-driver and python3-selenium), starting an axon
program and reading its address, waiting for a condition, clicking a robot on the fps page."""
import shutil
import subprocess
import sys
import time

from selenium import webdriver
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.common.by import By


def start_chromium():
    """A headless Chromium; when none can start at all the test has nothing to check: SKIP, exit 0."""
    options = webdriver.ChromeOptions()
    for arg in ('--headless=new', '--no-sandbox', '--disable-gpu', '--disable-dev-shm-usage', '--window-size=1400,1000'):
        options.add_argument(arg)
    options.binary_location = shutil.which('chromium') or '/usr/bin/chromium'
    try:
        return webdriver.Chrome(service=Service(shutil.which('chromedriver') or '/usr/bin/chromedriver'), options=options)
    except Exception as e:  # no browser at all: nothing this test can check
        print('SKIP: chromium cannot start: %s' % str(e).splitlines()[0])
        sys.exit(0)


def wait_until(what, check, seconds=20.0, step=0.02):
    """check()'s first true value, polled every `step` s; AssertionError naming `what` after `seconds`."""
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        value = check()
        if value:
            return value
        time.sleep(step)
    raise AssertionError('timed out waiting for ' + what)


def page(driver, expression):
    """The value of a JavaScript expression in the page."""
    return driver.execute_script('return ' + expression)


def start_program(args, until, stderr=None):
    """Starts `args` with stdout a pipe and reads its lines up to the first that starts with `until`
    ('ready', 'listening http '); returns (process, the lines read). AssertionError, naming the
    program, if it ends before."""
    p = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=stderr, text=True)
    lines = []
    for line in p.stdout:
        lines.append(line.rstrip('\n'))
        if line.startswith(until):
            return p, lines
    p.wait()
    raise AssertionError('%s ended (exit %s) before printing %r' % (' '.join(args[:3]), p.returncode, until))


def http_url(lines):
    """'http://HOST:PORT' from the 'listening http HOST:PORT' line among a program's `lines`."""
    found = [l.split()[2] for l in lines if l.startswith('listening http ')]
    assert found, 'no "listening http" line in %r' % lines[-5:]
    return 'http://' + found[0]


def click_robot(driver, robot):
    """Clicks robot `robot` on the fps page's canvas and waits until the details panel shows it."""
    spot = page(driver, 'window.axonFps.robotOnCanvas(%d)' % robot)
    canvas = driver.find_element(By.ID, 'plane')
    size = canvas.size
    ActionChains(driver).move_to_element_with_offset(canvas, spot['x'] - size['width'] / 2,
                                                     spot['y'] - size['height'] / 2).click().perform()
    # The details panel is rebuilt with every state update (10 a second): read it in one script
    # call each time, never through an element reference an update may have replaced.
    wait_until('details of robot %d' % robot,
               lambda: page(driver, "document.getElementById('details').dataset.robot") == str(robot))
