#!/usr/bin/python3
"""fpp-scanner's web page (firmware/scanner/web) in a real browser.

Debian's chromium, headless, driven through Debian's chromedriver by
python3-selenium: the page takes the token (a wrong one shows the 401
message), scans (the progress bar follows the server-sent events to
`written`), draws the cloud with WebGL (the canvas read back must show the
cloud), lays out in one column on a phone, and downloads the PLY through its
link byte for byte.

Either against a scanner someone else started:
    test_page.py --url http://HOST:PORT --token-file FILE [--store DIR]
or it starts one itself on the simulated board, with a table it makes the
way a person does (README, "Calibrating a scanner": the scanner records a
checkerboard session in capture mode, fpp-calib calibrates it), the camera
binned 4 x 4 to keep that to seconds:
    test_page.py --scanner fpp-scanner --calib fpp-calib [--binning 2]

Exit status: 0 passed, 1 failed, 77 skipped (chromium, chromedriver or
selenium missing; with CI=true that is a failure). Runs with /usr/bin/python3
(Debian's selenium); standard library otherwise.
"""

import argparse
import hashlib
import json
import math
import os
import re
import secrets
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
import urllib.error
import urllib.request
from pathlib import Path

from browser_support import START, Failure, check, log, shown, text_of, viewer_state, wait_for
from page_states import (check_accessibility, check_accessibility_checker, check_bad_cloud,
                         check_controls, check_deleted_elsewhere, check_poor_scan, check_reload_transfer,
                         check_replayed_events, check_scanner_gone)

SOURCE_DIR = Path(__file__).resolve().parents[2]
TEST_NAME = "Browser.PageScansAndDrawsTheCloud"
EXIT_SKIP = 77
CHROME_ARGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--disable-default-apps", "--disable-extensions", "--no-default-browser-check",
    # WebGL on the CPU: SwiftShader through ANGLE (headless has no GPU).
    "--use-gl=angle", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
    "--window-size=1280,1100",
]


def skip(reason):
    if os.environ.get("CI") == "true":
        raise Failure(f"(CI, where every tool must be installed) {reason}")
    print(f"{TEST_NAME}: SKIPPED: {reason}", flush=True)
    sys.exit(EXIT_SKIP)


def parse_args():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--url", help="a running scanner's base URL (then --token-file is needed)")
    p.add_argument("--token-file", help="the running scanner's token file")
    p.add_argument("--store", help="the running scanner's scan store, to compare the download with")
    p.add_argument("--scanner", help="fpp-scanner to start (when no --url)")
    p.add_argument("--calib", help="fpp-calib, to make the table (when no --url and no --table)")
    p.add_argument("--table", help="a table for the simulated board instead of calibrating one")
    p.add_argument("--binning", type=int, choices=(2, 4), default=4,
                   help="camera binning of the simulated board (2: board/sim.yaml as it is; "
                        "4: the same binned 4 x 4, the default, a quicker calibration)")
    p.add_argument("--web-root", default=str(SOURCE_DIR / "firmware/scanner/web"))
    p.add_argument("--artifacts", help="folder for screenshots and logs")
    p.add_argument("--chromium", default=shutil.which("chromium") or "/usr/bin/chromium")
    p.add_argument("--chromedriver", default=shutil.which("chromedriver") or "/usr/bin/chromedriver")
    p.add_argument("--keep", action="store_true", help="keep the temporary folder")
    args = p.parse_args()
    if args.url and not args.token_file:
        p.error("--url needs --token-file")
    if not args.url and not args.scanner:
        p.error("give --url and --token-file, or --scanner")
    if not args.url and not args.table and not args.calib:
        p.error("a started scanner needs --calib (to make its table) or --table")
    return args


def require_tools(args):
    for tool in (args.chromium, args.chromedriver):
        if not (os.path.isfile(tool) and os.access(tool, os.X_OK)):
            skip(f"{tool} not installed (apt-get install chromium chromium-driver)")
    try:
        import selenium  # noqa: F401
    except ImportError:
        skip(f"selenium not importable by {sys.executable} (apt-get install python3-selenium)")


# ---- the scanner ----------------------------------------------------------


