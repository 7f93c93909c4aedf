"""The page's truth about the scanner, checked in the browser: replayed
events, a bad cloud, a reload's bytes, labels and live regions, a poor scan
started from the keyboard, a scan deleted elsewhere, the scanner killed and
stopped, no table (tests/browser/test_page.py runs them)."""

import json
import time
import urllib.request
from pathlib import Path

from browser_support import call_page, check, log, shown, text_of, viewer_state, wait_for


def api_send(base, token, method, path, body=None):
    data = json.dumps(body).encode() if body is not None else None
    request = urllib.request.Request(base + path, data=data, method=method)
    request.add_header("Authorization", "Bearer " + token)
    if data is not None:
        request.add_header("Content-Type", "application/json")
    with urllib.request.urlopen(request, timeout=30) as response:
        return response.status


ACCESSIBILITY_RULES = (Path(__file__).parent / "accessibility.js").read_text()


def check_accessibility(driver, where):
    """The page's accessibility in its state now (`where`): the rules of
    accessibility.js (WCAG A/AA checks in the manner of axe-core), and this
    page's own: its state and messages in live regions."""
    result = driver.execute_script("const result =\n" + ACCESSIBILITY_RULES + "\nreturn result;")
    problems = result["violations"] + driver.execute_script("""
        const out = [];
        for (const id of ['scan-status', 'scan-error', 'scan-quality', 'viewer-message', 'connection-banner'])
          if (!document.getElementById(id).matches('[aria-live], [role="alert"], [role="status"]'))
            out.push('live-region: #' + id + ' is not a live region');
        if (!document.getElementById('state').closest('[aria-live]')) out.push('live-region: the state is not live');
        return out;""")
    check(not problems, f"accessibility ({where}): {len(problems)} violation(s):\n  " + "\n  ".join(problems))
    c = result["contrast"]
    check(c["judged"] > 10, f"accessibility ({where}): contrast decided for {c['judged']} text elements only")
    log(f"accessibility ({where}): {len(result['rules']) + 1} rules, no violation; contrast of "
        f"{c['judged']} text elements, the lowest {c['lowest']:.1f}:1 (as normal text)")


def check_accessibility_checker(driver):
    """The checker finds what it should: a block with one fault per rule it
    can see in a fragment, put into the page and taken out again."""
    driver.execute_script("""
        const block = document.createElement('div');
        block.id = 'a11y-faults';
        block.innerHTML = `
          <h4>skips two levels</h4>
          <button></button>
          <a href="#x"></a>
          <img src="data:,">
          <input type="text">
          <span id="twice"></span><span id="twice"></span>
          <div role="buton">x</div>
          <div aria-live="loud">x</div>
          <p aria-labelledby="no-such-id">x</p>
          <div aria-hidden="true"><button>hidden but focusable</button></div>
          <button tabindex="3">ahead of order</button>
          <a href="#y"><button>inside a link</button></a>
          <ul><div>not an item</div></ul>
          <p id="a11y-grey">grey on white</p>`;
        document.querySelector('main').appendChild(block);
        // Through the CSSOM: the page's Content-Security-Policy drops style attributes.
        const grey = document.getElementById('a11y-grey');
        grey.style.color = '#999';
        grey.style.background = '#fff';""")
    try:
        result = driver.execute_script("const result =\n" + ACCESSIBILITY_RULES + "\nreturn result;")
    finally:
        driver.execute_script("document.getElementById('a11y-faults').remove()")
    expected = {"heading-order", "button-name", "link-name", "image-alt", "label", "duplicate-id",
                "aria-valid-role", "aria-live-value", "aria-valid-reference", "aria-hidden-focus",
                "tabindex", "nested-interactive", "list", "color-contrast"}
    found = {v.split(":")[0] for v in result["violations"]}
    check(expected <= found, f"the accessibility checker missed {sorted(expected - found)} in a block "
          f"made to fail them; it found: {result['violations']}")
    log(f"accessibility checker: {len(expected)} kinds of fault put into the page, each found")


def check_poor_scan(driver, base, token):
    """A scan at 100 us is written, flagged on the page with what to do, and
    started from the keyboard."""
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    check(api_send(base, token, "PUT", "/api/v1/settings", {"exposure_us": 100}) == 200, "exposure 100 us")
    button = driver.find_element(By.ID, "scan-button")
    driver.execute_script("arguments[0].focus()", button)
    check(driver.switch_to.active_element == button, "the Scan button takes the keyboard focus")
    button.send_keys(Keys.ENTER)
    quality = wait_for(driver, "the poor scan's warning",
                       lambda d: text_of(d, "scan-quality") if shown(d, "scan-quality") else None, timeout=180)
    check("Raise the exposure (now 100 us)" in quality, f"the warning says {quality!r}")
    log(f"poor scan (started with Enter): {quality!r}")
    scan_id = wait_for(driver, "the poor scan's row", lambda d: d.execute_script(
        "const r = document.querySelector('#scan-list tr.poor'); return r && r.dataset.scanId"), timeout=20)
    check(api_send(base, token, "PUT", "/api/v1/settings", {"exposure_us": 8000}) == 200, "exposure back")
    return scan_id


