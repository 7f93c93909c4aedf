#!/usr/bin/env bash
# The scanner's Debian package on a booted Debian with systemd (13, the
# release the board files name; 12 with --suite bookworm), on the virtual
# ARM board (toolchain/vm/run-booted.sh: the disk that
# toolchain/vm/make-rootfs.sh built at install time, booted from a throwaway
# overlay). The package is the one --deb names (Debian 13's, which cpack
# makes in the Debian 13 root: the test command's trixie-aarch64 phase), or
# made here from the AArch64 build (cpack, as tests/package/check_deb.sh
# does); a copy is repacked at a newer version;
# the guest (tests/vm/booted-guest.sh, run by the disk's fpp-vm-hook.service)
# installs it with apt, offline, and the live checks are:
#   install: apt succeeds with the disk's packages alone; the unit is not
#     enabled by the package; the postinst's token is 64 hex digits,
#     root:fpp-scanner 0640; the user fpp-scanner is in video and gpio
#   service: with a board file for the virtual board (tests/vm/vm-hardware.yaml's
#     devices, Aravis's fake camera on the guest's loopback, rpi5.yaml's http
#     and settings) `systemctl enable --now` starts it as fpp-scanner, with
#     no capabilities, no_new_privs and a seccomp filter, / and /etc read-only
#   from here, through the forwarded port: /api/v1/status 200 with the
#     token, 401 without it or with a wrong one; the page and three.js 200;
#     a capture through the API (POST /api/v1/scans) lands in the scan store
#   systemd-analyze security on the running unit: its exposure at most
#     1.5, what it measures (check_deb.sh's offline bound is 2.0)
#   SocketBindDeny: a process placed in the unit's cgroup binds TCP 8081,
#     9000 or 0: EPERM where systemd enforces it (+BPF_FRAMEWORK: Debian
#     13's, required there); Debian 12's systemd is built without, and the
#     bind succeeds (asserted, reported); TCP 8080 is allowed (in use by the
#     scanner: EADDRINUSE), UDP is (port 0 and 40000: Aravis's GigE Vision
#     sockets); outside the cgroup 8081 binds
#   Restart=: after SIGKILL the main PID changes and the unit is active
#     again (RestartSec=3), listening again
#   the journal: the scanner's lines under its identifier, its warnings at
#     warning priority, the SIGKILL
#   upgrade to the newer version: token, edited board file and scan store
#     kept, the running service restarted on the new binary, the same token
#     still opens the API
#   remove, then purge: the token, /etc/fpp-scanner, the unit's
#     enablement link and the state folder (scans, table) go with the purge;
#     the system user stays
#     (board/debian/postrm: the scans are the user's data)
# Usage: tests/vm/run_vm_booted.sh [AARCH64_BUILD] [--suite trixie|bookworm]
#          [--deb FILE] [--keep DIR]
#   AARCH64_BUILD  the build the package is of (default: build/trixie-aarch64
#                  for trixie, build/aarch64 for bookworm)
#   --suite S      the disk's release (default trixie: CACHE/rootfs-trixie)
#   --deb PATH     the package, or the folder holding it (default: made with
#                  cpack from AARCH64_BUILD)
#   --keep DIR     keep the results there (console.log, guest.log, results,
#                  the journal, systemd-analyze security's table, apt logs)
# Exit status: 0 passed, 1 failed, 77 skipped (no QEMU, no disk in the VM
# cache, no cross build or cpack; in CI a skip is a failure).
set -euo pipefail
source_dir=$(cd "$(dirname "$0")/../.." && pwd)
build="" keep="" suite=trixie deb=""
# The running unit's exposure (systemd-analyze security), measured 1.5 on
# both disks (systemd 252 and 257): more is a loss of hardening.
exposure_max=1.5
positional=()
while [ $# -gt 0 ]; do
  case "$1" in
    --keep) keep="$2"; shift 2 ;;
    --suite) suite="$2"; shift 2 ;;
    --deb) deb="$2"; shift 2 ;;
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
    *) positional+=("$1"); shift ;;
  esac
done
case "$suite" in
  trixie) build="${positional[0]:-$source_dir/build/trixie-aarch64}" ;;
  bookworm) build="${positional[0]:-$source_dir/build/aarch64}" ;;
  *) echo "run_vm_booted: --suite trixie or bookworm" >&2; exit 2 ;;
