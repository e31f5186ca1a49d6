"""What the browser tests (tests/integration/web_*.py) share: headless Chromium through Selenium
(Debian's chromium, chromium-driver and python3-selenium), and waiting for a condition."""
import shutil
import sys
import time

from selenium import webdriver
from selenium.webdriver.chrome.service import Service


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