def run(command, log_file, what):
    log(f"{what}: {' '.join(map(str, command))}")
    began = time.monotonic()
    with open(log_file, "ab") as out:
        result = subprocess.run(list(map(str, command)), stdout=out, stderr=subprocess.STDOUT)
    if result.returncode != 0:
        tail = Path(log_file).read_text(errors="replace")[-3000:]
        raise Failure(f"{what} exited with {result.returncode}; its output ends:\n{tail}")
    log(f"{what}: done in {time.monotonic() - began:.1f} s")


def board_file(name, binning, work):
    """A board file of board/: as it is at binning 2, else binned with its
    rig path made absolute (it was relative to board/)."""
    original = SOURCE_DIR / "board" / name
    if binning == 2:
        return original
    text = original.read_text()
    for old, new in (("binning: 2", f"binning: {binning}"),
                     ("rig: sim/", f"rig: {SOURCE_DIR / 'board/sim'}/")):
        check(old in text, f"{original}: no '{old}' to replace")
        text = text.replace(old, new, 1)
    path = work / f"{binning}x-{name}"
    path.write_text(text)
    return path


def make_table(args, work, logs):
    """The table for the simulated board, as README's "Calibrating a
    scanner" makes it: 30 capture-mode poses of the checkerboard, calibrated."""
    session = work / "session"
    run([args.scanner, "--board", board_file("sim-checkerboard-session.yaml", args.binning, work),
         "--mode", "capture", "--scans", "30", "--store", session],
        logs / "calibration.log", "record the checkerboard session")
    table = work / "table.fpt"
    run([args.calib, "calibrate", session, "--out", work / "calib.yaml", "--table", table],
        logs / "calibration.log", "fpp-calib calibrate")
    return table


def die_with_parent():
    """In the child before exec: SIGTERM when this test dies, even by SIGKILL
    (a ctest timeout), so that no scanner outlives it."""
    import ctypes
    PR_SET_PDEATHSIG = 1
    ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGTERM)


class Daemon:
    """fpp-scanner serving the API; its output goes to daemon.log."""

    LISTENING = re.compile(r"info: http: listening on (\S+):(\d+)")

    def __init__(self, command, log_path):
        log("start the scanner: " + " ".join(map(str, command)))
        self.log_file = open(log_path, "w", buffering=1)
        self.port = None
        self.found = threading.Event()
        self.process = subprocess.Popen(list(map(str, command)), stdout=self.log_file,
                                        stderr=subprocess.PIPE, text=True, errors="replace",
                                        preexec_fn=die_with_parent)
        self.reader = threading.Thread(target=self._read_stderr, daemon=True)
        self.reader.start()

    def _read_stderr(self):
        for line in self.process.stderr:
            self.log_file.write(line)
            match = self.LISTENING.search(line)
            if match and not self.found.is_set():
                self.port = int(match.group(2))
                self.found.set()

    def wait_listening(self, timeout=60):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.found.wait(0.1):
                return self.port
            if self.process.poll() is not None:
                break
        self.reader.join(2)
        tail = Path(self.log_file.name).read_text(errors="replace")[-3000:]
        state = f"exited with {self.process.returncode}" if self.process.poll() is not None else "still silent"
        raise Failure(f"the scanner did not log 'info: http: listening on ...' ({state}); its log ends:\n{tail}")

    def stop(self, kill=False):
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGKILL if kill else signal.SIGTERM)
            try:
                self.process.wait(20)
            except subprocess.TimeoutExpired:
                log("the scanner ignored SIGTERM for 20 s: killed")
                self.process.kill()
                self.process.wait()
        self.reader.join(5)
        self.log_file.close()
        return self.process.returncode


def write_token(path):
    token = secrets.token_urlsafe(32)
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "w") as f:
        f.write(token + "\n")
    return token


def api_get(base, path, token):
    request = urllib.request.Request(base + path)
    if token is not None:
        request.add_header("Authorization", "Bearer " + token)
    with urllib.request.urlopen(request, timeout=30) as response:
        return response.status, dict(response.headers), response.read()