esac
test_name=run_vm_booted
# shellcheck source=tests/vm/common.sh
source "$source_dir/tests/vm/common.sh"
require_vm
disk="$cache/rootfs-$suite"
{ [ -s "$disk/debian-arm64.img" ] && [ -s "$disk/boot-initrd.cpio" ]; } ||
  skip "no Debian $suite disk in $disk (toolchain/vm/make-rootfs.sh --suite $suite builds it)"
require_arm64_scanner "$build"
if [ -n "$deb" ]; then
  if [ -d "$deb" ]; then
    debs=("$deb"/fpp-scanner_*_arm64.deb)
    [ ${#debs[@]} -eq 1 ] || fail "${#debs[@]} fpp-scanner_*_arm64.deb in $deb, not one"
    deb=${debs[0]}
  fi
  [ -f "$deb" ] || skip "no package $deb (the test command's trixie-aarch64 phase makes it)"
else
  [ -f "$build/CPackConfig.cmake" ] || skip "no $build/CPackConfig.cmake"
  command -v cpack > /dev/null || skip "cpack not installed"
fi
command -v curl > /dev/null || skip "curl not installed"

t_start=$EPOCHREALTIME
elapsed() { awk -v a="$t_start" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.1f", b - a }'; }
work=$(mktemp -d "${TMPDIR:-/tmp}/fpp-vm-booted.XXXXXX")
out="${keep:-$work/out}"
vm_pid=""
# shellcheck disable=SC2317 # called by the EXIT trap
cleanup() {
  if [ -n "$vm_pid" ] && kill -0 "$vm_pid" 2> /dev/null; then
    kill "$vm_pid" 2> /dev/null || true
    wait "$vm_pid" 2> /dev/null || true
  fi
  rm -rf "$work"
}
trap cleanup EXIT
trap 'exit 130' INT TERM
rm -rf "$out"
mkdir -p "$out"

# --- The packages ---------------------------------------------------------------
in="$work/in"
mkdir -p "$in/new"
if [ -z "$deb" ]; then
  cpack --config "$build/CPackConfig.cmake" -B "$work/cpack" > "$work/cpack.log" 2>&1 ||
    { cat "$work/cpack.log"; fail "cpack in $build"; }
  deb=$(ls "$work"/cpack/fpp-scanner_*_arm64.deb)
fi
# The package must be of the build the test names (a stale one would pass
# unseen): the same GNU build id (the install drops the build's RUNPATH, so
# the bytes differ).
build_id() { readelf -n "$1" | sed -n 's/^ *Build ID: //p'; }
dpkg-deb --fsys-tarfile "$deb" | tar -xO ./usr/bin/fpp-scanner > "$work/packaged-scanner"
packaged_id=$(build_id "$work/packaged-scanner")
if [ -z "$packaged_id" ] || [ "$packaged_id" != "$(build_id "$build/firmware/scanner/fpp-scanner")" ]; then
  fail "$deb does not hold $build/firmware/scanner/fpp-scanner (GNU build ids differ)"
fi
version=$(dpkg-deb -f "$deb" Version)
cp "$deb" "$in/"
# The same package at a newer version (VERSION+1 sorts after VERSION).
dpkg-deb -R "$deb" "$work/repack"
sed -i "s/^Version: .*/Version: $version+1/" "$work/repack/DEBIAN/control"
dpkg-deb --root-owner-group -b "$work/repack" "$in/new/fpp-scanner_${version}+1_arm64.deb" > /dev/null
[ "$(dpkg-deb -f "$in/new/fpp-scanner_${version}+1_arm64.deb" Version)" = "$version+1" ] ||
  fail "the repacked package's version"
echo "run_vm_booted: $(basename "$deb") ($(stat -c %s "$deb") bytes) and $version+1 at $(elapsed) s"

# The board: tests/vm/vm-hardware.yaml's devices, the package's state folder,
# rpi5.yaml's http and settings sections as shipped.
sed -e 's|^store: .*$|table: /var/lib/fpp-scanner/table.fpt\nstore: {directory: /var/lib/fpp-scanner/scans, max_mb: 256}|' \
  "$source_dir/tests/vm/vm-hardware.yaml" > "$in/board.yaml"
sed -n '/^http:/,/^settings:/p' "$source_dir/board/rpi5.yaml" >> "$in/board.yaml"
grep -q '^  listen: 0.0.0.0:8080$' "$in/board.yaml" || fail "board/rpi5.yaml does not listen on 0.0.0.0:8080"
grep -q '^store: {directory: /var/lib/fpp-scanner/scans' "$in/board.yaml" ||
  fail "tests/vm/vm-hardware.yaml has no store line"
cp "$source_dir/tests/vm/booted-guest.sh" "$in/guest.sh"

# --- Boot ------------------------------------------------------------------------------
"$source_dir/toolchain/vm/run-booted.sh" --image "$disk/debian-arm64.img" --in "$in" --out "$out" \
  --forward 8080 --timeout 840 --quiet \
  > "$work/run-booted.out" 2> "$work/run-booted.err" &
vm_pid=$!
show_console() { echo "--- guest console (last 80 lines):"; tail -n 80 "$out/console.log" || true; }
# wait_guest NAME: until the guest writes /out/NAME.ready (1 when the VM ended first).
wait_guest() {
  while [ ! -e "$out/$1.ready" ]; do
    kill -0 "$vm_pid" 2> /dev/null || return 1
    sleep 0.2
  done
}
if ! wait_guest http; then
  show_console; cat "$work/run-booted.err"
  fail "the guest never got the service listening (see above)"
fi
t_http=$(elapsed)
port=$(awk '$1 == 8080 { print $2 }' "$out/forwards")
base="http://127.0.0.1:$port"
token=$(cat "$out/token")
printf 'Authorization: Bearer %s\n' "$token" > "$work/auth"
printf 'Authorization: Bearer %s\n' "wrong-$token" > "$work/wrong-auth"
# http METHOD PATH [curl args]: prints the status code, the body to $work/body.
http() {
  curl -sS -m 60 -o "$work/body" -w '%{http_code}' -X "$1" "${@:3}" "$base$2" 2>> "$work/curl.log" || true
}
host_results="$out/host-results"
: > "$host_results"
hres() { echo "$1=$2" >> "$host_results"; echo "run_vm_booted: host: $1=$2"; }
hres status_with_token "$(http GET /api/v1/status -H @"$work/auth")"
python3 - "$work/body" > "$work/status.txt" << 'EOF' || true
import json, sys
s = json.load(open(sys.argv[1]))
print(s["state"], s["board"]["name"], s["camera"]["width"], s["camera"]["height"], s["table"])
EOF
hres status_body "$(cat "$work/status.txt")"
hres status_without_token "$(http GET /api/v1/status)"
hres status_wrong_token "$(http GET /api/v1/status -H @"$work/wrong-auth")"
hres page "$(http GET /)"
hres three "$(http GET /three/build/three.min.js)"
hres three_bytes "$(stat -c %s "$work/body")"
hres scan_without_token "$(http POST /api/v1/scans -H 'Content-Type: application/json' --data '{"mode": "capture"}')"
hres scan_post "$(http POST /api/v1/scans -H @"$work/auth" -H 'Content-Type: application/json' \
  --data '{"mode": "capture"}')"
scan_id=$(python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["id"])' "$work/body" 2> /dev/null || true)
hres scan_id "$scan_id"
# The capture is done when the status names it as the last scan.
scan_state=timeout
if [ -n "$scan_id" ]; then
  for _ in $(seq 1 600); do
    http GET /api/v1/status -H @"$work/auth" > /dev/null
    scan_state=$(python3 -c 'import json, sys
s = json.load(open(sys.argv[1]))
l = s.get("last_scan") or {}
print("ok" if l.get("id") == sys.argv[2] and l.get("ok") else
      "failed: %s" % l.get("error") if l.get("id") == sys.argv[2] else "running")' "$work/body" "$scan_id" \
      2> /dev/null || echo running)
    [ "$scan_state" = running ] || break
    scan_state=timeout
    sleep 0.5
  done
fi
hres scan_state "$scan_state"
hres scan_listed "$(http GET /api/v1/scans -H @"$work/auth")"
hres scan_in_list "$(python3 -c 'import json, sys; print(sum(s["id"] == sys.argv[2] for s in json.load(open(sys.argv[1]))["scans"]))' \
  "$work/body" "$scan_id" 2> /dev/null || echo 0)"
hres capture_tar "$(http GET "/api/v1/scans/$scan_id/capture.tar" -H @"$work/auth")"
: > "$out/http.done"

if ! wait_guest upgraded; then
  show_console; fail "the guest did not reach the upgrade's check"
fi
hres status_after_upgrade "$(http GET /api/v1/status -H @"$work/auth")"
hres status_after_upgrade_without_token "$(http GET /api/v1/status)"
hres scan_in_list_after_upgrade "$(http GET /api/v1/scans -H @"$work/auth" > /dev/null
  python3 -c 'import json, sys; print(sum(s["id"] == sys.argv[2] for s in json.load(open(sys.argv[1]))["scans"]))' \
  "$work/body" "$scan_id" 2> /dev/null || echo 0)"
: > "$out/upgraded.done"

status=0
wait "$vm_pid" || status=$?
vm_pid=""
grep -v '^run-booted: the guest' "$work/run-booted.err" || true
case "$status" in
  0) ;;
  124) show_console; fail "the VM did not power off in time" ;;
  *) show_console; fail "the VM could not run (status $status)" ;;