def check_deleted_elsewhere(driver, base, token, scan_id):
    """The scan on screen deleted through the API: its row and its cloud go."""
    call_page(driver, "cloud.js", "loadCloud", scan_id)
    wait_for(driver, f"{scan_id} on screen", lambda d: (lambda v: v and v["scanId"] == scan_id)(viewer_state(d)),
             timeout=30)
    check(api_send(base, token, "DELETE", f"/api/v1/scans/{scan_id}") == 204, "DELETE through the API")
    wait_for(driver, "the deleted scan to leave the page", lambda d: d.execute_script("""
        return !document.querySelector('#scan-list tr[data-scan-id="' + arguments[0] + '"]') &&
               document.getElementById('viewer-title').textContent === '' &&
               document.getElementById('viewer-message').textContent.includes('was deleted')""", scan_id)
             and viewer_state(d) is None, timeout=10)
    log(f"{scan_id} deleted through the API: its row and its cloud left the page")


def check_scanner_gone(driver, restart):
    """The scanner killed mid-scan (no `failed` event: a crash, a power cut)
    and stopped while idle, then back: the page says so at once, greys its
    actions, and ends right."""
    from selenium.webdriver.common.by import By

    driver.find_element(By.ID, "scan-button").click()
    wait_for(driver, "a scan under way", lambda d: d.execute_script(
        "return document.getElementById('progress').value >= 2"), timeout=30)
    began = time.monotonic()
    restart(lambda: wait_for(driver, "the banner", lambda d: shown(d, "connection-banner"), timeout=30),
            kill=True)
    log(f"scanner killed mid-scan: banner after {time.monotonic() - began:.1f} s: "
        f"{text_of(driver, 'connection-banner')!r}")
    wait_for(driver, "the page back", lambda d: not shown(d, "connection-banner")
             and text_of(d, "state") == "idle" and d.find_element(By.ID, "scan-button").is_enabled(), timeout=30)
    status = text_of(driver, "scan-status")
    check("did not finish" in status and driver.execute_script(
        "return document.getElementById('progress').value") == 0,
        f"after the restart the scan's line says {status!r}")
    check(not shown(driver, "scan-error"), f"a stale error stays: {text_of(driver, 'scan-error')!r}")
    log(f"scanner back: {status!r}, progress reset, no stale error")
    # While idle: the same, and Scan is off while it is away.
    restart(lambda: (wait_for(driver, "the banner", lambda d: shown(d, "connection-banner"), timeout=30),
                     check(not driver.find_element(By.ID, "scan-button").is_enabled(),
                           "Scan is enabled while the scanner is away"),
                     check_accessibility(driver, "the scanner away")))
    wait_for(driver, "the page back", lambda d: not shown(d, "connection-banner")
             and d.find_element(By.ID, "scan-button").is_enabled(), timeout=30)
    log("scanner stopped while idle and back: banner, Scan off while away, back on after")
    # Without a table: Scan off with a plain message and a link, on again
    # for a capture-only scan; with the table back, on again.
    restart(lambda: None, table_path="/nonexistent/table.fpt")
    message = wait_for(driver, "the no-table message", lambda d: text_of(d, "no-table")
                       if shown(d, "no-table") and not d.find_element(By.ID, "scan-button").is_enabled()
                       else None, timeout=30)
    check("No calibration table is installed" in message and driver.find_element(
        By.CSS_SELECTOR, "#no-table a[href='#table-section']"), f"the no-table message: {message!r}")
    driver.find_element(By.ID, "scan-capture").click()
    check(driver.find_element(By.ID, "scan-button").is_enabled(), "Scan stays off for a capture-only scan")
    driver.find_element(By.ID, "scan-capture").click()
    log(f"no table: Scan off, {message!r}; on for a capture-only scan")
    check_accessibility(driver, "no table")
    restart(lambda: None)
    wait_for(driver, "the table back", lambda d: not shown(d, "no-table")
             and d.find_element(By.ID, "scan-button").is_enabled(), timeout=30)


CHECKERBOARD_YAML = "format: fpp-board/1\nkind: checkerboard\ninner_corners: [13, 9]\nsquare_size: 10.0\n"