def check_server_basics(base, token):
    """What the page relies on: its files need no token, the API does."""
    for path in ("/", "/app.js", "/session.js", "/viewer.js", "/style.css", "/three/build/three.min.js",
                 "/three/examples/js/controls/OrbitControls.js"):
        try:
            status, _, body = api_get(base, path, None)
        except urllib.error.HTTPError as e:
            raise Failure(f"GET {path} without a token: {e.code} {e.reason}; expected 200 (the page's files)") from None
        check(status == 200 and body, f"GET {path} without a token: {status}, {len(body)} bytes; expected 200")
    try:
        api_get(base, "/api/v1/status", None)
        raise Failure("GET /api/v1/status without a token answered 200; expected 401")
    except urllib.error.HTTPError as e:
        check(e.code == 401, f"GET /api/v1/status without a token: {e.code}; expected 401")
        check(e.headers.get("WWW-Authenticate", "").startswith("Bearer"),
              f"401 without 'WWW-Authenticate: Bearer' (got {e.headers.get('WWW-Authenticate')!r})")
    _, _, body = api_get(base, "/api/v1/status", token)
    return json.loads(body)


# ---- the browser ------------------------------------------------------------


def start_browser(args, profile, downloads):
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = args.chromium
    for a in CHROME_ARGS + [f"--user-data-dir={profile}"]:
        options.add_argument(a)
    options.add_experimental_option("prefs", {
        "download.default_directory": str(downloads),
        "download.prompt_for_download": False,
        "download.directory_upgrade": True,
        "safebrowsing.enabled": False,
    })
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    # An explicit driver: selenium must not go looking for one on the network.
    service = Service(executable_path=args.chromedriver)
    driver = webdriver.Chrome(service=service, options=options)
    # Headless Chrome also wants downloads allowed explicitly.
    driver.execute_cdp_cmd("Page.setDownloadBehavior", {"behavior": "allow", "downloadPath": str(downloads)})
    return driver


def enter_token(driver, token):
    from selenium.webdriver.common.by import By

    field = driver.find_element(By.ID, "token")
    field.clear()
    field.send_keys(token)
    driver.find_element(By.ID, "token-save").click()


def check_webgl(driver):
    info = driver.execute_script("""
        const gl = document.createElement('canvas').getContext('webgl');
        if (!gl) return null;
        const debug = gl.getExtension('WEBGL_debug_renderer_info');
        return debug ? gl.getParameter(debug.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER);""")
    check(info, "the browser has no WebGL (headless SwiftShader did not start)")
    log(f"WebGL renderer: {info}")


def check_tokens(driver, token):
    """No token: asked for one. A wrong one: the 401 message. The right one:
    the message goes, the status and the event stream come."""
    wait_for(driver, "the page to ask for a token", lambda d: shown(d, "auth-message"))
    log(f"without a token the page says: {text_of(driver, 'auth-message')!r}")
    enter_token(driver, "wrong-" + secrets.token_hex(12))
    wait_for(driver, "the 401 message", lambda d: shown(d, "auth-message") and "401" in text_of(d, "auth-message"))
    log(f"with a wrong token: {text_of(driver, 'auth-message')!r}")
    enter_token(driver, token)
    wait_for(driver, "the 401 message to go", lambda d: not shown(d, "auth-message"))
    wait_for(driver, "the state 'idle'", lambda d: text_of(d, "state") == "idle")
    wait_for(driver, "the event stream", lambda d: text_of(d, "events-state") == "live")
    stored = driver.execute_script("return localStorage.getItem('fpp-scanner.token')")
    check(stored == token, "the token is not kept in localStorage")
    log(f"token accepted: state {text_of(driver, 'state')}, table {text_of(driver, 'table')!r}")


def scan(driver):
    """Presses Scan and follows the progress bar to `written`."""
    from selenium.webdriver.common.by import By

    driver.find_element(By.ID, "scan-button").click()
    began = time.monotonic()
    seen = []
    deadline = began + 120
    while True:
        value, maximum, status, error = driver.execute_script("""
            const p = document.getElementById('progress');
            return [p.value, p.max, document.getElementById('scan-status').textContent,
                    document.getElementById('scan-error').hidden ? '' : document.getElementById('scan-error').textContent];""")
        if not seen or seen[-1] != (value, maximum):
            seen.append((value, maximum))
        if error:
            raise Failure(f"the page shows a scan error: {error!r} (status {status!r})")
        if status.startswith("written") and value == maximum:
            break
        if time.monotonic() > deadline:
            raise Failure(f"no 'written' in 120 s: progress {value}/{maximum}, status {status!r}")
        time.sleep(0.05)
    match = re.match(r"written: (scan-[0-9-]+)", status)
    check(match, f"the status {status!r} names no scan")
    check(maximum > 1, f"the progress bar's max is {maximum}: the frame count never came")
    values = [v for v, _ in seen]
    check(values == sorted(values), f"the progress went backwards: {seen}")
    log(f"scan written in {time.monotonic() - began:.1f} s: {status!r}; progress seen "
        + ", ".join(f"{v:g}/{m:g}" for v, m in seen))
    scan_id = match.group(1)
    wait_for(driver, f"the viewer to draw {scan_id}", lambda d: (
        lambda v: v and v["points"] > 0 and v["scanId"] == scan_id)(viewer_state(d)), timeout=60, poll=0.02)
    log(f"click to shaded cloud on screen: {time.monotonic() - began:.2f} s")
    return scan_id