esac
t_total=$(elapsed)

# --- The checks -------------------------------------------------------------------------
[ -s "$out/results" ] || { show_console; fail "the guest wrote no results"; }
failures=()
# check KEY EXPECTED [guest|host]: the value the guest (or host) wrote, exactly.
value() { sed -n "s/^$1=//p" "$out/${2:-results}" | tail -n 1; }
check() {
  local file=results got
  [ "${3:-guest}" = guest ] || file=host-results
  got=$(value "$1" "$file")
  [ "$got" = "$2" ] || failures+=("$1: '$got', expected '$2'")
}
# check_num KEY AWK-CONDITION-ON-v: a numeric value and its bound.
check_num() {
  local got
  got=$(value "$1")
  awk -v v="$got" "BEGIN { exit !(v ~ /^[0-9.]+\$/ && ($2)) }" || failures+=("$1: '$got', not $2")
}
check system_state running
check failed_units 0
check install_status 0
check installed "installed $version"
check enabled_after_install disabled
check active_after_install inactive
check token_stat "640 root fpp-scanner"
check token_format "1 1"
check user "fpp-scanner fpp-scanner gpio video "
check gpiochip_group "gpio 660"
check enable_status 0
check active active
check process_user fpp-scanner
check no_new_privs 1
check seccomp 2
check cap_eff 0000000000000000
check cap_bnd 0000000000000000
check ns_root_ro 1
check ns_etc_ro 1
check ns_home 0
check host_http "done"
check status_with_token 200 host
check status_without_token 401 host
check status_wrong_token 401 host
check page 200 host
check three 200 host
check three_bytes "$(stat -L -c %s /usr/share/javascript/three/build/three.min.js 2> /dev/null || value three_bytes host-results)" host
# "STATE BOARD WIDTH HEIGHT TABLE": the virtual board, no table yet.
[ "$(value status_body host-results | cut -d' ' -f2,5)" = "vm-hardware None" ] ||
  failures+=("status_body: '$(value status_body host-results)', not board vm-hardware without a table")
