#!/usr/bin/python3
"""fpp-scanner's HTTP API (firmware/scanner/http-api.md) against the real
daemon on the simulated board, on loopback: every endpoint (the refusals and
bad requests are test_api_refusals.py).

    python3 test_api.py --scanner BUILD/firmware/scanner/fpp-scanner \
        --table-tool BUILD/tests/fpp_test_truth_table --boards REPO/board \
        --tmp SCRATCH [EveryEndpoint | Class.test_name ...]

The sim board's button cannot be pressed from outside the daemon: the race
of a press and a request is tests/integration/scanner/test_scanner_service.cpp.
"""

import hashlib
import json
import os
import re
import sys
import time

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import api_support as s  # noqa: E402

ISO_UTC = re.compile(r"^\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ$")
HEX16 = re.compile(r"^[0-9a-f]{16}$")
DaemonCase = s.DaemonCase


# ============================================================ every endpoint


class Scans(DaemonCase):
    """Status, scans in both modes with their events and files, preview, the
    page's static files."""

    @classmethod
    def setUpClass(cls):
        folder = s.fresh_dir("scans")
        s.copy_table(os.path.join(folder, "table.fpt"))
        cls.daemon = cls.start_daemon(folder=folder)

    def test_status_fields_and_types(self):
        d = self.daemon
        st = d.status()
        self.assertEqual(set(st), {"api", "state", "error", "board", "camera", "display",
                                   "sequence", "table", "store", "last_scan", "scans_completed"})
        self.assertEqual(st["api"], 1)
        self.assertEqual(st["state"], "idle")
        self.assertIsNone(st["error"])
        # sim.yaml has no session board of its own (sim-checkerboard-session.yaml has).
        self.assertEqual(st["board"], {"name": "sim", "simulated": True, "session_board": False})
        self.assertEqual(st["camera"], {"width": 800, "height": 600, "bit_depth": 8,
                                        "pixel_format": "Mono8", "exposure_us": 8000})
        self.assertEqual(st["display"], {"width": 1280, "height": 800})
        self.assertEqual(st["sequence"]["name"], "gray-x")
        self.assertIsInstance(st["sequence"]["frames"], int)
        self.assertGreaterEqual(st["sequence"]["frames"], 10)
        t = st["table"]
        self.assertEqual(t["path"], d.table)
        self.assertEqual(t["model"], "rational")
        self.assertEqual(t["camera"], {"width": 800, "height": 600})
        self.assertEqual(t["projector"], {"width": 1280, "height": 800})
        self.assertEqual(t["bytes"], os.path.getsize(d.table))
        self.assertRegex(t["file_fnv1a64"], HEX16)
        self.assertRegex(t["calibration_fnv1a64"], HEX16)
        self.assertIsNone(t["trueness"])  # the rig's exact table: no calibration's uncertainty
        self.assertRegex(t["installed_utc"], ISO_UTC)
        self.assertRegex(t["created_utc"], ISO_UTC)
        store = st["store"]
        self.assertEqual(store["directory"], d.store)
        self.assertEqual(store["max_bytes"], 256 * 1024 * 1024)  # sim.yaml's max_mb
        for key in ("used_bytes", "scans", "sessions"):
            self.assertIsInstance(store[key], int)
            self.assertGreaterEqual(store[key], 0)
        self.assertEqual(store["scans"], len(self.store_scans(d)))
        self.assertIsInstance(st["scans_completed"], int)
        if st["scans_completed"] == 0:
            self.assertIsNone(st["last_scan"])
        else:
            last = st["last_scan"]
            self.assertEqual(set(last),
                             {"id", "mode", "ok", "points", "quality", "error", "session"})
            self.assertRegex(last["id"], s.SCAN_ID)
            self.assertIn(last["mode"], ("scan", "capture"))
            self.assertIsInstance(last["ok"], bool)
            self.assertIsInstance(last["points"], int)

    def test_table_hash_in_status_is_the_files_fnv1a64(self):
        st = self.daemon.status()
        self.assertEqual(st["table"]["file_fnv1a64"], s.fnv1a64(s.read_bytes(self.daemon.table)))

    def follow_scan(self, body, expect_mode):
        """POST /scans with `body`, every event of it in order; checks the
        202 answer and the events."""
        d = self.daemon
        frames = d.status()["sequence"]["frames"]
        with d.follow() as events:
            first = events.snapshot()[0]
            self.assertEqual(events.content_type, "text/event-stream")
            self.assertEqual((first.name, first.data), ("state", {"state": "idle", "error": None}))
            r = d.request("POST", "/api/v1/scans", body)
            self.assertEqual(r.status, 202, r)
            answer = r.json()
            self.assertEqual(set(answer), {"id", "mode"})
            self.assertEqual(answer["mode"], expect_mode)
            scan_id = answer["id"]
            self.assertRegex(scan_id, s.SCAN_ID)
            self.assertEqual(r.header("location"), "/api/v1/scans/" + scan_id)
            events.wait_for(lambda e: e.name == "written" and e.data["id"] == scan_id, 120)
            events.wait_for(lambda e: e.name == "state" and e.data["state"] == "idle"
                            and e is not first, 10)
            seen = events.snapshot()[1:]
        mine = [e for e in seen if e.name != "state"]
        self.assertTrue(all(e.data["id"] == scan_id for e in mine), mine)
        names = [e.name for e in mine]
        self.assertEqual(names, ["scan-started"] + ["frame-captured"] * frames
                         + ["decoded", "written"], names)
        self.assertEqual(mine[0].data, {"id": scan_id, "mode": expect_mode, "frames": frames,
                                        "source": "api", "session": None})
        self.assertEqual([e.data["frame"] for e in mine[1:1 + frames]], list(range(1, frames + 1)))
        self.assertTrue(all(e.data["frames"] == frames for e in mine[1:1 + frames]))
        written = mine[-1].data
        self.assertEqual(set(written), {"id", "mode", "points", "quality", "session"})
        self.assertEqual(set(written["quality"]), {"good", "coverage", "reasons", "advice"})
        self.assertEqual((written["mode"], written["session"]), (expect_mode, None))
        states = [e.data for e in seen if e.name == "state"]
        self.assertEqual(states, [{"state": "scanning", "error": None},
                                  {"state": "idle", "error": None}])
        return scan_id, written, frames

    def check_listed_and_scan_json(self, scan_id, mode, points, frames):
        d = self.daemon
        folder = d.folder_of(scan_id)
        self.assertTrue(os.path.isdir(folder))
        listing = d.get_json("/api/v1/scans")["scans"]
        ids = [e["id"] for e in listing]
        self.assertEqual(ids[0], scan_id, "newest first")
        self.assertEqual(ids, sorted(ids, reverse=True))
        self.assertEqual(sorted(ids), self.store_scans(d))
        entry = listing[0]
        self.assertEqual(set(entry), {"id", "mode", "started_utc", "points", "quality", "bytes",
                                      "cloud", "capture"})
        self.assertEqual(entry["mode"], mode)
        self.assertRegex(entry["started_utc"], ISO_UTC)
        self.assertEqual(entry["points"], points)
        self.assertEqual(entry["bytes"], sum(len(b) for b in s.files_under(folder).values()))
        self.assertIs(entry["cloud"], True)
        self.assertIs(entry["capture"], mode == "capture")
        r = d.request("GET", "/api/v1/scans/" + scan_id)
        self.assertEqual(r.status, 200, r)
        self.assertEqual(r.header("content-type"), "application/json")
        on_disk = s.read_bytes(os.path.join(folder, "scan.json"))
        self.assertEqual(r.body, on_disk, "scan.json as written")
        meta = r.json()
        self.assertEqual(meta, json.loads(on_disk))
        self.assertEqual((meta["mode"], meta["points"], meta["frames"]), (mode, points, frames))
        self.assertEqual(meta["started_utc"], entry["started_utc"])
        self.assertEqual(len(meta["flips"]), frames)
        return meta

    def check_cloud(self, scan_id):
        d = self.daemon
        r = d.request("GET", f"/api/v1/scans/{scan_id}/cloud.ply")
        self.assertEqual(r.status, 200, r)
        self.assertEqual(r.header("content-type"), "application/octet-stream")
        self.assertEqual(r.header("content-disposition"),
                         f'attachment; filename="{scan_id}-cloud.ply"')
        self.assertTrue(r.body.startswith(b"ply\n"))
        self.assertEqual(hashlib.sha256(r.body).hexdigest(),
                         s.sha256_file(os.path.join(d.folder_of(scan_id), "cloud.ply")))

    def check_deleted(self, scan_id):
        d = self.daemon
        with d.follow() as events:
            r = d.request("DELETE", "/api/v1/scans/" + scan_id)
            self.assertEqual(r.status, 204, r)
            # Every client hears of it (the page drops the scan and its cloud).
            events.wait_for(lambda e: e.name == "deleted"
                            and e.data == {"id": scan_id, "session": None}, 10)
        self.assertEqual(r.body, b"")
        self.assertFalse(os.path.exists(d.folder_of(scan_id)))
        for path in ("", "/cloud.ply", "/capture.tar", "/texture.png"):
            self.assert_error(d.request("GET", f"/api/v1/scans/{scan_id}{path}"), 404, scan_id)
        self.assert_error(d.request("DELETE", "/api/v1/scans/" + scan_id), 404, scan_id)
        self.assertNotIn(scan_id, [e["id"] for e in d.get_json("/api/v1/scans")["scans"]])

    def test_scan_mode_events_list_files_delete(self):
        d = self.daemon
        before = d.status()
        scan_id, written, frames = self.follow_scan({"mode": "scan"}, "scan")
        # The composite scene fills most of the 800 x 600 image.
        self.assertGreater(written["points"], 250000)
        meta = self.check_listed_and_scan_json(scan_id, "scan", written["points"], frames)
        self.assertEqual(meta["table"]["path"], d.table)
        self.assertEqual(meta["table"]["file_fnv1a64"], before["table"]["file_fnv1a64"])
        st = d.status()
        self.assertEqual(st["state"], "idle")
        self.assertEqual(st["scans_completed"], before["scans_completed"] + 1)
        self.assertEqual(st["last_scan"], {"id": scan_id, "mode": "scan", "ok": True,
                                           "points": written["points"],
                                           "quality": written["quality"], "error": None,
                                           "session": None})
        self.assertTrue(written["quality"]["good"], written["quality"])
        self.check_cloud(scan_id)
        # A scan-mode scan has no capture set, so no texture either.
        self.assert_error(d.request("GET", f"/api/v1/scans/{scan_id}/capture.tar"), 404,
                          "capture")
        self.assert_error(d.request("GET", f"/api/v1/scans/{scan_id}/texture.png"), 404)
        self.assert_error(d.request("GET", f"/api/v1/scans/{scan_id}/nope.bin"), 404)
        self.check_deleted(scan_id)

    def test_capture_mode_capture_tar_and_texture(self):
        d = self.daemon
        scan_id, written, frames = self.follow_scan({"mode": "capture"}, "capture")
        self.assertGreater(written["points"], 250000)  # a table is installed: a cloud too
        self.check_listed_and_scan_json(scan_id, "capture", written["points"], frames)
        self.check_cloud(scan_id)
        folder = d.folder_of(scan_id)
        r = d.request("GET", f"/api/v1/scans/{scan_id}/capture.tar")
        self.assertEqual(r.status, 200, r)
        self.assertEqual(r.header("content-type"), "application/x-tar")
        members, order = s.parse_tar(r.body)
        on_disk = s.files_under(os.path.join(folder, "capture"), "capture/")
        frame_names = [f"capture/{i:03d}.png" for i in range(frames)]
        self.assertEqual(sorted(members), sorted(["capture/capture.yaml"] + frame_names))
        self.assertEqual(sorted(members), sorted(on_disk))
        self.assertEqual(order, sorted(order))
        for name, data in members.items():
            self.assertEqual(data, on_disk[name], name)
        # gray-x starts with the white frame: the texture is 000.png.
        manifest = members["capture/capture.yaml"].decode()
        self.assertLess(manifest.find("white"), manifest.find("black"), manifest[:800])
        texture = d.request("GET", f"/api/v1/scans/{scan_id}/texture.png")
        self.assertEqual(self.assert_png(texture), s.CAMERA)
        self.assertEqual(texture.body, on_disk["capture/000.png"])
        self.check_deleted(scan_id)

    def test_empty_body_is_a_scan_and_bad_bodies_are_400(self):
        d = self.daemon
        before = d.status()["scans_completed"]
        folders = self.store_scans(d)
        for body, part in ((b'{"mode": "nope"}', "mode"), (b'{"mode": 1}', "mode"),
                           (b'{"mode": null}', "mode"), (b'{"other": 1}', "other"),
                           (b'{"mode": "scan", "x": 2}', "x"), (b"[]", "object"),
                           (b'"scan"', "object"), (b"not json", "JSON"), (b"{", "JSON")):
            self.assert_error(d.request("POST", "/api/v1/scans", body,
                                        {"Content-Type": "application/json"}), 400, part)
        self.assertEqual(d.status()["scans_completed"], before)
        self.assertEqual(self.store_scans(d), folders)
        scan_id, written, frames = self.follow_scan(None, "scan")
        self.assertGreater(written["points"], 250000)
        self.check_deleted(scan_id)

    def test_preview_png_and_levels(self):
        r = self.daemon.request("GET", "/api/v1/preview.png")
        self.assertEqual(self.assert_png(r), s.CAMERA)
        saturated = float(r.header("x-preview-saturated"))
        mean = float(r.header("x-preview-mean"))
        self.assertGreaterEqual(saturated, 0.0)
        self.assertLessEqual(saturated, 1.0)
        # The scene under the white pattern at 8 ms: lit, mostly unsaturated.
        self.assertGreater(mean, 0.1)
        self.assertLess(mean, 0.95)
        self.assertLess(saturated, 0.5)
        self.assertEqual(self.daemon.status()["state"], "idle")

    def test_events_keep_alive_every_10_s(self):
        d = self.daemon
        with d.follow() as events:
            time.sleep(10.8)
            self.assertEqual(events.comments, 1)
            self.assertEqual([e.name for e in events.snapshot()], ["state"])
            self.assertIsNone(events.error)

    def test_page_files_need_no_token(self):
        d = self.daemon
        for path, ctype in (("/", "text/html"), ("/index.html", "text/html"),
                            ("/app.js", "text/javascript"), ("/viewer.js", "text/javascript"),
                            ("/session.js", "text/javascript"),
                            ("/style.css", "text/css")):
            r = d.request("GET", path, token=None)
            self.assertEqual(r.status, 200, (path, r))
            self.assertTrue(r.header("content-type").startswith(ctype), (path, r.headers))
            self.assertIn("default-src 'self'", r.header("content-security-policy"))
            self.assertEqual(r.header("x-content-type-options"), "nosniff")
        if os.path.exists("/usr/share/javascript/three/build/three.module.js"):
            r = d.request("GET", "/three/build/three.module.js", token=None)
            self.assertEqual(r.status, 200, r)
            self.assertEqual(r.body, s.read_bytes("/usr/share/javascript/three/build/three.module.js"))
        for path in ("/nope.html", "/secret.txt", "/web/index.html", "/.hidden.js"):
            self.assertEqual(d.request("GET", path, token=None).status, 404, path)
        r = d.request("HEAD", "/index.html", token=None)
        self.assertEqual((r.status, r.body), (200, b""))
        self.assertTrue(r.header("content-type").startswith("text/html"))

    def test_page_files_revalidate_and_three_js_is_cached(self):
        # The page is revalidated on every load (no-cache + ETag: 304 while
        # unchanged); three.js is kept a week. A reload transfers headers only.
        d = self.daemon
        paths = ["/", "/app.js", "/session.js", "/viewer.js", "/style.css"]
        three = "/usr/share/javascript/three/build/three.module.js"
        if os.path.exists(three):
            paths.append("/three/build/three.module.js")
        for path in paths:
            with self.subTest(path=path):
                first = d.request("GET", path, token=None)
                etag = first.header("etag")
                self.assertEqual(first.status, 200)
                self.assertRegex(etag or "", r'^"[0-9a-f]+-[0-9a-f]+"$')
                self.assertEqual(first.header("cache-control"),
                                 "public, max-age=604800" if path.startswith("/three/")
                                 else "no-cache")
                again = d.request("GET", path, None, {"If-None-Match": etag}, token=None)
                self.assertEqual((again.status, again.body), (304, b""))
                self.assertEqual(again.header("etag"), etag)
                other = d.request("GET", path, None, {"If-None-Match": '"0-0"'}, token=None)
                self.assertEqual(other.status, 200)
                self.assertEqual(other.body, first.body)
        # The API is never cached.
        self.assertEqual(d.request("GET", "/api/v1/status").header("cache-control"), "no-store")


