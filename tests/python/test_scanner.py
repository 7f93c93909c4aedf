"""fpp.Scanner against the real daemon (fpp-scanner on the simulated board
board/sim.yaml, 800 x 600 camera) on loopback, as tests/api does."""

import os
import re
import secrets
import shutil
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import fpp

from conftest import BOARDS, program

BOARD_YAML = "format: fpp-board/1\nkind: checkerboard\ninner_corners: [13, 9]\nsquare_size: 10.0\n"
LISTENING = re.compile(r"info: http: listening on 127\.0\.0\.1:(\d+) \(")


class Daemon:
    """fpp-scanner --http 127.0.0.1:0 on board/sim.yaml in `folder`; stopped by stop()."""

    def __init__(self, folder, table=None):
        shutil.rmtree(folder, ignore_errors=True)
        os.makedirs(folder)
        self.token = secrets.token_hex(16)
        token_file = os.path.join(folder, "token")
        fd = os.open(token_file, os.O_WRONLY | os.O_CREAT, 0o600)
        with os.fdopen(fd, "w") as f:
            f.write(self.token + "\n")
        cmd = [program("FPP_SCANNER_EXE"), "--board", os.path.join(BOARDS, "sim.yaml"),
               "--http", "127.0.0.1:0", "--token-file", token_file,
               "--store", os.path.join(folder, "store"),
               "--settings", os.path.join(folder, "settings.yaml"),
               "--table", os.path.join(folder, "table.fpt")]
        if table:
            shutil.copyfile(table, os.path.join(folder, "table.fpt"))
        self.lines = []
        self.ready = threading.Event()
        self.proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                     stderr=subprocess.PIPE, text=True, errors="replace")
        self.port = None
        threading.Thread(target=self._read, daemon=True).start()
        if not self.ready.wait(60) or self.port is None:
            self.stop()
            raise RuntimeError("fpp-scanner did not start:\n" + "\n".join(self.lines))
        self.url = f"http://127.0.0.1:{self.port}"

    def _read(self):
        for line in self.proc.stderr:
            self.lines.append(line.rstrip("\n"))
            m = LISTENING.search(line)
            if m:
                self.port = int(m.group(1))
            if self.port and "idle: waiting for the button or a request" in line:
                self.ready.set()
        self.ready.set()

    def stop(self):
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        return self.proc.returncode


@pytest.fixture(scope="module")
def daemon(tmp_root, truth_table):
    d = Daemon(os.path.join(tmp_root, "daemon"), table=truth_table)
    yield d
    assert d.stop() == 0


@pytest.fixture
def scanner(daemon):
    return fpp.Scanner(daemon.url, daemon.token, timeout=30)


def test_status_and_settings(scanner):
    s = scanner.status()
    assert s["api"] == 1 and s["state"] == "idle"
    assert s["camera"]["width"] == 800 and s["table"]["camera"] == {"width": 800, "height": 600}
    exposure = scanner.settings()["exposure_us"]
    assert scanner.set_exposure(exposure)["exposure_us"] == exposure


def test_scan_with_progress_then_download_the_cloud(scanner, tmp_root):
    seen = []
    written = scanner.scan(progress=lambda name, data: seen.append((name, data)))
    names = [n for n, _ in seen]
    frames = [d["frame"] for n, d in seen if n == "frame-captured"]
    assert names[0] == "scan-started" and names[-1] == "written" and "decoded" in names
    assert frames == list(range(1, seen[0][1]["frames"] + 1))
    assert written["points"] > 100000 and written["quality"]["good"]
    assert scanner.list()[0]["id"] == written["id"]
    path = scanner.download_cloud(written["id"], os.path.join(tmp_root, "scanned.ply"))
    cloud = fpp.read_ply(path)
    assert cloud.organised and cloud.xyz.shape == (600, 800, 3)
    assert cloud.count_points() == written["points"]
    with pytest.raises(fpp.ScannerError) as e:  # a scan-mode scan keeps no capture
        scanner.download_capture(written["id"], os.path.join(tmp_root, "no-capture"))
    assert e.value.status == 404 and e.value.message
    info = scanner.scan_info(written["id"])
    assert info["decode"]["decoded"] >= written["points"]