check scan_without_token 401 host
check scan_post 202 host
check scan_state ok host
check scan_in_list 1 host
check capture_tar 200 host
check security_status 0
exposure=$(value exposure)
awk -v e="${exposure%% *}" -v m="$exposure_max" 'BEGIN { exit !(e ~ /^[0-9.]+$/ && e <= m) }' ||
  failures+=("exposure: '$exposure', above $exposure_max")
check bind_outside_8081 0
bpf=$(value systemd_bpf_framework)
[ "$suite" = bookworm ] || [ "$bpf" = +BPF_FRAMEWORK ] ||
  failures+=("systemd_bpf_framework: '$bpf' on Debian $suite, whose systemd enforces SocketBindDeny")
case "$bpf" in
  +BPF_FRAMEWORK)
    check bind_unit_8081 1 # EPERM
    check bind_unit_9000 1
    check bind_unit_0 1 # the rules apply to port 0 too
    socket_bind="enforced: EPERM for TCP 8081, 9000 and 0; UDP free" ;;
  -BPF_FRAMEWORK)
    # Debian 12's systemd 252 is built without it: the unit's
    # SocketBindDeny=any is accepted and not enforced. Checked, so that the
    # day it is enforced (a systemd with +BPF_FRAMEWORK) this test says so.
    check bind_unit_8081 0
    check bind_unit_9000 0
    check bind_unit_0 0
    socket_bind="NOT enforced: systemd without BPF_FRAMEWORK, 8081 and 9000 bound from the unit's cgroup" ;;
  *) failures+=("systemd_bpf_framework: '$bpf'") ;;
