#!/usr/bin/python3
"""fpp-scanner's HTTP API (firmware/scanner/http-api.md) against the real
daemon on the simulated board, on loopback: the refusals (401/404/405/409/
413) and bad requests over raw sockets (every endpoint: test_api.py).

    python3 test_api_refusals.py --scanner BUILD/firmware/scanner/fpp-scanner \
        --table-tool BUILD/tests/fpp_test_truth_table --boards REPO/board \
        --tmp SCRATCH [Refusals | BadRequests | Class.test_name ...]

The sim board's button cannot be pressed from outside the daemon: the race
of a press and a request is tests/integration/scanner/test_scanner_service.cpp.
"""

import json
import os
import re
import socket
import sys
import threading
import time

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import api_support as s  # noqa: E402

ISO_UTC = re.compile(r"^\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ$")
HEX16 = re.compile(r"^[0-9a-f]{16}$")
DaemonCase = s.DaemonCase


# ============================================================ refusals


class Refusals(DaemonCase):
    @classmethod
    def setUpClass(cls):
        folder = s.fresh_dir("refusals")
        s.copy_table(os.path.join(folder, "table.fpt"))
        cls.daemon = cls.start_daemon(folder=folder)

    def test_401_without_the_right_token(self):
        d = self.daemon
        t = d.token
        wrong_last = t[:-1] + ("0" if t[-1] != "0" else "1")
        for auth in (None, "", "Bearer", "Bearer ", "Bearer  " + t, "Bearer\t" + t, "Basic " + t,
                     "Bearer " + wrong_last, "Bearer " + t[:-1], "Bearer " + t + "0",
                     "Bearer " + t.upper() if t.upper() != t else "Bearer x" + t[1:],
                     "Bearer " + "0" * len(t), t):
            headers = {} if auth is None else {"Authorization": auth}
            for method, path in (("GET", "/api/v1/status"), ("POST", "/api/v1/scans"),
                                 ("GET", "/api/v1/table"), ("GET", "/api/v1/nope"),
                                 ("DELETE", "/api/v1/sessions/x"), ("GET", "/api/v2/x")):
                r = d.request(method, path, None, headers, token=None)
                self.assert_error(r, 401, "token")
                self.assertEqual(r.header("www-authenticate"), "Bearer", (auth, path))
        self.assertEqual(d.status()["scans_completed"], 0)
        self.assertEqual(self.store_scans(d), [])
        # The scheme's name in any case (RFC 7235): let in.
        for scheme in ("bearer", "BEARER", "bEaReR"):
            r = d.request("GET", "/api/v1/status", None, {"Authorization": scheme + " " + t},
                          token=None)
            self.assertEqual(r.status, 200, (scheme, r.body[:200]))

    def test_404_for_unknown_paths(self):
        d = self.daemon
        for path in ("/api/v1/nope", "/api/v1", "/api/v1/", "/api/v2/status", "/api/status",
                     "/api/v1/status/x", "/api/v1/scans/nope", "/api/v1/scans/scan-1",
                     "/api/v1/scans/scan-20990101-000000-000",
                     "/api/v1/scans/scan-20990101-000000-000/cloud.ply",
                     "/api/v1/sessions/nope", "/api/v1/table/x", "/api/v1/events/x",
                     "/api/v1/settings/exposure_us", "/nope", "/api/v1/STATUS",
                     "/index.htm", "/three/", "/three/nope.js"):
            r = d.request("GET", path)
            self.assertEqual(r.status, 404, (path, r))
            self.assertTrue(r.json()["error"])

    def test_405_for_other_methods(self):
        d = self.daemon
        for method, path, allow in (("POST", "/api/v1/status", "GET"),
                                    ("DELETE", "/api/v1/status", "GET"),
                                    ("PUT", "/api/v1/scans", "GET, POST"),
                                    ("DELETE", "/api/v1/scans", "GET, POST"),
                                    ("POST", "/api/v1/events", "GET"),
                                    ("POST", "/api/v1/preview.png", "GET"),
                                    ("POST", "/api/v1/settings", "GET, PUT"),
                                    ("DELETE", "/api/v1/table", "GET, PUT"),
                                    ("PATCH", "/api/v1/sessions", "GET, POST"),
                                    # The page's files are only read.
                                    ("POST", "/", "GET, HEAD"),
                                    ("DELETE", "/index.html", "GET, HEAD"),
                                    ("PUT", "/app.js", "GET, HEAD"),
                                    ("OPTIONS", "/style.css", "GET, HEAD")):
            r = d.request(method, path, b"" if method in ("POST", "PUT", "PATCH") else None,
                          token=path.startswith("/api/") or None)
            self.assert_error(r, 405, "method")
            self.assertEqual(r.header("allow"), allow, (method, path))
        self.assertEqual(d.status()["scans_completed"], 0)

    def test_409_while_a_scan_runs(self):
        d = self.daemon
        # Long exposures keep the scan running through the refusals below on
        # a loaded machine: 17 frames of 120 ms each on the steady clock (with
        # 8 ms a scan once ended before the last refusal was answered).
        long_exposure = {"exposure_us": 120000}
        self.assertEqual(d.request("PUT", "/api/v1/settings", long_exposure).status, 200)
        with d.follow() as events:
            r = d.request("POST", "/api/v1/scans", {"mode": "scan"})
            self.assertEqual(r.status, 202, r)
            scan_id = r.json()["id"]
            table_before = s.read_bytes(d.table)
            self.assert_error(d.request("POST", "/api/v1/scans", {"mode": "capture"}), 409, "scan")
            self.assert_error(d.request("POST", "/api/v1/scans"), 409)
            self.assert_error(d.request("GET", "/api/v1/preview.png"), 409)
            self.assert_error(d.request("PUT", "/api/v1/settings", {"exposure_us": 4000}), 409)
            self.assert_error(d.request("PUT", "/api/v1/table", table_before,
                                        {"Content-Type": "application/octet-stream"}), 409)
            self.assertEqual(d.status()["state"], "scanning")
            events.wait_for(lambda e: e.name == "written" and e.data["id"] == scan_id, 120)
        self.assertEqual(d.get_json("/api/v1/settings"), long_exposure)
        self.assertEqual(d.request("PUT", "/api/v1/settings", {"exposure_us": 8000}).status, 200)
        self.assertFalse(os.path.exists(d.table + ".previous"))
        self.assertEqual(self.uploads_left(), [])
        self.assertEqual(self.store_scans(d).count(scan_id), 1)

    def test_two_posts_racing_one_202_one_409(self):
        d = self.daemon
        rounds = 8
        for k in range(rounds):
            barrier = threading.Barrier(2)
            answers = [None, None]

            def post(i):
                c = d.client()
                barrier.wait()
                answers[i] = c.request("POST", "/api/v1/scans", {"mode": "scan"})

            with d.follow() as events:
                threads = [threading.Thread(target=post, args=(i,)) for i in range(2)]
                for t in threads:
                    t.start()
                for t in threads:
                    t.join()
                codes = sorted(a.status for a in answers)
                self.assertEqual(codes, [202, 409], (k, answers))
                won = [a for a in answers if a.status == 202][0].json()["id"]
                events.wait_for(lambda e: e.name == "written" and e.data["id"] == won, 120)
                time.sleep(0.2)
                started = [e for e in events.snapshot() if e.name == "scan-started"]
            self.assertEqual([e.data["id"] for e in started], [won], k)

    def test_413_bodies_over_the_limits(self):
        d = self.daemon
        before = d.status()
        big = b'{"mode": "scan", "pad": "' + b"x" * (64 * 1024) + b'"}'
        status, _ = s.raw_exchange(
            d.port,
            b"POST /api/v1/scans HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer " + d.token.encode()
            + b"\r\nContent-Type: application/json\r\nContent-Length: " + str(len(big)).encode()
            + b"\r\nConnection: close\r\n\r\n" + big)
        self.assertEqual(status, 413)
        # Exactly at the limit: taken (and refused as JSON with an unknown key).
        at_limit = b'{"pad": "' + b"x" * (64 * 1024 - 11) + b'"}'
        self.assertEqual(len(at_limit), 64 * 1024)
        self.assert_error(d.request("POST", "/api/v1/scans", at_limit,
                                    {"Content-Type": "application/json"}), 400, "pad")
        # The same over the limit without a length (chunked): 413 with a JSON
        # reason, as soon as the body passes the limit.
        chunk = b"%x\r\n%s\r\n" % (len(big), big)
        status, raw = s.raw_exchange(
            d.port,
            b"POST /api/v1/scans HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer " + d.token.encode()
            + b"\r\nContent-Type: application/json\r\nTransfer-Encoding: chunked\r\n"
            b"Connection: close\r\n\r\n" + chunk + b"0\r\n\r\n")
        self.assertEqual(status, 413, raw[:300])
        self.assertIn("65536", json.loads(raw.split(b"\r\n\r\n", 1)[1])["error"])
        # A table over 64 bytes a pixel + 1 MiB, by its Content-Length: 413
        # before a byte of it is read, nothing installed.
        limit = 64 * 800 * 600 + (1 << 20)
        status, raw = s.raw_exchange(
            d.port,
            b"PUT /api/v1/table HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer " + d.token.encode()
            + b"\r\nContent-Type: application/octet-stream\r\nContent-Length: "
            + str(limit + 1).encode() + b"\r\nConnection: close\r\n\r\n" + b"\0" * 4096)
        self.assertEqual(status, 413, raw[:300])
        self.assertIn(str(limit).encode(), raw)
        # Chunked, 1 MiB a chunk: nothing stored past the limit, the rest
        # read and dropped, and a 413 when the body ends (libmicrohttpd 0.9.75
        # queues no answer while a body arrives); a body that goes on 8 MiB
        # past the limit loses its connection.
        for extra, answered in ((2, True), (3 * limit >> 20, False)):
            answer = self.chunked_table_upload(d, (limit >> 20) + extra)
            if answered:
                self.assertEqual(answer[:12], b"HTTP/1.1 413", answer[:300])
                self.assertIn(str(limit).encode(), answer)
            else:
                self.assertNotIn(b"HTTP/1.1 2", answer[:300])
        time.sleep(0.5)
        self.assertEqual(d.status()["table"], before["table"])
        self.assertEqual(self.uploads_left(), [])
        self.assertEqual(d.status()["scans_completed"], before["scans_completed"])


    @staticmethod
    def chunked_table_upload(d, mebibytes):
        """PUTs a chunked table of `mebibytes` chunks of 1 MiB; the answer."""
        piece = b"%x\r\n" % (1 << 20) + b"\0" * (1 << 20) + b"\r\n"
        head = (b"PUT /api/v1/table HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer "
                + d.token.encode() + b"\r\nContent-Type: application/octet-stream\r\n"
                b"Transfer-Encoding: chunked\r\nConnection: close\r\n\r\n")
        _, answer = s.raw_exchange(d.port, None, read_timeout=10,
                                   chunks=[head] + [piece] * mebibytes + [b"0\r\n\r\n"])
        return answer


