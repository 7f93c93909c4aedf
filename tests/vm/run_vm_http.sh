#!/usr/bin/env bash
# The scanner's HTTP API and page on the virtual ARM board, reached from this
# machine as from a laptop on the scanner's network: the arm64 fpp-scanner
# runs as a daemon in the VM on the simulated board (board/sim.yaml, camera
# binned 4 x 4) with the `http` and `settings` sections of the shipped
# board/rpi5.yaml (0.0.0.0:8080, the token in /etc/fpp-scanner/token, the
# table and settings in /var/lib/fpp-scanner, as the package lays them out),
# the page where the package puts it beside the binary
# (/fpp/bin/../share/fpp-scanner/web) and Debian's three.js in
# /usr/share/javascript/three. Its table is calibrated here first (the
# scanner records a checkerboard session, `fpp-calib calibrate`), the guest's
# port 8080 is forwarded to a free port of 127.0.0.1 (QEMU user network), and
# from here:
#   GET /api/v1/status with the token: 200, JSON with "state" and the table;
#   without it, or with a wrong one: 401;
#   the page and three.js without a token: 200;
#   tests/browser/test_page.py --url (chromium: token, scan, viewer, PLY
#   download compared with the guest's store, which is the host's /out);
#   PUT /api/v1/settings and PUT /api/v1/table: installed in the guest's
#   /var/lib/fpp-scanner (the previous table kept as table.fpt.previous);
# then the daemon is stopped (SIGTERM) and must exit 0.
# Usage: tests/vm/run_vm_http.sh HOST_BUILD [AARCH64_BUILD] [--keep DIR]
#   HOST_BUILD     this machine's build folder (fpp-scanner, fpp-calib)
#   AARCH64_BUILD  default: build/aarch64 of this tree
#   --keep DIR     keep the results there (console.log, scans, the browser's
#                  screenshots in DIR/browser)
# Exit status: 0 passed, 1 failed, 77 skipped (no QEMU, kernel cache, cross
# build with the HTTP API, host tools or curl; in CI a skip is a failure).
# Without chromium, chromedriver or selenium only the browser part is
# skipped (in CI that fails too, as test_page.py says).
set -euo pipefail
source_dir=$(cd "$(dirname "$0")/../.." && pwd)
host="" build="$source_dir/build/aarch64" keep=""
positional=()
while [ $# -gt 0 ]; do
  case "$1" in
    --keep) keep="$2"; shift 2 ;;
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
    *) positional+=("$1"); shift ;;
  esac
