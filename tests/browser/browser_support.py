"""What the page's browser test and its state checks share: failures, the
log with its clock, and waiting on the page (tests/browser/test_page.py)."""

import time

START = time.monotonic()


class Failure(Exception):
    pass


def log(message):
    print(f"[{time.monotonic() - START:6.1f} s] {message}", flush=True)


def check(condition, message):
    if not condition:
        raise Failure(message)


def wait_for(driver, what, condition, timeout=30, poll=0.05):
    from selenium.common.exceptions import TimeoutException
    from selenium.webdriver.support.ui import WebDriverWait

    try:
        return WebDriverWait(driver, timeout, poll_frequency=poll).until(condition)
    except TimeoutException:
        raise Failure(f"timed out after {timeout} s waiting for {what}") from None


def text_of(driver, element_id):
    return driver.execute_script(f"return document.getElementById('{element_id}').textContent")


def shown(driver, element_id):
    return driver.execute_script(
        f"const e = document.getElementById('{element_id}'); return !e.hidden && e.offsetParent !== null")