class Settings(DaemonCase):
    @classmethod
    def setUpClass(cls):
        folder = s.fresh_dir("settings")
        s.copy_table(os.path.join(folder, "table.fpt"))
        cls.daemon = cls.start_daemon(folder=folder)

    def test_settings_put_persists_and_survives_a_restart(self):
        d = self.daemon
        self.assertEqual(d.get_json("/api/v1/settings"), {"exposure_us": 8000})
        mean_before = float(d.request("GET", "/api/v1/preview.png").header("x-preview-mean"))
        with d.follow() as events:
            r = d.request("PUT", "/api/v1/settings", {"exposure_us": 2500})
            self.assertEqual(r.status, 200, r)
            self.assertEqual(r.json(), {"exposure_us": 2500})
            events.wait_for(lambda e: e.name == "settings" and e.data == {"exposure_us": 2500}, 10)
        with open(d.settings) as f:
            text = f.read()
        m = re.fullmatch(r"format: fpp-scanner-settings/1\nexposure_us: (\S+)\n", text)
        self.assertTrue(m, text)
        self.assertEqual(float(m.group(1)), 2500)
        self.assertEqual(d.get_json("/api/v1/settings"), {"exposure_us": 2500})
        self.assertEqual(d.status()["camera"]["exposure_us"], 2500)
        # Used from the next frame on: a third of the light.
        mean_after = float(d.request("GET", "/api/v1/preview.png").header("x-preview-mean"))
        self.assertLess(mean_after, 0.6 * mean_before, (mean_before, mean_after))
        # ... and in the next scan.
        _, events = d.scan("scan")
        scan_id = events[0].data["id"]
        with open(os.path.join(d.folder_of(scan_id), "scan.json")) as f:
            self.assertEqual(json.load(f)["camera"]["exposure_us"], 2500)
        # A restart keeps it.
        self.assertEqual(d.stop(), 0)
        d.start()
        self.assertEqual(d.get_json("/api/v1/settings"), {"exposure_us": 2500})
        self.assertEqual(d.status()["camera"]["exposure_us"], 2500)
        r = d.request("PUT", "/api/v1/settings", {"exposure_us": 8000})
        self.assertEqual((r.status, r.json()), (200, {"exposure_us": 8000}))

    def test_scans_are_judged_and_poor_ones_say_what_to_do(self):
        # Every scan is written; scan.json, the `written` event, the last
        # scan in the status and the scan list say whether it is good, and a
        # poor one why and what to do, in plain words.
        d = self.daemon

        def scan_at(exposure_us):
            self.assertEqual(d.request("PUT", "/api/v1/settings",
                                       {"exposure_us": exposure_us}).status, 200)
            _, events = d.scan()
            written = [e for e in events if e.name == "written"]
            self.assertEqual(len(written), 1, events)
            quality = written[0].data["quality"]
            with open(os.path.join(d.folder_of(written[0].data["id"]), "scan.json")) as f:
                self.assertEqual(json.load(f)["quality"], quality)
            self.assertEqual(d.status()["last_scan"]["quality"], quality)
            listed = {e["id"]: e for e in d.get_json("/api/v1/scans")["scans"]}
            self.assertEqual(listed[written[0].data["id"]]["quality"], quality)
            return written[0].data, quality

        good, quality = scan_at(8000)
        self.assertTrue(quality["good"], quality)
        self.assertGreater(quality["coverage"], 0.3)
        self.assertEqual((quality["reasons"], quality["advice"]), ([], ""))
        dark, quality = scan_at(100)
        self.assertFalse(quality["good"], quality)
        self.assertIn("Raise the exposure (now 100 us)", quality["advice"])
        self.assertTrue(any("last good scan (" + good["id"] + ")" in r
                            for r in quality["reasons"]), quality)
        bright, quality = scan_at(200000)
        self.assertFalse(quality["good"], quality)
        self.assertIn("of the lit pixels are saturated", quality["reasons"][0])
        self.assertIn("Lower the exposure (now 200 ms)", quality["advice"])
        d.request("PUT", "/api/v1/settings", {"exposure_us": 8000})

    def test_settings_bad_values_are_400_and_change_nothing(self):
        d = self.daemon
        now = d.get_json("/api/v1/settings")
        file_before = s.read_bytes(d.settings) if os.path.exists(d.settings) else None
        for body, part in ((b'{"exposure_us": 9}', "exposure_us"),
                           (b'{"exposure_us": 1000001}', "exposure_us"),
                           (b'{"exposure_us": -5}', "exposure_us"),
                           (b'{"exposure_us": 1e400}', None),
                           (b'{"exposure_us": "8000"}', "exposure_us"),
                           (b'{"exposure_us": null}', "exposure_us"),
                           (b'{"exposure_us": true}', "exposure_us"),
                           (b'{"exposure_us": [8000]}', "exposure_us"),
                           (b"{}", "exposure_us"),
                           (b'{"exposure_us": 8000, "gain": 2}', "gain"),
                           (b'{"gain": 2}', "gain"),
                           (b"exposure_us=8000", "JSON")):
            self.assert_error(d.request("PUT", "/api/v1/settings", body,
                                        {"Content-Type": "application/json"}), 400, part)
        self.assertEqual(d.get_json("/api/v1/settings"), now)
        self.assertEqual(s.read_bytes(d.settings) if os.path.exists(d.settings) else None,
                         file_before)
        # The limits themselves are taken.
        for value in (10, 1000000, now["exposure_us"]):
            r = d.request("PUT", "/api/v1/settings", {"exposure_us": value})
            self.assertEqual((r.status, r.json()), (200, {"exposure_us": value}))