class NoTable(DaemonCase):
    """A daemon whose --table file does not exist yet and without a settings
    file: capture only, until a table is installed."""

    @classmethod
    def setUpClass(cls):
        folder = s.fresh_dir("no-table")
        cls.daemon = cls.start_daemon(folder=folder, settings=False)

    def test_scan_409_without_table_capture_works_then_install(self):
        d = self.daemon
        self.assertTrue(d.logged("no table at " + d.table))
        st = d.status()
        self.assertIsNone(st["table"])
        self.assertIsNone(st["last_scan"])
        self.assert_error(d.request("GET", "/api/v1/table"), 404, "table")
        self.assert_error(d.request("POST", "/api/v1/scans", {"mode": "scan"}), 409, "table")
        self.assert_error(d.request("POST", "/api/v1/scans"), 409, "table")
        self.assertEqual(self.store_scans(d), [])
        _, events = d.scan("capture")
        scan_id = events[0].data["id"]
        self.assertEqual(events[-1].name, "written")
        self.assertEqual(events[-1].data["points"], 0)
        self.assert_error(d.request("GET", f"/api/v1/scans/{scan_id}/cloud.ply"), 404)
        r = d.request("GET", f"/api/v1/scans/{scan_id}/capture.tar")
        self.assertEqual(r.status, 200)
        self.assertIn("capture/capture.yaml", s.parse_tar(r.body)[0])
        with open(os.path.join(d.folder_of(scan_id), "scan.json")) as f:
            self.assertNotIn("table", json.load(f))
        # Installed from nothing: no previous file.
        r = d.request("PUT", "/api/v1/table", s.read_bytes(s.truth_table()),
                      {"Content-Type": "application/octet-stream"}, timeout=120)
        self.assertEqual(r.status, 200, r)
        self.assertEqual(r.json()["path"], d.table)
        self.assertFalse(os.path.exists(d.table + ".previous"))
        _, events = d.scan("scan")
        self.assertGreater(events[-1].data["points"], 250000)

    def test_settings_409_without_a_settings_file(self):
        d = self.daemon
        self.assert_error(d.request("PUT", "/api/v1/settings", {"exposure_us": 4000}), 409,
                          "settings")
        self.assertEqual(d.get_json("/api/v1/settings"), {"exposure_us": 8000})
        # Values are checked first all the same.
        self.assert_error(d.request("PUT", "/api/v1/settings", {"exposure_us": 1}), 400)