def count_drawn_pixels(driver):
    """The viewer's canvas read back (toDataURL) and compared with the clear
    colour pixel by pixel."""
    result = driver.execute_async_script("""
        const done = arguments[arguments.length - 1];
        const canvas = document.querySelector('#viewer canvas');
        if (!canvas) { done({error: 'no canvas in #viewer'}); return; }
        const clear = document.getElementById('viewer').dataset.clearColour;
        const bg = [1, 3, 5].map(i => parseInt(clear.slice(i, i + 2), 16));
        const image = new Image();
        image.onerror = () => done({error: 'the canvas PNG did not load'});
        image.onload = () => {
          const c = document.createElement('canvas');
          c.width = image.width; c.height = image.height;
          const g = c.getContext('2d');
          g.drawImage(image, 0, 0);
          const data = g.getImageData(0, 0, c.width, c.height).data;
          let differing = 0;
          for (let i = 0; i < data.length; i += 4)
            if (Math.abs(data[i] - bg[0]) > 8 || Math.abs(data[i + 1] - bg[1]) > 8 || Math.abs(data[i + 2] - bg[2]) > 8)
              ++differing;
          done({width: c.width, height: c.height, differing: differing, clear: clear});
        };
        image.src = canvas.toDataURL('image/png');""")
    check("error" not in result, f"reading the canvas: {result.get('error')}")
    return result