class Table(DaemonCase):
    """PUT/GET /table: a good table installed (the previous kept), bad ones
    refused with the loader's message and the table in use unchanged."""

    @classmethod
    def setUpClass(cls):
        folder = s.fresh_dir("table")
        s.copy_table(os.path.join(folder, "table.fpt"))
        cls.daemon = cls.start_daemon(folder=folder)
        # A second valid table for the same camera and display: the truth
        # of the ideal rig (no distortion; same sizes).
        cls.other = s.truth_table("paper-rig.yaml", 2)
        cls.effects = s.truth_table("paper-rig-effects.yaml", 2)

    def put_table(self, data, headers=None):
        h = {"Content-Type": "application/octet-stream"}
        h.update(headers or {})
        return self.daemon.request("PUT", "/api/v1/table", data, h, timeout=120)

    def test_get_table_returns_the_installed_bytes(self):
        d = self.daemon
        r = d.request("GET", "/api/v1/table")
        self.assertEqual(r.status, 200, r)
        self.assertEqual(r.header("content-type"), "application/octet-stream")
        self.assertEqual(r.body, s.read_bytes(d.table))
        self.assertEqual(d.status()["table"]["file_fnv1a64"], s.fnv1a64(r.body))

    def test_put_good_table_installs_it_and_keeps_the_previous(self):
        d = self.daemon
        old = s.read_bytes(d.table)
        old_hash = d.status()["table"]["file_fnv1a64"]
        new = s.read_bytes(self.other if old == s.read_bytes(self.effects) else self.effects)
        self.assertNotEqual(new, old)
        with d.follow() as events:
            r = self.put_table(new)
            self.assertEqual(r.status, 200, r)
            t = r.json()
            events.wait_for(lambda e: e.name == "table", 10)
            table_event = [e for e in events.snapshot() if e.name == "table"]
        self.assertEqual(t, d.status()["table"])
        self.assertNotEqual(t["file_fnv1a64"], old_hash)
        self.assertEqual(t["file_fnv1a64"], s.fnv1a64(new))
        self.assertEqual((t["path"], t["bytes"], t["model"]), (d.table, len(new), "rational"))
        self.assertEqual(t["camera"], {"width": 800, "height": 600})
        self.assertEqual([e.data for e in table_event],
                         [{"model": "rational", "file_fnv1a64": t["file_fnv1a64"]}])
        self.assertEqual(s.read_bytes(d.table), new)
        self.assertEqual(s.read_bytes(d.table + ".previous"), old)
        self.assertEqual(d.request("GET", "/api/v1/table").body, new)
        self.assertEqual(self.uploads_left(), [])
        # The next scan uses it.
        _, events = d.scan("scan")
        with open(os.path.join(d.folder_of(events[0].data["id"]), "scan.json")) as f:
            meta = json.load(f)
        self.assertEqual(meta["table"]["file_fnv1a64"], t["file_fnv1a64"])
        self.assertEqual(meta["table"]["path"], d.table)
        self.assertGreater(meta["points"], 250000)
        # The same bytes again: installed, hash as before, previous = the same.
        r = self.put_table(new)
        self.assertEqual((r.status, r.json()["file_fnv1a64"]), (200, t["file_fnv1a64"]))
        self.assertEqual(s.read_bytes(d.table + ".previous"), new)
        # And back to the first: its hash again.
        r = self.put_table(old)
        self.assertEqual((r.status, r.json()["file_fnv1a64"]), (200, old_hash))
        self.assertEqual(s.read_bytes(d.table + ".previous"), new)

    def test_bad_tables_are_400_and_the_table_in_use_stays(self):
        d = self.daemon
        good = s.read_bytes(d.table)
        status_before = d.status()["table"]
        previous = s.read_bytes(d.table + ".previous") if os.path.exists(
            d.table + ".previous") else None
        flipped = bytearray(good)
        flipped[len(good) // 2] ^= 0x5A
        header_flipped = bytearray(good)
        header_flipped[20] ^= 0x01
        small = s.read_bytes(s.truth_table("paper-rig-effects.yaml", 4))  # 400 x 300 camera
        cases = [
            ("a byte flipped in a tile", bytes(flipped), "crc"),
            ("a byte flipped in the header", bytes(header_flipped), None),
            ("truncated to half", good[:len(good) // 2], "truncated"),
            ("truncated inside the header", good[:40], "truncated"),
            ("one byte too many", good + b"\0", "extra bytes"),
            ("not a table", b"hello, scanner\n" * 100, "magic"),
            ("for a 400 x 300 camera", small, "camera_size"),
        ]
        for what, data, part in cases:
            with self.subTest(what):
                r = self.put_table(data)
                self.assert_error(r, 400, part)
                self.assertEqual(d.status()["table"], status_before)
                self.assertEqual(self.uploads_left(), [])
        self.assert_error(self.put_table(b""), 400, ".fpt")
        self.assertEqual(s.read_bytes(d.table), good)
        self.assertEqual(d.request("GET", "/api/v1/table").body, good)
        self.assertEqual(s.read_bytes(d.table + ".previous") if os.path.exists(
            d.table + ".previous") else None, previous)
        # The scanner still scans with the table in use.
        _, events = d.scan("scan")
        with open(os.path.join(d.folder_of(events[0].data["id"]), "scan.json")) as f:
            meta = json.load(f)
        self.assertEqual(meta["table"]["file_fnv1a64"], status_before["file_fnv1a64"])
        self.assertGreater(meta["points"], 250000)


class Sessions(DaemonCase):
    """Calibration sessions on the checkerboard session board (it gives its
    own board_yaml)."""

    @classmethod
    def setUpClass(cls):
        folder = s.fresh_dir("sessions")
        cls.daemon = cls.start_daemon(
            folder=folder, board=os.path.join(s.BOARDS, "sim-checkerboard-session.yaml"),
            table=False)

    def session_dir(self, name):
        return os.path.join(self.daemon.store, "sessions", name)

    def test_session_names_and_bodies(self):
        d = self.daemon
        for name in ("../x", ".hidden", "x" * 65, "", "a/b", "a b", "ä", "x\n", "..", "."):
            self.assert_error(d.request("POST", "/api/v1/sessions", {"name": name}), 400, "name")
        for body, part in (({}, "name"), ({"name": 7}, "name"), ({"name": "ok", "x": 1}, "x"),
                           ({"name": "ok", "board_yaml": 3}, "board_yaml"),
                           ({"name": "ok", "board_yaml": "format: nope\n"}, "board_yaml")):
            self.assert_error(d.request("POST", "/api/v1/sessions", body), 400, part)
        self.assertFalse(os.path.exists(self.session_dir("ok")))
        longest = "A" + "b-_.9" * 12 + "xyz"
        self.assertEqual(len(longest), 64)
        r = d.request("POST", "/api/v1/sessions", {"name": longest})
        self.assertEqual((r.status, r.json()), (201, {"name": longest, "poses": 0}))
        self.assertEqual(d.request("DELETE", "/api/v1/sessions/" + longest).status, 204)
        for path in ("/api/v1/sessions/..", "/api/v1/sessions/.hidden",
                     "/api/v1/sessions/nope", "/api/v1/sessions/nope/session.tar",
                     "/api/v1/sessions/" + "x" * 65):
            self.assertEqual(d.request("GET", path).status, 404, path)
        self.assert_error(d.request("POST", "/api/v1/sessions/nope/poses"), 404, "nope")

    def test_session_create_poses_tar_delete(self):
        d = self.daemon
        name = "cb-01"
        r = d.request("POST", "/api/v1/sessions", {"name": name})
        self.assertEqual(r.status, 201, r)
        self.assertEqual(r.json(), {"name": name, "poses": 0})
        board_yaml = s.read_bytes(os.path.join(self.session_dir(name), "board.yaml")).decode()
        self.assertIn("fpp-board/1", board_yaml)
        self.assert_error(d.request("POST", "/api/v1/sessions", {"name": name}), 409, name)
        listed = d.get_json("/api/v1/sessions")["sessions"]
        entry = [e for e in listed if e["name"] == name]
        self.assertEqual(len(entry), 1, listed)
        self.assertEqual(entry[0]["poses"], 0)
        self.assertRegex(entry[0].get("created_utc", ""), ISO_UTC, entry[0])
        self.assertEqual(d.status()["store"]["sessions"], len(listed))

        ids = []
        for k in range(3):
            with d.follow() as events:
                r = d.request("POST", f"/api/v1/sessions/{name}/poses")
                self.assertEqual(r.status, 202, r)
                answer = r.json()
                self.assertEqual(set(answer), {"id", "session"})
                self.assertEqual(answer["session"], name)
                self.assertRegex(answer["id"], s.SCAN_ID)
                self.assertEqual(r.header("location"),
                                 f"/api/v1/sessions/{name}/poses/{answer['id']}")
                w = events.wait_for(lambda e: e.name == "written"
                                    and e.data["id"] == answer["id"], 120)
                started = events.wait_for(lambda e: e.name == "scan-started", 1)
            self.assertEqual((w.data["mode"], w.data["session"]), ("capture", name))
            self.assertEqual((started.data["source"], started.data["session"]), ("api", name))
            ids.append(answer["id"])
            self.assertTrue(os.path.isdir(os.path.join(self.session_dir(name), answer["id"])))
        # Poses go into the session, not the store's scans.
        self.assertEqual([n for n in os.listdir(d.store) if n.startswith("scan-")], [])
        self.assertEqual(d.get_json("/api/v1/scans"), {"scans": []})

        session = d.get_json(f"/api/v1/sessions/{name}")
        self.assertEqual(session["name"], name)
        self.assertEqual(session["board_yaml"], board_yaml)
        self.assertEqual([p["id"] for p in session["poses"]], ids)
        for p in session["poses"]:
            self.assertRegex(p["started_utc"], ISO_UTC)
        self.assertEqual([e["poses"] for e in d.get_json("/api/v1/sessions")["sessions"]
                          if e["name"] == name], [3])

        pose_dir = os.path.join(self.session_dir(name), ids[0])
        r = d.request("GET", f"/api/v1/sessions/{name}/poses/{ids[0]}")
        self.assertEqual((r.status, r.body), (200, s.read_bytes(os.path.join(pose_dir, "scan.json"))))
        texture = d.request("GET", f"/api/v1/sessions/{name}/poses/{ids[0]}/texture.png")
        self.assertEqual(self.assert_png(texture), s.CAMERA)
        # gray-xy starts with the white frame.
        self.assertEqual(texture.body, s.read_bytes(os.path.join(pose_dir, "capture", "000.png")))
        # No table on this board: no cloud.
        self.assertEqual(d.request("GET", f"/api/v1/sessions/{name}/poses/{ids[0]}/cloud.ply")
                         .status, 404)

        with d.follow() as events:
            r = d.request("DELETE", f"/api/v1/sessions/{name}/poses/{ids[1]}")
            self.assertEqual(r.status, 204, r)
            events.wait_for(lambda e: e.name == "deleted"
                            and e.data == {"id": ids[1], "session": name}, 10)
        self.assertFalse(os.path.exists(os.path.join(self.session_dir(name), ids[1])))
        self.assertEqual(d.request("DELETE", f"/api/v1/sessions/{name}/poses/{ids[1]}").status,
                         404)
        kept = [ids[0], ids[2]]
        self.assertEqual([p["id"] for p in d.get_json(f"/api/v1/sessions/{name}")["poses"]], kept)

        r = d.request("GET", f"/api/v1/sessions/{name}/session.tar")
        self.assertEqual(r.status, 200, r)
        self.assertEqual(r.header("content-type"), "application/x-tar")
        members, order = s.parse_tar(r.body)
        on_disk = s.files_under(self.session_dir(name), name + "/")
        self.assertEqual(sorted(members), sorted(on_disk))
        self.assertEqual(order, sorted(order))
        self.assertIn(f"{name}/board.yaml", members)
        frames = d.status()["sequence"]["frames"]
        for pose in kept:
            self.assertIn(f"{name}/{pose}/scan.json", members)
            self.assertIn(f"{name}/{pose}/capture/capture.yaml", members)
            for i in range(frames):
                self.assertIn(f"{name}/{pose}/capture/{i:03d}.png", members)
        self.assertFalse(any(ids[1] in m for m in members))
        for m, data in members.items():
            self.assertEqual(data, on_disk[m], m)

        with d.follow() as events:
            r = d.request("DELETE", f"/api/v1/sessions/{name}")
            self.assertEqual(r.status, 204, r)
            events.wait_for(lambda e: e.name == "deleted"
                            and e.data == {"id": None, "session": name}, 10)
        self.assertFalse(os.path.exists(self.session_dir(name)))
        self.assertEqual(d.request("GET", f"/api/v1/sessions/{name}").status, 404)
        self.assertEqual(d.request("DELETE", f"/api/v1/sessions/{name}").status, 404)
        self.assertNotIn(name, [e["name"] for e in d.get_json("/api/v1/sessions")["sessions"]])


GROUPS = {"EveryEndpoint": ["Scans", "Settings", "Table", "Sessions"]}

if __name__ == "__main__":
    s.main(GROUPS)
