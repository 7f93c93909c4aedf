"""What the API tests share: the command line, the real fpp-scanner daemon on
the simulated board (started on loopback, port 0, stopped with SIGTERM), an
HTTP client, a server-sent-events follower and raw-socket exchanges.

Python 3 standard library only. A test script runs as

    python3 SCRIPT --scanner FPP_SCANNER --table-tool FPP_TEST_TRUTH_TABLE \
        --boards REPO/board --tmp FRESH_DIR [--sanitized] [GROUP or unittest names...]

(tests/CMakeLists.txt gives these); --tmp is emptied first.
"""

import argparse
import hashlib
import http.client
import json
import os
import re
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
import unittest

# Set by main() from the command line.
SCANNER = None
TABLE_TOOL = None
BOARDS = None
TMP = None
SANITIZED = False  # fpp-scanner built with AddressSanitizer (--sanitized)

LISTENING = re.compile(r"info: http: listening on 127\.0\.0\.1:(\d+) \(")
SCAN_ID = re.compile(r"^scan-\d{8}-\d{6}-\d{3}(-\d{1,6})?$")
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"

# The sim board (board/sim.yaml): the camera binned 2 x 2, the paper's projector.
CAMERA = (800, 600)
PROJECTOR = (1280, 800)



class DaemonCase(unittest.TestCase):
    """A daemon per class, stopped with SIGTERM at the end (exit 0 asserted)."""

    daemon = None

    @classmethod
    def start_daemon(cls, **kwargs):
        d = Daemon(**kwargs)
        try:
            d.start()
        except Exception:
            d.stop()
            raise
        return d

    @classmethod
    def tearDownClass(cls):
        if cls.daemon is not None:
            code = cls.daemon.stop()
            cls.daemon = None
            if code != 0:
                raise AssertionError(f"fpp-scanner exited with {code} on SIGTERM")

    def assert_error(self, r, status, part=None):
        """`status` with {"error": "..."} naming `part`."""
        self.assertEqual(r.status, status, r)
        self.assertTrue(r.header("content-type", "").startswith("application/json"), r.headers)
        body = r.json()
        self.assertEqual(list(body), ["error"], body)
        self.assertIsInstance(body["error"], str)
        self.assertTrue(body["error"])
        if part is not None:
            self.assertIn(part, body["error"])
        return body["error"]

    def assert_png(self, r):
        self.assertEqual(r.status, 200, r)
        self.assertEqual(r.header("content-type"), "image/png")
        self.assertEqual(r.body[:8], PNG_SIGNATURE)
        return png_size(r.body)

    def uploads_left(self, wait_s=2.0):
        """Spooled uploads in the table's folder, once the server has had
        `wait_s` to remove them: a refused upload's file goes when its
        request is completed, which may be just after the client has read
        the answer."""
        folder = os.path.dirname(self.daemon.table)
        deadline = time.monotonic() + wait_s
        while True:
            left = [n for n in os.listdir(folder) if n.startswith(".upload-")]
            if not left or time.monotonic() > deadline:
                return left
            time.sleep(0.02)

    def store_scans(self, d):
        if not os.path.isdir(d.store):
            return []  # made by the first scan
        return sorted(n for n in os.listdir(d.store) if n.startswith("scan-"))

def main(groups):
    """Parses the paths, empties --tmp, runs the named tests. `groups` maps
    a name (the CTest test's) to unittest names."""
    global SCANNER, TABLE_TOOL, BOARDS, TMP, SANITIZED
    parser = argparse.ArgumentParser()
    parser.add_argument("--sanitized", action="store_true",
                        help="fpp-scanner runs under AddressSanitizer: its memory is not measured")
    parser.add_argument("--scanner", required=True)
    parser.add_argument("--table-tool", required=True)
    parser.add_argument("--boards", required=True)
    parser.add_argument("--tmp", required=True)
    args, rest = parser.parse_known_args()
    SCANNER, TABLE_TOOL, SANITIZED = args.scanner, args.table_tool, args.sanitized
    BOARDS, TMP = os.path.abspath(args.boards), os.path.abspath(args.tmp)
    for tool in (SCANNER, TABLE_TOOL):
        if not os.access(tool, os.X_OK):
            sys.exit(f"{tool}: not an executable (build fpp-scanner and fpp_test_truth_table)")
    shutil.rmtree(TMP, ignore_errors=True)
    os.makedirs(TMP)
    names = []
    for name in filter(None, rest):  # CMake passes "" for an unset option
        names.extend(groups.get(name, [name]))
    program = unittest.main(module="__main__", argv=[sys.argv[0], "-v"] + names, exit=False)
    ok = program.result.wasSuccessful()
    if ok:
        shutil.rmtree(TMP, ignore_errors=True)  # kept when something failed
    sys.exit(0 if ok else 1)


