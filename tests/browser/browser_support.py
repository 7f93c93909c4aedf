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


def viewer_state(driver):
    """What the viewer has drawn, as its element's data-* attributes say
    (viewer.js): None when no cloud is on screen."""
    d = driver.execute_script("return Object.assign({}, document.getElementById('viewer').dataset)")
    if not d.get("scanId"):
        return None
    return {"scanId": d["scanId"], "points": int(d["points"]), "total": int(d["total"]),
            "colourBy": d["colourBy"], "normals": d["normals"] == "true", "clearColour": d["clearColour"],
            "lod": {"fullFrameMs": float(d["fullFrameMs"]), "fullPoints": int(d["fullPoints"]),
                    "movingFrameMs": float(d["movingFrameMs"]), "movingPoints": int(d["movingPoints"])}}


def call_page(driver, module, function, *args):
    """Calls an exported function of one of the page's modules (the page's own
    instance: a module is loaded once per page) and waits for its promise."""
    error = driver.execute_async_script("""
        const [module, name, args, done] = arguments;
        import(module).then(m => m[name](...args)).then(() => done(null), e => done(String(e)));""",
                                        "/" + module, function, list(args))
    check(error is None, f"{module} {function}: {error}")