def check_viewer(driver, scan_id, artifacts):
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By

    viewer = wait_for(driver, f"the viewer to draw {scan_id}", lambda d: (
        lambda v: v if v and v["points"] > 0 and v["scanId"] == scan_id else None)(viewer_state(d)), timeout=60)
    log(f"viewer: {viewer['points']} of {viewer['total']} points drawn, coloured by {viewer['colourBy']}, "
        f"normals {viewer['normals']}")
    check(viewer["colourBy"] == "shaded" and viewer["normals"],
          f"the first view is not the shaded surface: {viewer['colourBy']}, normals {viewer['normals']}")
    grey_levels = driver.execute_script("""
        const c = document.querySelector('#viewer canvas'), t = document.createElement('canvas');
        t.width = c.width; t.height = c.height;
        const g = t.getContext('2d'); g.drawImage(c, 0, 0);
        const d = g.getImageData(0, 0, t.width, t.height).data, seen = new Set();
        for (let i = 0; i < d.length; i += 4) if (d[i] > 40) seen.add(d[i] >> 3);
        return seen.size;""")
    log(f"shaded view: {grey_levels} of 32 grey bands in use")
    check(grey_levels >= 12, f"the shaded view uses {grey_levels} grey bands: no shading to see the shape by")
    pixels = count_drawn_pixels(driver)
    share = pixels["differing"] / (pixels["width"] * pixels["height"])
    log(f"canvas {pixels['width']} x {pixels['height']}: {pixels['differing']} pixels "
        f"({100 * share:.1f} %) differ from the clear colour {pixels['clear']}")
    check(share >= 0.01, f"only {100 * share:.2f} % of the canvas is drawn (at least 1 % expected)")
    driver.save_screenshot(str(artifacts / "page-after-scan.png"))
    # The whole viewer in the window, or its screenshot is cut.
    driver.execute_script("document.getElementById('viewer').scrollIntoView({block: 'center'})")
    driver.find_element(By.ID, "viewer").screenshot(str(artifacts / "viewer.png"))
    # Colour by depth: a legend in mm; by quality: in DN.
    for mode, unit in (("depth", "mm"), ("quality", "DN")):
        driver.execute_script("const s = document.getElementById('colour-by'); s.value = arguments[0];"
                              "s.dispatchEvent(new Event('change'));", mode)
        wait_for(driver, f"the {mode} colours", lambda d: viewer_state(d)["colourBy"] == mode)
        legend = driver.find_element(By.ID, "viewer-legend")
        check(legend.is_displayed() and unit in legend.text, f"the {mode} legend shows {legend.text!r}")
        log(f"{mode} legend: {legend.text!r}")
    driver.find_element(By.ID, "viewer").screenshot(str(artifacts / "viewer-quality.png"))
    log(f"screenshots: {artifacts / 'page-after-scan.png'}, {artifacts / 'viewer.png'}, "
        f"{artifacts / 'viewer-quality.png'}")
    # A mouse drag turns the view (the orbit controls).
    canvas = driver.find_element(By.CSS_SELECTOR, "#viewer canvas")
    before = driver.execute_script("return arguments[0].toDataURL('image/png')", canvas)
    ActionChains(driver).move_to_element(canvas).click_and_hold().move_by_offset(120, 40) \
        .move_by_offset(60, 20).release().perform()
    wait_for(driver, "the view to turn under a mouse drag",
             lambda d: d.execute_script("return arguments[0].toDataURL('image/png')", canvas) != before, timeout=10)
    driver.find_element(By.ID, "viewer").screenshot(str(artifacts / "viewer-turned.png"))
    check_scale_bar(driver, canvas)
    log(f"a mouse drag turned the view: {artifacts / 'viewer-turned.png'}")
    lod = viewer_state(driver)["lod"]
    log(f"level of detail: a full frame of {lod['fullPoints']} points took {lod['fullFrameMs']:.0f} ms here; "
        f"while turning, {lod['movingPoints']} points in {lod['movingFrameMs']:.0f} ms a frame (budget 50 ms)")
    check(0 < lod["movingPoints"] <= lod["fullPoints"], f"no level of detail measured: {lod}")
    # Frame times are logged, not asserted: they follow the machine's load (a
    # turning frame of 106 ms once failed a bound here on the VM test's host).
    driver.find_element(By.ID, "view-reset").click()
    driver.execute_script("const s = document.getElementById('colour-by'); s.value = 'shaded';"
                          "s.dispatchEvent(new Event('change'));")
    return viewer


def scale_bar(driver):
    """The scale bar as shown: its length in mm and on screen (px)."""
    text, width = driver.execute_script("""
        const bar = document.querySelector('#viewer .scale-bar');
        return bar.hidden ? [null, 0] : [bar.querySelector('.scale-text').textContent,
                                         bar.querySelector('.scale-line').getBoundingClientRect().width];""")
    match = re.fullmatch(r"([0-9.]+) mm at the centre", text or "")
    check(match, f"the viewer's scale bar says {text!r}")
    return float(match.group(1)), width


def check_scale_bar(driver, canvas):
    """A scale bar of a round length in mm, as long as that length looks at
    the view's centre: it follows the zoom."""
    mm, px = scale_bar(driver)
    mantissa = mm / 10 ** math.floor(math.log10(mm))
    check(any(abs(mantissa - m) < 1e-6 for m in (1, 2, 5)), f"the scale bar's {mm} mm is not 1, 2 or 5 x 10^k")
    check(140 / 2.5 - 1 <= px <= 140 + 1, f"the scale bar is {px:.0f} px long for {mm} mm (56..140 px expected)")
    # The viewer publishes what it drew on every frame, writing only what
    # changed: zooming redraws, and only the frame figures may be rewritten.
    driver.execute_script("""
        const viewer = document.getElementById('viewer');
        window.viewerWrites = [];
        new MutationObserver(records => records.forEach(r => window.viewerWrites.push(r.attributeName)))
          .observe(viewer, {attributes: true});""")
    driver.execute_script("""
        for (let i = 0; i < 5; ++i)
          arguments[0].dispatchEvent(new WheelEvent('wheel', {deltaY: -100, bubbles: true, cancelable: true}));""",
                          canvas)
    zoomed_mm, zoomed_px = wait_for(driver, "the scale bar to follow the zoom", lambda d: (
        lambda bar: bar if bar[1] / bar[0] > 1.2 * px / mm else None)(scale_bar(d)), timeout=10)
    log(f"scale bar: {mm:g} mm over {px:.0f} px; zoomed in, {zoomed_mm:g} mm over {zoomed_px:.0f} px "
        f"({zoomed_px / zoomed_mm / (px / mm):.2f}x the pixels per mm)")
    writes = driver.execute_script("return window.viewerWrites")
    frame_figures = {"data-full-frame-ms", "data-full-points", "data-moving-frame-ms", "data-moving-points"}
    check(writes and set(writes) <= frame_figures,
          f"zooming rewrote the viewer's {sorted(set(writes) - frame_figures)} (only frame figures change)")
    log(f"zooming: {len(writes)} data-* writes, all frame figures")


