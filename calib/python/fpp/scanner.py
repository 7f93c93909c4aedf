"""The scanner's HTTP API from Python (firmware/scanner/http-api.md), on the
standard library alone: urllib for requests, the server-sent event stream
read line by line."""

import io
import json
import os
import socket
import tarfile
import urllib.error
import urllib.parse
import urllib.request


class ScannerError(Exception):
    """The scanner refused a request or could not be reached.

    str(e) is the API's own message ({"error": ...}) or what went wrong on
    the way; `status` is the HTTP status (None when there was no answer:
    unreachable, gone, timed out), `message` the API's message alone.
    """

    def __init__(self, message, status=None):
        super().__init__(message if status is None else f"HTTP {status}: {message}")
        self.status = status
        self.message = message


class Scanner:
    """A client of one scanner head's HTTP API.

    url: the scanner's address, e.g. 'http://scanner.local:8080'.
    token: the API token (the first line of the board's token file).
    timeout: seconds to wait for an answer, and for a sign of life (an event
      or the keep-alive the scanner sends every 10 s) on the event stream;
      default 30, the scanner's own idle timeout. A scanner that goes away
      raises ScannerError within it; Ctrl-C interrupts any blocking call.

    Every call raises ScannerError carrying the API's message on a refusal
    (e.g. 409 'a scan is running'), or why the scanner could not be reached.
    """

    def __init__(self, url, token, timeout=30.0):
        if not isinstance(url, str) or not url.startswith(("http://", "https://")):
            raise ValueError(f"url: expected 'http://HOST:PORT', got {url!r}")
        if not isinstance(token, str) or not token:
            raise ValueError("token: expected the API token (a non-empty string)")
        self.url = url.rstrip("/")
        self.token = token.strip()
        self.timeout = float(timeout)

    def __repr__(self):
        return f"<fpp.Scanner {self.url}>"

    # ---------------------------------------------------------------- plumbing

    def _open(self, method, path, body=None, content_type=None, timeout=None):
        headers = {"Authorization": "Bearer " + self.token}
        data = None
        if body is not None:
            if isinstance(body, (bytes, bytearray)):
                data = bytes(body)
                headers["Content-Type"] = content_type or "application/octet-stream"
            else:
                data = json.dumps(body).encode()
                headers["Content-Type"] = "application/json"
        request = urllib.request.Request(self.url + path, data=data, method=method,
                                         headers=headers)
        try:
            return urllib.request.urlopen(request, timeout=timeout or self.timeout)
        except urllib.error.HTTPError as e:
            raw = e.read()
            try:
                message = json.loads(raw)["error"]
            except (ValueError, KeyError, TypeError):
                message = raw.decode("utf-8", "replace").strip() or e.reason
            raise ScannerError(message, e.code) from None
        except (urllib.error.URLError, OSError) as e:
            reason = getattr(e, "reason", e)
            raise ScannerError(f"{self.url}: cannot reach the scanner: {reason}") from None

    def _request(self, method, path, body=None, content_type=None):
        with self._open(method, path, body, content_type) as r:
            try:
                raw = r.read()
            except (OSError, socket.timeout) as e:
                raise ScannerError(f"{self.url}{path}: the answer was cut off: {e}") from None
            if not raw:
                return None
            if r.headers.get_content_type() == "application/json":
                return json.loads(raw)
            return raw

    @staticmethod
    def _quote(name):
        return urllib.parse.quote(str(name), safe="")

    # ---------------------------------------------------------------- status

    def status(self):
        """The scanner's status (GET /api/v1/status) as a dict: state ('idle',
        'scanning', 'error'), camera, display, table (None when none is
        installed), store, last_scan, ..."""
        return self._request("GET", "/api/v1/status")

    def settings(self):
        """The settings in force, e.g. {'exposure_us': 8000}."""
        return self._request("GET", "/api/v1/settings")

    def set_exposure(self, exposure_us):
        """Sets the camera exposure (microseconds, 10..1000000) from the next
        frame on; returns the settings now in force."""
        return self._request("PUT", "/api/v1/settings", {"exposure_us": exposure_us})

    # ---------------------------------------------------------------- events

    def events(self, timeout=None):
        """The scanner's events as they come: a generator of (name, data)
        pairs (data a dict), starting with one 'state' event. Raises
        ScannerError when the stream ends (the scanner went away) or nothing,
        not even its 10-second keep-alive, arrives for `timeout` seconds
        (default: the client's). Close the generator to close the stream."""
        wait = float(timeout or self.timeout)
        response = self._open("GET", "/api/v1/events", timeout=wait)
        name, data = None, []
        try:
            while True:
                try:
                    line = response.readline()
                except (socket.timeout, TimeoutError):
                    raise ScannerError(f"{self.url}: no event or keep-alive for {wait:g} s: "
                                       "the scanner does not answer") from None
                except OSError as e:
                    raise ScannerError(f"{self.url}: the event stream broke: {e}") from None
                if not line:
                    raise ScannerError(f"{self.url}: the scanner closed the event stream "
                                       "(it stopped or restarted)")
                line = line.decode("utf-8", "replace").rstrip("\r\n")
                if not line:
                    if name is not None or data:
                        text = "\n".join(data)
                        try:
                            payload = json.loads(text) if text else {}
                        except ValueError:
                            payload = {"text": text}
                        yield name or "message", payload
                    name, data = None, []
                elif line.startswith(":"):
                    continue  # keep-alive
                elif line.startswith("event:"):
                    name = line[6:].strip()
                elif line.startswith("data:"):
                    data.append(line[5:].lstrip(" "))
        finally:
            response.close()

    def _run_and_follow(self, path, body, progress, timeout):
        """POSTs `path` (a scan or a pose) and follows its events to the end:
        the 'written' event's data, or ScannerError with the 'failed' one's."""
        stream = self.events(timeout)
        try:
            next(stream)  # the 'state' event: the stream is open before the scan starts
            started = self._request("POST", path, body)
            scan_id = started["id"]
            for name, data in stream:
                if data.get("id") != scan_id:
                    continue
                if progress is not None:
                    progress(name, data)
                if name == "written":
                    return data
                if name == "failed":
                    raise ScannerError(f"scan {scan_id} failed: {data.get('error')}")
        finally:
            stream.close()
        raise ScannerError("the event stream ended")  # not reached: events() raises first

    # ---------------------------------------------------------------- scans

    def scan(self, mode="scan", progress=None, wait=True, timeout=None):
        """Runs a scan, as a press of the scanner's button does.

        mode: 'scan' (decoded and reconstructed: needs an installed table) or
          'capture' (the frames alone, for calibration or the host's decode).
        progress: optional callable(name, data) called with each of the scan's
          events: 'scan-started', 'frame-captured' ({'frame', 'frames'}),
          'decoded', 'written'.
        wait: False returns at once with {'id', 'mode'} (follow events()).
        timeout: seconds without any sign of life before giving up (default:
          the client's).

        Returns the 'written' event's data: {'id', 'mode', 'points', 'quality',
        'session'}. Raises ScannerError with the API's message (409: a scan is
        running, no table installed), the scan's error when it failed, or when
        the scanner goes away; KeyboardInterrupt on Ctrl-C.
        """
        if mode not in ("scan", "capture"):
            raise ValueError(f"mode: expected 'scan' or 'capture', got {mode!r}")
        if not wait:
            return self._request("POST", "/api/v1/scans", {"mode": mode})
        return self._run_and_follow("/api/v1/scans", {"mode": mode}, progress, timeout)

    def list(self):
        """The scans in the store, newest first: a list of dicts {'id', 'mode',
        'started_utc', 'points', 'quality', 'bytes', 'cloud', 'capture'}."""
        return self._request("GET", "/api/v1/scans")["scans"]

    def scan_info(self, scan_id):
        """A scan's scan.json as a dict (its decode report, quality, ...)."""
        return self._request("GET", "/api/v1/scans/" + self._quote(scan_id))

    def delete(self, scan_id):
        """Deletes a scan from the scanner's store."""
        self._request("DELETE", "/api/v1/scans/" + self._quote(scan_id))

    def download_cloud(self, scan_id, path):
        """Saves a scan's cloud.ply (byte for byte) at `path`; returns the path
        (read it with fpp.read_ply). 404 (ScannerError) for a capture-mode scan."""
        data = self._request("GET", f"/api/v1/scans/{self._quote(scan_id)}/cloud.ply")
        with open(path, "wb") as f:
            f.write(data)
        return os.fspath(path)

    def download_capture(self, scan_id, folder):
        """Saves a capture-mode scan's capture set into the new folder `folder`
        (capture.yaml and its frames); returns the folder, ready for
        fpp.read_capture. 404 (ScannerError) for a scan-mode scan."""
        data = self._request("GET", f"/api/v1/scans/{self._quote(scan_id)}/capture.tar")
        _extract(data, "capture/", folder)
        return os.fspath(folder)

    # ---------------------------------------------------------------- sessions

    def sessions(self):
        """The calibration sessions: a list of {'name', 'poses', 'created_utc'}."""
        return self._request("GET", "/api/v1/sessions")["sessions"]

    def session(self, name):
        """One session: {'name', 'board_yaml', 'poses': [{'id', 'started_utc'}]}."""
        return self._request("GET", "/api/v1/sessions/" + self._quote(name))

    def create_session(self, name, board_yaml=None):
        """Creates a calibration session; board_yaml is the board's description
        (format fpp-board/1; a simulated session board may leave it out)."""
        body = {"name": name}
        if board_yaml is not None:
            body["board_yaml"] = board_yaml
        return self._request("POST", "/api/v1/sessions", body)

    def add_pose(self, name, progress=None, timeout=None):
        """Records a pose (a capture-mode scan) into session `name`, blocking
        as scan() does; returns the 'written' event's data."""
        return self._run_and_follow(f"/api/v1/sessions/{self._quote(name)}/poses", None,
                                    progress, timeout)

    def delete_session(self, name):
        """Deletes a session and its poses."""
        self._request("DELETE", "/api/v1/sessions/" + self._quote(name))

    def download_session(self, name, folder):
        """Saves a session (board.yaml and every pose's capture set) into the
        new folder `folder`, as fpp-calib calibrate reads it; returns it."""
        data = self._request("GET", f"/api/v1/sessions/{self._quote(name)}/session.tar")
        _extract(data, f"{name}/", folder)
        return os.fspath(folder)

    # ---------------------------------------------------------------- table

    def install_table(self, path):
        """Uploads and installs a coefficient table (.fpt); the scanner checks
        it against its camera and display first (400 with the loader's message
        otherwise, the table in use kept). Returns the status's new 'table'."""
        with open(path, "rb") as f:
            data = f.read()
        return self._request("PUT", "/api/v1/table", data, "application/octet-stream")


def _extract(data, prefix, folder):
    """The files of a tar archive under `prefix`, into the new `folder`; no
    member may leave it (absolute paths, '..', links are refused)."""
    folder = os.fspath(folder)
    os.makedirs(folder)
    root = os.path.realpath(folder)
    with tarfile.open(fileobj=io.BytesIO(data)) as archive:
        for member in archive.getmembers():
            if not member.name.startswith(prefix):
                continue
            relative = member.name[len(prefix):]
            target = os.path.realpath(os.path.join(root, relative))
            if not relative or member.issym() or member.islnk() or \
                    os.path.commonpath([root, target]) != root:
                if member.isdir() and relative in ("", "/"):
                    continue
                raise ScannerError(f"the archive holds an unsafe member: {member.name!r}")
            if member.isdir():
                os.makedirs(target, exist_ok=True)
            elif member.isfile():
                os.makedirs(os.path.dirname(target), exist_ok=True)
                with archive.extractfile(member) as src, open(target, "wb") as dst:
                    dst.write(src.read())