def check_controls(driver, table):
    """The page's other controls, each through its form: the exposure, the
    live preview beside Scan, a table upload, and the calibration helper (a
    session made, a pose taken, its thumbnail shown)."""
    from selenium.webdriver.common.by import By

    field = driver.find_element(By.ID, "exposure")
    for exposure in ("9000", "8000"):
        field.clear()
        field.send_keys(exposure)
        driver.find_element(By.CSS_SELECTOR, "#settings-form button[type=submit]").click()
        wait_for(driver, f"exposure {exposure}", lambda d: f"Exposure now {exposure} µs" in text_of(d, "settings-message"),
                 timeout=20)
    log(f"exposure set from the page: {text_of(driver, 'settings-message')!r}")
    driver.find_element(By.ID, "scan-preview-on").click()
    info = wait_for(driver, "the live preview beside Scan", lambda d: text_of(d, "scan-preview-info")
                    if "mean level" in text_of(d, "scan-preview-info") and d.execute_script(
                        "return document.getElementById('scan-preview').naturalWidth > 0") else None, timeout=20)
    driver.find_element(By.ID, "scan-preview-on").click()
    log(f"live preview beside Scan: {info!r}")
    driver.find_element(By.ID, "table-file").send_keys(str(table))
    driver.find_element(By.ID, "table-upload").click()
    installed = wait_for(driver, "the table installed", lambda d: text_of(d, "table-message")
                         if text_of(d, "table-message").startswith("Installed") else None, timeout=60)
    log(f"table uploaded from the page: {installed[:90]!r}...")
    driver.find_element(By.CSS_SELECTOR, "#calibration summary").click()
    driver.find_element(By.ID, "session-name").send_keys("page-session")
    driver.find_element(By.ID, "board-yaml").send_keys(CHECKERBOARD_YAML)
    driver.find_element(By.ID, "session-create").click()
    wait_for(driver, "the new session selected", lambda d: d.execute_script(
        "return document.getElementById('session-select').value") == "page-session"
        and d.find_element(By.ID, "take-pose").is_enabled(), timeout=20)
    driver.find_element(By.ID, "take-pose").click()
    wait_for(driver, "the pose and its thumbnail", lambda d: text_of(d, "pose-count") == "1" and d.execute_script(
        "const i = document.querySelector('#poses img'); return !!i && i.naturalWidth > 0"), timeout=60)
    preview = wait_for(driver, "the helper's preview", lambda d: text_of(d, "preview-info")
                       if "mean level" in text_of(d, "preview-info") else None, timeout=20)
    log(f"calibration helper: session page-session made, a pose taken and its thumbnail shown; "
        f"{text_of(driver, 'session-message')!r}, preview {preview!r}")
    driver.find_element(By.CSS_SELECTOR, "#calibration summary").click()


def check_replayed_events(driver, scan_id):
    """Events repeated after a reconnect, or out of order, leave the page
    where the scanner is."""
    before = driver.execute_script("""
        const p = document.getElementById('progress');
        return [document.getElementById('scan-status').textContent, p.value, p.max];""")
    driver.execute_async_script("""
        const [id, done] = arguments;
        import('/events.js').then(events => {
        const send = (n, d) => events.handleEvent(n, JSON.stringify(d));
        send('scan-started', {id: id, mode: 'scan', frames: 17, source: 'api', session: null});
        send('frame-captured', {id: id, frame: 3, frames: 17});
        send('decoded', {id: id});
        send('written', {id: id, mode: 'scan', points: 1, quality: null, session: null});
        send('state', {state: 'idle', error: null});
        done(); });""", scan_id)
    after = driver.execute_script("""
        const p = document.getElementById('progress');
        return [document.getElementById('scan-status').textContent, p.value, p.max];""")
    check(after == before, f"replayed events changed the page: {before} -> {after}")
    log(f"events of {scan_id} replayed: the page stays at {after[0]!r}")


def check_bad_cloud(driver, store, scan_id):
    """A truncated PLY on the scanner: the viewer says so; the page goes on."""
    from selenium.webdriver.common.by import By

    ply = Path(store) / scan_id / "cloud.ply"
    data = ply.read_bytes()
    ply.write_bytes(data[:len(data) // 2])
    try:
        call_page(driver, "cloud.js", "loadCloud", scan_id)
        message = wait_for(driver, "the viewer's message", lambda d: text_of(d, "viewer-message")
                           if "Cannot show" in text_of(d, "viewer-message") else None, timeout=20)
        check("shorter" in message and viewer_state(driver) is None,
              f"a truncated PLY: {message!r}")
        check(driver.find_element(By.ID, "scan-button").is_enabled(), "Scan is off after a bad cloud")
        log(f"truncated PLY: {message!r}; the page stays usable")
    finally:
        ply.write_bytes(data)


def check_reload_transfer(driver):
    """A second load of the page: three.js from the cache, the page's files
    revalidated (304): under 50 KB over the wire."""
    driver.refresh()
    wait_for(driver, "the page loaded again", lambda d: d.execute_script(
        "return document.readyState === 'complete' && !!document.querySelector('#viewer canvas')"), timeout=30)
    # The page's own files (the API's answers, a cloud among them, are data).
    total, parts = driver.execute_script("""
        const entries = performance.getEntriesByType('navigation').concat(performance.getEntriesByType('resource'))
          .filter(e => !new URL(e.name).pathname.startsWith('/api/'));
        return [entries.reduce((s, e) => s + (e.transferSize || 0), 0),
                entries.map(e => e.name.replace(location.origin, '') + ' ' + e.transferSize)];""")
    log(f"second load: the page's files {total} bytes over the wire ({', '.join(parts)})")
    check(total < 50 * 1024, f"a second load transferred {total} bytes: {parts}")