# ============================================================ bad requests


class BadRequests(DaemonCase):
    """Raw sockets: malformed requests, huge headers, path tricks, a cut
    upload, idle and surplus connections; then the daemon still scans. The
    board copy closes idle connections after 2 s and takes 8 at once."""

    TIMEOUT_S = 2
    MAX_CONNECTIONS = 8

    @classmethod
    def setUpClass(cls):
        folder = s.fresh_dir("bad-requests")
        s.copy_table(os.path.join(folder, "table.fpt"))
        board = s.board_copy(os.path.join(folder, "board.yaml"), http={
            "listen": "127.0.0.1:0", "token_file": os.path.join(folder, "token"),
            "timeout_s": cls.TIMEOUT_S, "max_connections": cls.MAX_CONNECTIONS})
        s.write_token(os.path.join(folder, "token"))
        cls.daemon = cls.start_daemon(folder=folder, board=board)
        # A scan to aim path tricks at (its folder is real).
        _, events = cls.daemon.scan("capture")
        cls.scan_id = events[0].data["id"]

    def auth(self):
        return b"Authorization: Bearer " + self.daemon.token.encode() + b"\r\n"

    def get_raw(self, target, auth=True):
        return s.raw_exchange(self.daemon.port, b"GET " + target + b" HTTP/1.1\r\nHost: x\r\n"
                              + (self.auth() if auth else b"") + b"Connection: close\r\n\r\n")

    def assert_served(self):
        r = self.daemon.request("GET", "/api/v1/status", timeout=5)
        self.assertEqual(r.status, 200)

    def test_malformed_request_lines(self):
        for line in (b"GARBAGE\r\n\r\n", b"GET\r\n\r\n", b"GET /api/v1/status\r\n\r\n",
                     b"GET /api/v1/status HTTP/9.9\r\nHost: x\r\n\r\n",
                     b"GET  HTTP/1.1\r\nHost: x\r\n\r\n",
                     b"\x00\x01\x02\x03\r\n\r\n", b"GET /api/v1/status HTTP/1.1\r\nNoColon\r\n\r\n",
                     b"G\xc3\xa9T / HTTP/1.1\r\nHost: x\r\n\r\n",

                     b"GET /api/v1/status HTTP/1.1\r\nHost: x\r\nContent-Length: -5\r\n\r\n",
                     b"POST /api/v1/scans HTTP/1.1\r\nHost: x\r\nContent-Length: 10\r\n"
                     b"Transfer-Encoding: chunked\r\n\r\n0\r\n\r\n"):
            with self.subTest(line=line[:40]):
                status, raw = s.raw_exchange(self.daemon.port, line, read_timeout=4,
                                             shut_write=True)
                self.assertTrue(status is None or 400 <= status < 600, raw[:300])
                self.assertNotIn(b'"api":1', raw)
        self.assert_served()
        self.assertEqual(self.daemon.status()["scans_completed"], 1)

    def test_bodies_that_are_not_utf8_are_400_with_a_json_reason(self):
        # Found by tests/fuzz/fuzz_http_api: the parse error quotes the bad
        # bytes, and writing that reason as JSON failed: a 500.
        for method, target, body in (
                (b"POST", b"/api/v1/scans", b'{"mo\xff\xff\xff\xffd'),
                (b"PUT", b"/api/v1/settings", b'{"\xc3\x28": 1}'),
                (b"POST", b"/api/v1/sessions", b'{"name": "a\xfe"}')):
            with self.subTest(target=target, body=body):
                status, raw = s.raw_exchange(
                    self.daemon.port, method + b" " + target + b" HTTP/1.1\r\nHost: x\r\n"
                    + self.auth() + b"Content-Type: application/json\r\nContent-Length: "
                    + str(len(body)).encode() + b"\r\nConnection: close\r\n\r\n" + body)
                self.assertEqual(status, 400, raw[:300])
                reason = json.loads(raw.split(b"\r\n\r\n", 1)[1])["error"]
                self.assertTrue(reason, raw[:300])
        self.assert_served()

    def test_long_targets_and_header_blocks_are_414_and_431_as_json(self):
        # Within the connection's 64 KiB: the daemon's own JSON answer.
        first = b"GET /api/v1/status HTTP/1.1\r\nHost: x\r\n" + self.auth()
        for request, code in (
                (b"GET /" + b"a" * (9 * 1024) + b" HTTP/1.1\r\nHost: x\r\n\r\n", 414),
                (first + b"X-Big: " + b"a" * (20 * 1024) + b"\r\n\r\n", 431),
                (first + b"".join(b"X-H%d: %s\r\n" % (i, b"b" * 100) for i in range(200))
                 + b"\r\n", 431)):
            with self.subTest(code=code, size=len(request)):
                status, raw = s.raw_exchange(self.daemon.port, request, read_timeout=5)
                self.assertEqual(status, code, raw[:300])
                self.assertIn("at most", json.loads(raw.split(b"\r\n\r\n", 1)[1])["error"])
        # Beyond it, libmicrohttpd answers (or drops) before the daemon sees it.
        for headers in (b"X-Big: " + b"a" * (80 * 1024) + b"\r\n",
                        b"".join(b"X-H%d: %s\r\n" % (i, b"b" * 100) for i in range(800)),
                        b"GET /" + b"a" * (80 * 1024)):
            request = (headers + b" HTTP/1.1\r\n\r\n") if headers.startswith(b"GET") \
                else first + headers + b"\r\n"
            status, raw = s.raw_exchange(self.daemon.port, request, read_timeout=5)
            self.assertTrue(status is None or 400 <= status < 500, raw[:300])
        self.assert_served()

    def test_path_tricks_stay_in_the_store(self):
        sid = self.scan_id.encode()
        targets = [b"/api/v1/scans/..%2f..%2fetc%2fpasswd", b"/api/v1/scans/..%2f..%2fetc",
                   b"/api/v1/scans/%2e%2e/%2e%2e/etc/passwd", b"/api/v1/scans/%2e%2e",
                   b"/api/v1/scans//etc/passwd", b"/api/v1/scans/%2Fetc%2Fpasswd",
                   b"/api/v1/scans/../../../etc/passwd", b"/api/v1/../../etc/passwd",
                   b"/api/v1/scans/" + sid + b"/../../../../etc/passwd",
                   b"/api/v1/scans/" + sid + b"/..%2f..%2f..%2fetc%2fpasswd",
                   b"/api/v1/scans/" + sid + b"/%2e%2e",
                   b"/api/v1/scans/" + sid + b"/capture%2fcapture.yaml",
                   b"/api/v1/scans/" + sid + b"%00/cloud.ply",
                   b"/api/v1/scans/" + sid + b"/..",
                   b"/api/v1/scans/scan-20260101-000000-000%2f..%2f..%2f..%2fetc",
                   b"/api/v1/sessions/..%2f..%2f..%2fetc/session.tar",
                   b"/api/v1/sessions/%2e%2e/session.tar", b"/api/v1/sessions/..",
                   b"/api/v1/sessions/%2fetc/session.tar",
                   b"/api/v1/sessions/x/poses/..%2f..%2f" + sid + b"/texture.png",
                   b"/three/../../etc/passwd", b"/three/..%2f..%2f..%2f..%2fetc%2fpasswd",
                   b"/three/%2e%2e/%2e%2e/%2e%2e/%2e%2e/etc/passwd", b"/../etc/passwd",
                   b"/..%2fetc%2fpasswd", b"/%2e%2e/%2e%2e/etc/passwd", b"//etc/passwd",
                   b"/etc/passwd", b"/index.html/../../../etc/passwd", b"/./index.html/.."]
        for target in targets:
            for auth in (True, False):
                with self.subTest(target=target, auth=auth):
                    status, raw = self.get_raw(target, auth)
                    ok = (400, 404) if auth or not target.startswith(b"/api/") else (401,)
                    self.assertIn(status, ok, raw[:300])
                    self.assertNotIn(b"root:", raw)
                    self.assertNotIn(b"fpp-capture", raw)
        self.assertTrue(os.path.isdir(self.daemon.folder_of(self.scan_id)))
        # A raw NUL byte in the URL: libmicrohttpd 0.9.75 hands the handler
        # a C string, cut at the NUL, so what is answered is what the part
        # before it names (the page, here) and never anything past it.
        index = s.read_bytes(os.path.join(s.BOARDS, "..", "firmware", "scanner", "web",
                                          "index.html"))
        for target in (b"/index.html\x00/../../../../etc/passwd", b"/\x00../../etc/passwd",
                       b"/three/\x00../../../etc/passwd"):
            status, raw = self.get_raw(target, auth=False)
            self.assertNotIn(b"root:", raw)
            if status == 200:
                self.assertTrue(raw.endswith(index), raw[:300])
            else:
                self.assertTrue(status is None or 400 <= status < 500, raw[:300])
        # DELETE with tricks removes nothing outside either.
        for target in (b"/api/v1/scans/..%2fstore", b"/api/v1/scans/..", b"/api/v1/sessions/..",
                       b"/api/v1/sessions/%2e%2e", b"/api/v1/scans/" + sid + b"/..",
                       b"/api/v1/scans/" + sid + b"%00/x", b"/api/v1/scans/" + sid + b"%00"):
            status, raw = s.raw_exchange(
                self.daemon.port, b"DELETE " + target + b" HTTP/1.1\r\nHost: x\r\n" + self.auth()
                + b"Connection: close\r\n\r\n")
            self.assertIn(status, (400, 404, 405), raw[:300])
        self.assertTrue(os.path.isdir(self.daemon.store))
        self.assertTrue(os.path.isdir(self.daemon.folder_of(self.scan_id)))
        self.assertTrue(os.path.exists(self.daemon.table))

    def test_table_upload_cut_half_way_installs_nothing(self):
        d = self.daemon
        before = d.status()["table"]
        good = s.read_bytes(s.truth_table("paper-rig.yaml", 2))
        folder = os.path.dirname(d.table)
        sock = socket.create_connection(("127.0.0.1", d.port), timeout=10)
        sock.sendall(b"PUT /api/v1/table HTTP/1.1\r\nHost: x\r\n" + self.auth()
                     + b"Content-Type: application/octet-stream\r\nContent-Length: "
                     + str(len(good)).encode() + b"\r\n\r\n")
        sock.sendall(good[:len(good) // 2])
        # The spool file exists while the upload runs ...
        deadline = time.monotonic() + 5
        while not [n for n in os.listdir(folder) if n.startswith(".upload-")]:
            self.assertLess(time.monotonic(), deadline, "no .upload-* file while uploading")
            time.sleep(0.05)
        sock.close()
        # ... and is gone within a second after the client went away.
        self.assertEqual(self.uploads_left(wait_s=1.0), [])
        self.assertEqual(d.status()["table"], before)
        self.assertEqual(s.fnv1a64(s.read_bytes(d.table)), before["file_fnv1a64"])
        self.assertFalse(os.path.exists(d.table + ".previous"))

    def test_idle_connection_closed_after_the_timeout_others_served(self):
        d = self.daemon
        idle = socket.create_connection(("127.0.0.1", d.port), timeout=30)
        half = socket.create_connection(("127.0.0.1", d.port), timeout=30)
        half.sendall(b"GET /api/v1/status HTTP/1.1\r\nHost: x\r\n")  # never ends its headers
        opened = time.monotonic()
        # Meanwhile others are served.
        for _ in range(5):
            self.assert_served()
        closed = {}
        for name, sock in (("idle", idle), ("half", half)):
            try:
                data = sock.recv(4096)
            except ConnectionResetError:
                data = b""
            closed[name] = time.monotonic() - opened
            self.assertNotIn(b"200 OK", data)
            sock.close()
        # Not before the timeout; the upper bound only has to tell "closed by
        # the timeout" from "never closed" (the socket's own 30 s), with room
        # for a machine loaded by other tests.
        for name, after in closed.items():
            self.assertGreater(after, self.TIMEOUT_S - 0.5, (name, after))
            self.assertLess(after, self.TIMEOUT_S + 10, (name, after))
        self.assert_served()

    def test_more_connections_than_the_limit_wait_or_are_refused(self):
        d = self.daemon
        idle = [socket.create_connection(("127.0.0.1", d.port), timeout=30)
                for _ in range(self.MAX_CONNECTIONS)]
        time.sleep(0.2)
        # One more: refused (closed) or served once an idle one times out;
        # never a hang beyond the timeout.
        started = time.monotonic()
        try:
            r = d.request("GET", "/api/v1/status", timeout=self.TIMEOUT_S + 15)
            outcome = r.status
        except (ConnectionError, OSError) as e:
            outcome = type(e).__name__
        waited = time.monotonic() - started
        self.assertIn(outcome, (200, "ConnectionResetError", "RemoteDisconnected",
                                "ConnectionAbortedError", "BrokenPipeError"), outcome)
        self.assertLess(waited, self.TIMEOUT_S + 10)  # as above: not a hang
        for sock in idle:
            sock.close()
        time.sleep(0.3)
        self.assert_served()
        self.assertTrue(d.logged("connection limit") or outcome == 200, outcome)

    def test_zz_after_all_of_it_the_daemon_still_scans(self):
        # Named to run last in this class (unittest sorts by name).
        d = self.daemon
        _, events = d.scan("scan")
        self.assertEqual(events[-1].name, "written")
        self.assertGreater(events[-1].data["points"], 250000)
        self.assertEqual(d.status()["state"], "idle")
        self.assertEqual(d.logged("error:"), [])


GROUPS = {"Refusals": ["Refusals", "NoTable"], "BadRequests": ["BadRequests"]}

if __name__ == "__main__":
    s.main(GROUPS)