esac
check bind_unit_8080 98 # EADDRINUSE: allowed, and the scanner holds it
# Aravis's GigE Vision sockets: UDP, bound to port 0 (or to a fixed port).
check bind_unit_udp_0 0
check bind_unit_udp_40000 0
read -r pid_killed pid_new <<< "$(value restart_pids)"
{ [ -n "${pid_new:-}" ] && [ "$pid_new" != 0 ] && [ "$pid_new" != "$pid_killed" ]; } ||
  failures+=("restart_pids: '$(value restart_pids)': the main PID did not change")
check_num restarted_s 'v >= 3 && v < 60'
read -r n_before n_after <<< "$(value nrestarts)"
[ "$((n_after - n_before))" = 1 ] || failures+=("nrestarts: '$(value nrestarts)', not one more")
check listening_after_restart 2
check_num journal_ident 'v >= 4'
check journal_sigkill 1
check_num journal_warning_priority 'v >= 2'
check upgrade_status 0
check upgraded "installed $version+1"
check token_kept yes
check token_stat_after_upgrade "640 root fpp-scanner"
check board_kept yes
check scans_kept yes
check_num scans_after 'v >= 1'
check active_after_upgrade active
check enabled_after_upgrade enabled
read -r pid_old pid_upgraded <<< "$(value upgrade_pids)"
[ "${pid_upgraded:-0}" != 0 ] && [ "$pid_upgraded" != "$pid_old" ] ||
  failures+=("upgrade_pids: '$(value upgrade_pids)': not restarted on the new binary")
check host_upgraded "done"
check status_after_upgrade 200 host
check status_after_upgrade_without_token 401 host
check scan_in_list_after_upgrade 1 host
check remove_status 0
check after_remove "token board  inactive"
check purge_status 0
check after_purge_etc gone
# (systemctl is-enabled of a unit that is gone: nothing from systemd 252,
# "not-found" from 257.)
case "$(value after_purge_unit)" in
  "gone " | "gone not-found") ;;
  *) failures+=("after_purge_unit: '$(value after_purge_unit)', expected the unit gone") ;;
esac
check after_purge_wants none
# Remove keeps the scans, purge takes them (board/debian/postrm); the
# system user stays (Debian keeps system users).
check_num after_remove_scans 'v >= 1'
check after_purge_state gone
check after_purge_user kept
check "done" yes

echo "run_vm_booted: guest: boot finished in $(value boot_finished) s (systemd-analyze time, systemd" \
  "$(value systemd_version)), guest.sh at $(value guest_sh_started_s) s of uptime; apt install" \
  "$(value install_s) s, listening $(value listening_s) s after enable --now, restarted" \
  "$(value restarted_s) s after SIGKILL, upgrade $(value upgrade_s) s; exposure $exposure;" \
  "host reached the API at $t_http s, whole run $t_total s"
echo "run_vm_booted: SocketBindDeny $socket_bind; remove kept" \
  "$(value after_remove_scans) scan(s) in /var/lib/fpp-scanner/scans, purge took them; the user stays"
if [ ${#failures[@]} -gt 0 ]; then
  printf 'run_vm_booted: %s\n' "${failures[@]}"
  echo "--- guest results:"; cat "$out/results"
  [ -z "$keep" ] || echo "run_vm_booted: the guest's logs are in $out"
  fail "${#failures[@]} live check(s) failed"
fi
echo "run_vm_booted: PASSED in $t_total s"