def check_phone_layout(driver, artifacts):
    """One column on a phone-sized window."""
    size = driver.get_window_size()
    driver.set_window_size(390, 844)
    try:
        lefts = wait_for(driver, "the one-column layout", lambda d: d.execute_script("""
            const ids = ['auth-section', 'status-section', 'scan-section', 'viewer-section', 'table-section'];
            const lefts = ids.map(id => Math.round(document.getElementById(id).getBoundingClientRect().left));
            const root = document.documentElement;
            const wide = root.scrollWidth > root.clientWidth;
            return lefts.every(x => x === lefts[0]) && !wide ? lefts : null;"""), timeout=10)
        driver.save_screenshot(str(artifacts / "page-phone.png"))
        log(f"phone layout: one column (sections at x = {lefts[0]} px), no sideways scrolling")
        small = driver.execute_script("""
            const out = [];
            for (const e of document.querySelectorAll('main button, main a, main select, main input')) {
              const r = e.getBoundingClientRect();
              if (r.width === 0 || r.height === 0 || e.closest('[hidden], details:not([open])')) continue;
              const target = e.type === 'checkbox' ? e.closest('label') || e : e;
              const t = target.getBoundingClientRect();
              if (t.height < 44) out.push((e.id || e.className || e.tagName) + ' ' + Math.round(t.height) + ' px');
            }
            return out;""")
        check(not small, f"tap targets under 44 px on a phone: {small}")
        log("phone layout: every visible control at least 44 px tall")
        check_accessibility(driver, "phone")
    finally:
        driver.set_window_size(size["width"], size["height"])


def check_download(driver, scan_id, downloads, expected):
    from selenium.webdriver.common.by import By

    link = driver.find_element(By.CSS_SELECTOR, f'#scan-list tr[data-scan-id="{scan_id}"] a.download-ply')
    name = link.get_attribute("download")
    check(name == f"{scan_id}-cloud.ply", f"the PLY link's file name is {name!r}")
    link.click()
    target = downloads / name

    def complete(_):
        partial = list(downloads.glob("*.crdownload"))
        return target.exists() and not partial and target.stat().st_size == len(expected)

    wait_for(driver, f"the download of {name}", complete, timeout=60, poll=0.1)
    got = hashlib.sha256(target.read_bytes()).hexdigest()
    want = hashlib.sha256(expected).hexdigest()
    check(got == want, f"{name} downloaded through the page differs: sha256 {got}, the scanner's {want}")
    log(f"download {name}: {len(expected)} bytes, sha256 {got[:16]}… matches the scanner's file")


def check_console(driver):
    entries = driver.get_log("browser")
    for e in entries:
        if e["level"] in ("SEVERE", "WARNING"):
            log(f"browser console {e['level']}: {e['message']}")
    errors = [e for e in entries if e["level"] == "SEVERE" and "Uncaught" in e["message"]]
    check(not errors, f"JavaScript errors on the page: {[e['message'] for e in errors]}")