done
[ ${#positional[@]} -ge 1 ] || { echo "usage: $0 HOST_BUILD [AARCH64_BUILD] [--keep DIR]" >&2; exit 2; }
host="${positional[0]}"
[ ${#positional[@]} -lt 2 ] || build="${positional[1]}"
calib="$host/calib/fpp-calib"
test_name=run_vm_http
# shellcheck source=tests/vm/common.sh
source "$source_dir/tests/vm/common.sh"
scanner="$host/firmware/scanner/$(sim_scanner_name "$host")"
require_vm
require_arm64_scanner "$build"
# The guest's scanner runs the sim board: fpp-scanner-sim beside a device build's.
guest_scanner=$(sim_scanner_name "$build")
readelf -d "$build/firmware/scanner/$guest_scanner" | grep -q 'libmicrohttpd' ||
  skip "$build/firmware/scanner/$guest_scanner has no HTTP API (rebuild: cmake --workflow --preset aarch64)"
{ [ -x "$scanner" ] && [ -x "$calib" ]; } || skip "no host tools in $host"
command -v curl > /dev/null || skip "curl not installed"
three=/usr/share/javascript/three
[ -f "$three/build/three.min.js" ] || skip "no $three (apt-get install libjs-three)"
web="$source_dir/firmware/scanner/web"
[ -f "$web/index.html" ] || fail "no page in $web"

t_start=$EPOCHREALTIME
elapsed() { awk -v a="$t_start" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.1f", b - a }'; }
work=$(mktemp -d "${TMPDIR:-/tmp}/fpp-vm-http.XXXXXX")
out="${keep:-$work/out}"
vm_pid=""
# shellcheck disable=SC2317 # called by the EXIT trap
cleanup() {
  if [ -n "$vm_pid" ] && kill -0 "$vm_pid" 2> /dev/null; then
    : > "$out/stop" 2> /dev/null || true
    sleep 2
    kill "$vm_pid" 2> /dev/null || true
    wait "$vm_pid" 2> /dev/null || true
  fi
  rm -rf "$work"
}
trap cleanup EXIT
trap 'exit 130' INT TERM
rm -rf "$out/scans" "$out/fpp-scanner" "$out/stop" "$out/browser" "$out/console.log" "$out/forwards"
mkdir -p "$out"

# --- The table, calibrated here from a session the scanner records ---------
sed -e 's/^\(  binning:\) 2$/\1 4/' -e "s|rig: sim/|rig: $source_dir/board/sim/|" \
  "$source_dir/board/sim-checkerboard-session.yaml" > "$work/session-board.yaml"
grep -q '^  binning: 4$' "$work/session-board.yaml" ||
  fail "board/sim-checkerboard-session.yaml has no 'binning: 2' line"
"$scanner" --board "$work/session-board.yaml" --mode capture --scans 30 --store "$work/cb" \
  > /dev/null 2> "$work/host.log" || fail "checkerboard session (see $work/host.log)"
"$calib" calibrate "$work/cb" --out "$work/calib.yaml" --table "$work/table.fpt" \
  > /dev/null 2>> "$work/host.log" || { cat "$work/host.log"; fail "fpp-calib calibrate"; }
echo "run_vm_http: table calibrated here in $(elapsed) s"

# --- The guest's files --------------------------------------------------------
# The board: board/sim.yaml binned 4 x 4, its store the host's /out, its
# table where the package's boards keep it, and rpi5.yaml's http and
# settings sections as shipped.
files="$work/files"
mkdir -p "$files" "$work/etc" "$work/state"
cp -r "$source_dir/board/sim" "$files/sim"
sed -e 's/^\(  binning:\) 2$/\1 4/' \
  -e 's|^table: .*$|table: /var/lib/fpp-scanner/table.fpt|' \
  -e 's|^store: .*$|store: {directory: /out/scans, max_mb: 256}|' \
  "$source_dir/board/sim.yaml" > "$files/board.yaml"
sed -n '/^http:/,/^settings:/p' "$source_dir/board/rpi5.yaml" >> "$files/board.yaml"
grep -q '^  binning: 4$' "$files/board.yaml" || fail "board/sim.yaml has no 'binning: 2' line"
grep -q '^  listen: 0.0.0.0:8080$' "$files/board.yaml" || fail "board/rpi5.yaml does not listen on 0.0.0.0:8080"
grep -q '^  token_file: /etc/fpp-scanner/token$' "$files/board.yaml" ||
  fail "board/rpi5.yaml does not read /etc/fpp-scanner/token"
grep -q '^settings: /var/lib/fpp-scanner/settings.yaml$' "$files/board.yaml" ||
  fail "board/rpi5.yaml has no settings in /var/lib/fpp-scanner"
# The token as the package's postinst makes it.
od -An -tx1 -N32 /dev/urandom | tr -d ' \n' > "$work/etc/token"
echo >> "$work/etc/token"
token=$(cat "$work/etc/token")
cp "$work/table.fpt" "$work/state/table.fpt"
# The command: the daemon until this script creates /out/stop, then SIGTERM.
cat > "$files/until-stopped.sh" << 'EOF'
"$@" &
pid=$!
while [ ! -e /out/stop ] && kill -0 $pid 2> /dev/null; do sleep 0.2; done
kill -0 $pid 2> /dev/null && kill -TERM $pid
wait $pid
status=$?
echo "fpp-scanner exit status $status"
exit $status
EOF

# --- Boot, with the guest's 8080 forwarded here -------------------------------
"$source_dir/toolchain/vm/run-vm.sh" --build "$build" --files "$files" --out "$out" --quiet \
  --timeout 540 --forward 8080 \
  --tree "$web=/fpp/share/fpp-scanner/web" --tree "$three=$three" \
  --tree "$work/etc=/etc/fpp-scanner" --tree "$work/state=/var/lib/fpp-scanner" \
  --collect /var/lib/fpp-scanner \
  -- sh until-stopped.sh "$guest_scanner" --board board.yaml > "$work/run-vm.out" 2> "$work/run-vm.err" &
vm_pid=$!
show_console() { echo "--- guest console:"; grep -v '^fpp-vm-init: gpio line' "$out/console.log" || true; }
listening=""
for _ in $(seq 1 1800); do
  listening=$(grep -m 1 -o 'info: http: listening on [^ ]*' "$out/console.log" 2> /dev/null || true)
  [ -z "$listening" ] || break
  kill -0 "$vm_pid" 2> /dev/null || break
  sleep 0.1
done
if [ -z "$listening" ]; then
  show_console; cat "$work/run-vm.err"
  fail "the daemon never logged 'info: http: listening on' in the guest"
fi
port=$(awk '$1 == 8080 { print $2 }' "$out/forwards")
base="http://127.0.0.1:$port"
echo "run_vm_http: guest says '$listening' at $(elapsed) s; the host reaches it at $base"

# --- The API from here ----------------------------------------------------------
printf 'Authorization: Bearer %s\n' "$token" > "$work/auth"
printf 'Authorization: Bearer %s\n' "wrong-$token" > "$work/wrong-auth"
# http GET|PUT PATH [curl args]: prints the status code, the body to $work/body.
http() {
  curl -sS -m 60 -o "$work/body" -w '%{http_code}' -X "$1" "${@:3}" "$base$2" 2>> "$work/curl.log" || true
}
code=$(http GET /api/v1/status -H @"$work/auth")
[ "$code" = 200 ] || { cat "$work/body" "$work/curl.log" 2> /dev/null; fail "GET /api/v1/status with the token: $code"; }
python3 - "$work/body" << 'EOF' || fail "GET /api/v1/status: $(cat "$work/body")"
import json, sys
s = json.load(open(sys.argv[1]))
assert s["state"] in ("idle", "scanning", "error"), s["state"]
assert s["board"]["name"] == "sim", s["board"]
assert s["table"] and s["table"]["path"] == "/var/lib/fpp-scanner/table.fpt", s["table"]
print(f"run_vm_http: status 200: state {s['state']}, board {s['board']['name']}, camera "
      f"{s['camera']['width']} x {s['camera']['height']}, table {s['table']['path']}")
EOF
code=$(http GET /api/v1/status)
[ "$code" = 401 ] || fail "GET /api/v1/status without a token: $code, not 401"
code=$(http GET /api/v1/status -H @"$work/wrong-auth")
[ "$code" = 401 ] || fail "GET /api/v1/status with a wrong token: $code, not 401"
for path in / /three/build/three.min.js; do
  code=$(http GET "$path")
  { [ "$code" = 200 ] && [ -s "$work/body" ]; } || fail "GET $path without a token: $code"
done
cmp -s "$work/body" "$three/build/three.min.js" || fail "/three/build/three.min.js is not libjs-three's"
echo "run_vm_http: 401 without or with a wrong token; the page and three.js served at $(elapsed) s"

# --- The page in a browser --------------------------------------------------------
browser_test="$source_dir/tests/browser/test_page.py"
if [ -f "$browser_test" ]; then
  py=/usr/bin/python3 # Debian's, which has selenium
  [ -x "$py" ] || py=python3
  set +e
  "$py" "$browser_test" --url "$base" --token-file "$work/etc/token" --store "$out/scans" \
    --artifacts "$out/browser" 2>&1 | sed -u 's/^/  browser: /'
  status=${PIPESTATUS[0]}
  set -e
  case "$status" in
    0) echo "run_vm_http: the page works in chromium against the VM ($(elapsed) s)" ;;
    77) [ "${CI:-}" != true ] || fail "(CI) the browser test skipped"
        echo "run_vm_http: browser part skipped (see above)" ;;
    *) show_console; fail "tests/browser/test_page.py against the VM: status $status" ;;
  esac
else
  echo "run_vm_http: no tests/browser/test_page.py: browser part left out"
fi

# --- Settings and table installed in the guest's state folder ----------------------
code=$(http PUT /api/v1/settings -H @"$work/auth" -H 'Content-Type: application/json' \
  --data '{"exposure_us": 9000}')
{ [ "$code" = 200 ] && grep -q '"exposure_us": *9000' "$work/body"; } ||
  fail "PUT /api/v1/settings: $code $(cat "$work/body")"
code=$(http PUT /api/v1/table -H @"$work/auth" -H 'Content-Type: application/octet-stream' \
  --data-binary @"$work/table.fpt")
[ "$code" = 200 ] || fail "PUT /api/v1/table: $code $(cat "$work/body")"
echo "run_vm_http: settings and table installed through the API at $(elapsed) s"

# --- Stop --------------------------------------------------------------------------
: > "$out/stop"
status=0
wait "$vm_pid" || status=$?
vm_pid=""
if [ -n "$keep" ]; then cat "$work/run-vm.err"; else grep -v '^run-vm: results in' "$work/run-vm.err" || true; fi
case "$status" in
  0) ;;
  124) show_console; fail "the VM did not finish in time" ;;
  125) show_console; fail "the VM could not run the scanner" ;;
  *) show_console; fail "fpp-scanner exited with status $status in the guest (SIGTERM must give 0)" ;;
esac
state="$out/fpp-scanner"
grep -q 'exposure_us"\?: *9000' "$state/settings.yaml" 2> /dev/null ||
  fail "the guest's /var/lib/fpp-scanner/settings.yaml does not hold exposure_us 9000"
cmp -s "$state/table.fpt" "$work/table.fpt" || fail "the installed table differs from the one sent"
[ -f "$state/table.fpt.previous" ] || fail "no table.fpt.previous beside the installed table"
echo "run_vm_http: PASSED in $(elapsed) s"