def test_capture_download_decodes_in_python(scanner, tmp_root, truth_table):
    written = scanner.scan("capture")
    folder = scanner.download_capture(written["id"], os.path.join(tmp_root, "downloaded"))
    r = fpp.decode(fpp.read_capture(folder))
    assert r.camera == (800, 600) and r.coverage_of_lit > 0.9
    xyz = fpp.Table.load(truth_table).apply(r.proj_x)
    assert np.isfinite(xyz[..., 2]).sum() > 100000
    scanner.delete(written["id"])
    assert written["id"] not in [s["id"] for s in scanner.list()]


def test_sessions_and_table(scanner, truth_table, tmp_root):
    scanner.create_session("py-session", BOARD_YAML)
    assert "py-session" in [s["name"] for s in scanner.sessions()]
    pose = scanner.add_pose("py-session")
    assert pose["session"] == "py-session"
    folder = scanner.download_session("py-session", os.path.join(tmp_root, "session"))
    assert os.path.exists(os.path.join(folder, "board.yaml"))
    assert fpp.read_capture(os.path.join(folder, pose["id"], "capture")).camera == (800, 600)
    with pytest.raises(fpp.ScannerError) as e:
        scanner.create_session("py-session", BOARD_YAML)
    assert e.value.status == 409 and e.value.message
    scanner.delete_session("py-session")
    table = scanner.install_table(truth_table)
    assert table["camera"] == {"width": 800, "height": 600}


def test_refusals_carry_the_apis_message(daemon, scanner, tmp_root):
    with pytest.raises(fpp.ScannerError) as e:
        fpp.Scanner(daemon.url, "wrong-token-0123456789").status()
    assert e.value.status == 401 and e.value.message
    with pytest.raises(fpp.ScannerError) as e:
        scanner.scan_info("scan-19700101-000000-000")
    assert e.value.status == 404
    bad = os.path.join(tmp_root, "not-a-table.fpt")
    with open(bad, "wb") as f:
        f.write(b"not a table")
    with pytest.raises(fpp.ScannerError) as e:
        scanner.install_table(bad)
    assert e.value.status == 400 and e.value.message
    with pytest.raises(ValueError):
        scanner.scan("sideways")
    with pytest.raises(fpp.ScannerError) as e:
        fpp.Scanner("http://127.0.0.1:9", "token", timeout=5).status()
    assert e.value.status is None and "cannot reach" in str(e.value)


def test_a_scanner_that_goes_away_mid_scan_raises(tmp_root, truth_table):
    d = Daemon(os.path.join(tmp_root, "daemon-killed"), table=truth_table)
    try:
        client = fpp.Scanner(d.url, d.token, timeout=10)

        def kill_at_the_second_frame(name, data):
            if name == "frame-captured" and data["frame"] == 2:
                d.proc.kill()

        with pytest.raises(fpp.ScannerError) as e:
            client.scan("capture", progress=kill_at_the_second_frame)
        assert e.value.status is None
        assert "closed the event stream" in str(e.value) or "broke" in str(e.value)
    finally:
        d.stop()


def test_ctrl_c_interrupts_a_blocking_call(daemon):
    """A blocking read of the event stream, in a child Python, ended by SIGINT."""
    code = ("import fpp, sys\n"
            f"s = fpp.Scanner({daemon.url!r}, {daemon.token!r}, timeout=30)\n"
            "for name, data in s.events():\n"
            "    print(name, flush=True)\n")
    env = dict(os.environ)
    child = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True, env=env)
    try:
        assert child.stdout.readline().strip() == "state"
        time.sleep(0.2)  # into the blocking read
        child.send_signal(signal.SIGINT)
        _, err = child.communicate(timeout=20)
        assert "KeyboardInterrupt" in err
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