def browser_test(args, base, token, store, work, artifacts, restart=None, table=None):
    downloads = work / "downloads"
    downloads.mkdir()
    log(f"chromium {args.chromium}, chromedriver {args.chromedriver}")
    driver = start_browser(args, work / "profile", downloads)
    try:
        driver.set_script_timeout(60)
        driver.get(base + "/")
        check(driver.title == "fpp scanner", f"the page's title is {driver.title!r}")
        check_webgl(driver)
        check_tokens(driver, token)
        scan_id = scan(driver)
        check_viewer(driver, scan_id, artifacts)
        if store:
            expected = (Path(store) / scan_id / "cloud.ply").read_bytes()
            log(f"expected bytes from {Path(store) / scan_id / 'cloud.ply'}")
        else:
            expected = api_get(base, f"/api/v1/scans/{scan_id}/cloud.ply", token)[2]
            log("expected bytes from GET /api/v1/scans/{id}/cloud.ply (no --store given)")
        check_download(driver, scan_id, downloads, expected)
        check_replayed_events(driver, scan_id)
        if table:
            check_controls(driver, table)
        if store:
            check_bad_cloud(driver, store, scan_id)
        check_accessibility_checker(driver)
        check_accessibility(driver, "a cloud on screen")
        if restart:  # the simulated board: its brightness follows the exposure
            # (Aravis's fake camera on the virtual ARM board ignores it)
            poor = check_poor_scan(driver, base, token)
            check_deleted_elsewhere(driver, base, token, poor)
            check_scanner_gone(driver, restart)
        check_phone_layout(driver, artifacts)
        check_reload_transfer(driver)
        check_console(driver)
        return scan_id
    except Exception:
        try:
            driver.save_screenshot(str(artifacts / "failure.png"))
            log(f"screenshot of the failure: {artifacts / 'failure.png'}")
        except Exception:
            pass
        raise
    finally:
        driver.quit()


def main():
    # SIGTERM (ctest, a person) ends the test through its `finally`.
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(128 + signal.SIGTERM))
    args = parse_args()
    try:
        require_tools(args)
    except Failure as e:
        print(f"{TEST_NAME}: FAILED: {e}", flush=True)
        return 1
    work = Path(tempfile.mkdtemp(prefix="fpp-browser-"))
    artifacts = Path(args.artifacts) if args.artifacts else work / "artifacts"
    artifacts.mkdir(parents=True, exist_ok=True)
    daemon = None
    failed = False
    restart = None  # a scanner someone else started is not ours to restart
    try:
        if args.url:
            base = args.url.rstrip("/")
            token = Path(args.token_file).read_text().splitlines()[0].strip()
            store = args.store
        else:
            table = Path(args.table) if args.table else make_table(args, work, artifacts)
            token_file = work / "token"
            token = write_token(token_file)
            store = work / "store"
            board = board_file("sim.yaml", args.binning, work)

            def command(port, table_path=table):
                return [args.scanner, "--board", board, "--http", f"127.0.0.1:{port}",
                        "--token-file", token_file, "--store", store, "--table", table_path,
                        "--settings", work / "settings.yaml", "--web-root", args.web_root]

            daemon = Daemon(command(0), artifacts / "daemon.log")
            port = daemon.wait_listening()
            base = f"http://127.0.0.1:{port}"
            log(f"scanner listening at {base}")
            runs = [daemon]

            def restart(while_away, kill=False, table_path=table):
                """Stops (or kills) the scanner, runs `while_away`, starts it on the
                same port (with `table_path` as its table: one that is not there
                starts it without)."""
                runs[-1].stop(kill)
                while_away()
                runs.append(Daemon(command(port, table_path), artifacts / f"daemon-{len(runs)}.log"))
                runs[-1].wait_listening()
        status = check_server_basics(base, token)
        log(f"status: state {status['state']}, board {status['board']['name']}, "
            f"camera {status['camera']['width']} x {status['camera']['height']}, "
            f"table {'loaded' if status['table'] else 'none'}")
        scan_id = browser_test(args, base, token, store, work, artifacts, restart,
                               None if args.url else table)
        log(f"{TEST_NAME}: PASSED ({scan_id}, {time.monotonic() - START:.1f} s)")
        return 0
    except Failure as e:
        print(f"{TEST_NAME}: FAILED: {e}", flush=True)
        failed = True
        return 1
    except Exception as e:  # the browser or the OS: still a failure with a message
        print(f"{TEST_NAME}: FAILED: {type(e).__name__}: {e}", flush=True)
        failed = True
        return 1
    finally:
        if daemon:
            daemon = runs[-1]
            code = daemon.stop()
            log(f"scanner stopped (exit code {code}); its log: {artifacts / 'daemon.log'}")
            if failed:
                tail = (artifacts / "daemon.log").read_text(errors="replace").splitlines()[-15:]
                print("the scanner's log ends:\n  " + "\n  ".join(tail), flush=True)
        if args.keep:
            log(f"kept {work}")
        else:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