def fresh_dir(prefix):
    return tempfile.mkdtemp(prefix=prefix + "-", dir=TMP)


def sha256_file(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def read_bytes(path):
    with open(path, "rb") as f:
        return f.read()


_fnv_memo = {}


def fnv1a64(data):
    """The table's file hash as status and scan.json give it (hex, 16 digits).
    Pure Python: seconds for a 800 x 600 table, so remembered per content."""
    key = hashlib.sha256(data).digest()
    if key not in _fnv_memo:
        h = 0xCBF29CE484222325
        for b in data:
            h = ((h ^ b) * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
        _fnv_memo[key] = f"{h:016x}"
    return _fnv_memo[key]


_tables = {}
_tables_lock = threading.Lock()


def truth_table(rig="paper-rig-effects.yaml", binning=2):
    """The path of the truth table of board/sim/RIG binned BINNING (made once
    per run by fpp_test_truth_table; copy it before handing it to a daemon)."""
    key = (rig, binning)
    with _tables_lock:
        if key not in _tables:
            out = os.path.join(TMP, f"truth-{os.path.splitext(rig)[0]}-b{binning}.fpt")
            run = subprocess.run([TABLE_TOOL, os.path.join(BOARDS, "sim", rig), str(binning), out],
                                 capture_output=True, text=True, timeout=120)
            if run.returncode != 0:
                raise RuntimeError(f"fpp_test_truth_table failed: {run.stderr}")
            _tables[key] = out
        return _tables[key]


def copy_table(dest, rig="paper-rig-effects.yaml", binning=2):
    shutil.copyfile(truth_table(rig, binning), dest)
    return dest


def write_token(path):
    token = secrets.token_hex(16)  # 32 hex characters
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "w") as f:
        f.write(token + "\n")
    return token


def board_copy(dest, source="sim.yaml", http=None):
    """A copy of board/SOURCE whose sim rig path is absolute (board paths are
    relative to the board file), with an `http` section when given (a
    dict: listen, token_file, timeout_s, max_connections)."""
    with open(os.path.join(BOARDS, source)) as f:
        text = f.read()
    text = re.sub(r"(\n  rig: )(\S+)", lambda m: m.group(1) + os.path.join(BOARDS, m.group(2)), text)
    if http:
        fields = ", ".join(f"{k}: {v}" for k, v in http.items())
        text += f"http: {{{fields}}}\n"
    with open(dest, "w") as f:
        f.write(text)
    return dest


class Daemon:
    """fpp-scanner --http 127.0.0.1:0 on a sim board, in `folder`:
    folder/token (0600), folder/store, folder/settings.yaml, folder/table.fpt
    (what --table names; the caller puts a table there or not). stderr is read
    by a thread all along (kept in `lines`)."""

    def __init__(self, folder, board=None, table=True, settings=True, extra=()):
        self.folder = folder
        self.board = board or os.path.join(BOARDS, "sim.yaml")
        self.token_file = os.path.join(folder, "token")
        self.store = os.path.join(folder, "store")
        self.settings = os.path.join(folder, "settings.yaml") if settings else None
        self.table = os.path.join(folder, "table.fpt") if table else None
        self.extra = list(extra)
        self.token = write_token(self.token_file) if not os.path.exists(self.token_file) \
            else read_bytes(self.token_file).decode().splitlines()[0]
        self.proc = None
        self.port = None
        self.lines = []
        self._lines_lock = threading.Condition()
        self._reader = None

    def start(self, timeout=60):
        cmd = [SCANNER, "--board", self.board, "--http", "127.0.0.1:0",
               "--token-file", self.token_file, "--store", self.store]
        if self.settings:
            cmd += ["--settings", self.settings]
        if self.table:
            cmd += ["--table", self.table]
        cmd += self.extra
        self.lines = []
        self.port = None  # another one after a restart
        self.proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                     stderr=subprocess.PIPE, text=True, errors="replace")
        self._reader = threading.Thread(target=self._read_stderr, daemon=True)
        self._reader.start()
        deadline = time.monotonic() + timeout
        with self._lines_lock:
            while self.port is None:
                if self.proc.poll() is not None and not self._reader.is_alive():
                    raise RuntimeError("fpp-scanner exited at start:\n" + "\n".join(self.lines))
                left = deadline - time.monotonic()
                if left <= 0:
                    raise RuntimeError("fpp-scanner did not listen:\n" + "\n".join(self.lines))
                self._lines_lock.wait(min(left, 0.5))
        # The scanning thread says so once it waits for the button or a request.
        self.wait_line("idle: waiting for the button or a request", timeout)
        return self

    def _read_stderr(self):
        # Also kept in FOLDER/scanner.log (the temp folder stays when a test fails).
        log = open(os.path.join(self.folder, "scanner.log"), "a", buffering=1)
        try:
            self._keep_lines(log)
        finally:
            log.close()

    def _keep_lines(self, log):
        for line in self.proc.stderr:
            log.write(line)
            line = line.rstrip("\n")
            with self._lines_lock:
                self.lines.append(line)
                m = LISTENING.search(line)
                if m and self.port is None:
                    self.port = int(m.group(1))
                self._lines_lock.notify_all()
        with self._lines_lock:
            self._lines_lock.notify_all()

    def wait_line(self, part, timeout=10):
        deadline = time.monotonic() + timeout
        with self._lines_lock:
            while not any(part in l for l in self.lines):
                left = deadline - time.monotonic()
                if left <= 0 or (self.proc.poll() is not None and not self._reader.is_alive()):
                    raise AssertionError(f"no line with {part!r} in:\n" + "\n".join(self.lines))
                self._lines_lock.wait(min(left, 0.2))

    def logged(self, part):
        with self._lines_lock:
            return [l for l in self.lines if part in l]

    def stop(self, timeout=30):
        """SIGTERM and wait; the exit code (0 expected)."""
        if self.proc is None:
            return None
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
        try:
            code = self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
            code = "hung: killed after SIGTERM"
        self._reader.join(5)
        self.proc.stderr.close()
        self.proc = None
        return code

    def pid(self):
        return self.proc.pid

    # ---- HTTP

    def client(self, token=True, timeout=30):
        return Client(self.port, self.token if token is True else token, timeout)

    def request(self, method, path, body=None, headers=None, token=True, timeout=30):
        return self.client(token, timeout).request(method, path, body, headers)

    def get_json(self, path):
        r = self.request("GET", path)
        if r.status != 200:
            raise AssertionError(f"GET {path}: {r.status} {r.body[:300]!r}")
        return r.json()

    def status(self):
        return self.get_json("/api/v1/status")

    def follow(self):
        return EventFollower(self.port, self.token).start()

    def scan(self, mode="scan", path="/api/v1/scans", body=None, timeout=120):
        """POST a scan, follow it to `written`; (post response, events of it)."""
        with self.follow() as events:
            r = self.request("POST", path, body if body is not None else {"mode": mode})
            if r.status != 202:
                raise AssertionError(f"POST {path}: {r.status} {r.body[:300]!r}")
            scan_id = r.json()["id"]
            events.wait_for(lambda e: e.name in ("written", "failed") and e.data.get("id") == scan_id,
                            timeout)
            return r, [e for e in events.snapshot() if e.data.get("id") == scan_id]

    def folder_of(self, scan_id, session=None):
        if session:
            return os.path.join(self.store, "sessions", session, scan_id)
        return os.path.join(self.store, scan_id)

    def fd_count(self):
        return len(os.listdir(f"/proc/{self.proc.pid}/fd"))

    def rss_kib(self):
        with open(f"/proc/{self.proc.pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1])
        return 0

    def threads(self):
        with open(f"/proc/{self.proc.pid}/status") as f:
            for line in f:
                if line.startswith("Threads:"):
                    return int(line.split()[1])
        return 0


class Response:
    def __init__(self, status, headers, body):
        self.status = status
        self.headers = headers  # lower-case names
        self.body = body

    def json(self):
        return json.loads(self.body)

    def header(self, name, default=None):
        return self.headers.get(name.lower(), default)

    def __repr__(self):
        return f"<{self.status} {self.body[:200]!r}>"


class Client:
    """One request per connection (what the page and fpp-calib do)."""

    def __init__(self, port, token, timeout=30):
        self.port, self.token, self.timeout = port, token, timeout

    def request(self, method, path, body=None, headers=None):
        h = dict(headers or {})
        if self.token is not None and "Authorization" not in h:
            h["Authorization"] = "Bearer " + self.token
        if isinstance(body, (dict, list)):
            body = json.dumps(body).encode()
            h.setdefault("Content-Type", "application/json")
        elif isinstance(body, str):
            body = body.encode()
        conn = http.client.HTTPConnection("127.0.0.1", self.port, timeout=self.timeout)
        try:
            conn.request(method, path, body=body, headers=h)
            r = conn.getresponse()
            data = r.read()
            return Response(r.status, {k.lower(): v for k, v in r.getheaders()}, data)
        finally:
            conn.close()


class Event:
    def __init__(self, name, data, at):
        self.name = name
        self.data = data
        self.at = at

    def __repr__(self):
        return f"{self.name} {self.data}"


class EventFollower:
    """GET /api/v1/events read by a thread; events parsed from `event:` and
    `data:` lines (one JSON line each), comments counted."""

    def __init__(self, port, token):
        self.port, self.token = port, token
        self.events = []
        self.comments = 0
        self.error = None
        self.content_type = None
        self._cv = threading.Condition()
        self._conn = None
        self._thread = None
        self.ended = False

    def start(self, timeout=10):
        self._conn = http.client.HTTPConnection("127.0.0.1", self.port, timeout=60)
        self._conn.request("GET", "/api/v1/events", headers={"Authorization": "Bearer " + self.token})
        self._response = self._conn.getresponse()
        if self._response.status != 200:
            raise AssertionError(f"/events: {self._response.status} {self._response.read()!r}")
        self.content_type = self._response.getheader("Content-Type")
        self._thread = threading.Thread(target=self._read, daemon=True)
        self._thread.start()
        # The first event (state) says the subscription is in place.
        self.wait_for(lambda e: True, timeout)
        return self

    def _read(self):
        name, data = None, None
        try:
            while True:
                line = self._response.readline()
                if not line:
                    break
                line = line.decode().rstrip("\r\n")
                if line == "":
                    if name is not None:
                        with self._cv:
                            self.events.append(Event(name, json.loads(data) if data else None,
                                                     time.monotonic()))
                            self._cv.notify_all()
                    name, data = None, None
                elif line.startswith(":"):
                    with self._cv:
                        self.comments += 1
                elif line.startswith("event: "):
                    name = line[7:]
                elif line.startswith("data: "):
                    if data is not None:
                        raise ValueError("two data lines in one event")
                    data = line[6:]
                else:
                    raise ValueError(f"not an SSE line: {line!r}")
        except (OSError, ValueError, http.client.HTTPException) as e:
            if not self._closing:
                self.error = e
        finally:
            with self._cv:
                self.ended = True
                self._cv.notify_all()

    _closing = False

    def snapshot(self):
        with self._cv:
            return list(self.events)

    def wait_for(self, predicate, timeout=60):
        """The first event (in order) matching; AssertionError on timeout."""
        deadline = time.monotonic() + timeout
        with self._cv:
            while True:
                for e in self.events:
                    if predicate(e):
                        return e
                left = deadline - time.monotonic()
                if left <= 0 or self.ended:
                    raise AssertionError(f"event not seen in {timeout} s (error {self.error}); "
                                         f"seen: {self.events[-12:]}")
                self._cv.wait(min(left, 0.5))

    def close(self):
        self._closing = True
        try:
            if self._conn.sock:
                self._conn.sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass
        self._thread.join(10)
        self._conn.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def raw_exchange(port, data, read_timeout=5.0, chunks=None, shut_write=False):
    """Sends `data` (or each of `chunks`) on a fresh connection and reads
    until the server closes or `read_timeout` passes with nothing new.
    Returns (status or None, everything read). A reset counts as closed."""
    s = socket.create_connection(("127.0.0.1", port), timeout=read_timeout)
    received = b""
    try:
        try:
            for piece in (chunks if chunks is not None else [data]):
                s.sendall(piece)
            if shut_write:
                s.shutdown(socket.SHUT_WR)
        except (BrokenPipeError, ConnectionResetError):
            pass
        try:
            while True:
                block = s.recv(65536)
                if not block:
                    break
                received += block
        except (socket.timeout, ConnectionResetError):
            pass
    finally:
        s.close()
    m = re.match(rb"HTTP/1\.[01] (\d{3}) ", received)
    return (int(m.group(1)) if m else None), received


def parse_tar(data):
    import io
    import tarfile
    with tarfile.open(fileobj=io.BytesIO(data), mode="r:") as tar:
        return {m.name: tar.extractfile(m).read() for m in tar.getmembers() if m.isfile()}, \
               [m.name for m in tar.getmembers()]


def files_under(folder, prefix=""):
    """{prefix + relative path: bytes} of the regular files under `folder`,
    hidden ones (atomic writes' temporaries) left out as the server does."""
    out = {}
    for root, dirs, files in os.walk(folder):
        dirs[:] = [d for d in dirs if not d.startswith(".")]
        for name in files:
            if name.startswith("."):
                continue
            path = os.path.join(root, name)
            out[prefix + os.path.relpath(path, folder)] = read_bytes(path)
    return out


def png_size(data):
    """(width, height) from a PNG's IHDR."""
    assert data[:8] == PNG_SIGNATURE and data[12:16] == b"IHDR", data[:16]
    return int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")
