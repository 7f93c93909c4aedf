#!/usr/bin/env bash
# Runs the arm64 scanner firmware on the virtual ARM board
# (toolchain/vm/run-vm.sh: qemu-system-aarch64, Debian's arm64 kernel,
# virtio-gpu DRM, PL061 GPIO) and checks the scan folder it brings back.
#
# Default: board/sim.yaml (the virtual scanner, camera binned 8 x 8 so that
# the emulated CPU is quick), `fpp-scanner --once --mode capture`.
# With --button the scanner runs as on the device: it waits for the button,
# the harness presses it (QEMU's power button, PL061 line 3) when the scanner
# logs "idle: waiting for the button", and the scanner is stopped (SIGTERM)
# when it is back waiting after that scan; it must then exit 0. That needs a
# board whose button is line 3, active high (e.g. tests/vm/vm-hardware.yaml).
# With --chip-gone as well, the PL061's driver is unbound for 3 s once the
# scanner is idle (its GPIO chip gone, back as another gpiochip number): the
# scanner must say so naming the board file's line, say the button answers
# again, and only then is the button pressed for the scan.
#
# Usage: tests/vm/run_vm_scan.sh [--build DIR] [--board FILE] [--mode capture|scan]
#          [--table FILE] [--button [--chip-gone]] [--fake-camera | --late-camera S] [--keep DIR]
#          [--timeout S]
#   --build DIR     the AArch64 build folder (default: build/aarch64 of this tree)
#   --board FILE    board file, used as is; its whole folder goes into the guest
#   --table FILE    coefficient table for scan mode (passed as --table)
#   --fake-camera   start Aravis's fake GigE camera on the guest's 127.0.0.1 first
#   --late-camera S start it S seconds after the scanner (with --button: the
#                   scanner must wait for it, log why, then scan)
#   --keep DIR      keep the results there (console.log, scans/)
# Exit status: 0 passed, 1 failed, 77 skipped (no qemu-system-aarch64, no
# kernel cache from toolchain/vm/fetch-deps.sh, or no cross-built fpp-scanner).
set -euo pipefail

source_dir=$(cd "$(dirname "$0")/../.." && pwd)
build="$source_dir/build/aarch64"
board="" table="" mode=capture button=0 chip_gone=0 fake_camera=0 camera_delay=0 keep="" timeout_s=240
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --board) board="$2"; shift 2 ;;
    --table) table="$2"; shift 2 ;;
    --mode) mode="$2"; shift 2 ;;
    --button) button=1; shift ;;
    --chip-gone) chip_gone=1; shift ;;
    --fake-camera) fake_camera=1; shift ;;
    --late-camera) fake_camera=1; camera_delay="$2"; shift 2 ;;
    --keep) keep="$2"; shift 2 ;;
    --timeout) timeout_s="$2"; shift 2 ;;
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
    *) echo "run_vm_scan: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
case "$mode" in capture|scan) ;; *) echo "run_vm_scan: --mode capture or scan" >&2; exit 2 ;; esac
[ "$chip_gone" -eq 0 ] || [ "$button" -eq 1 ] || { echo "run_vm_scan: --chip-gone needs --button" >&2; exit 2; }

test_name=run_vm_scan
# shellcheck source=tests/vm/common.sh
source "$source_dir/tests/vm/common.sh"
require_vm
require_arm64_scanner "$build"
require_libgpiod "$build"

t_start=$EPOCHREALTIME
work=$(mktemp -d "${TMPDIR:-/tmp}/fpp-vm-scan.XXXXXX")
trap 'rm -rf "$work"' EXIT
files="$work/files"
out="${keep:-$work/out}"
rm -rf "$out/scans" && mkdir -p "$files" "$out"

if [ -z "$board" ]; then
  cp -r "$source_dir/board/sim" "$files/sim"
  sed 's/^\(  binning:\) 2$/\1 8/' "$source_dir/board/sim.yaml" > "$files/board.yaml"
  grep -q '^  binning: 8$' "$files/board.yaml" || fail "board/sim.yaml has no 'binning: 2' line to change"
  board_name=board.yaml
else
  [ -f "$board" ] || fail "no board file $board"
  cp -rL "$(dirname "$board")/." "$files/"
  board_name=$(basename "$board")
fi
# A hardware board runs on the device binary; a sim board on the scanner
# with the virtual scanner (fpp-scanner-sim beside a device build's).
scanner=fpp-scanner
! grep -q '^sim:' "$files/$board_name" || scanner=$(sim_scanner_name "$build")
scanner_args=("$scanner" --board "$board_name" --mode "$mode" --store /out/scans)
if [ -n "$table" ]; then
  cp "$table" "$files/table.fpt"
  scanner_args+=(--table table.fpt)
fi

vm_args=(--build "$build" --files "$files" --out "$out" --timeout "$timeout_s" --quiet)
[ "$fake_camera" -eq 0 ] || vm_args+=(--fake-camera)
if [ "$button" -eq 1 ] && [ "$chip_gone" -eq 1 ]; then
  # Idle, chip gone and back (idle again), pressed, scanned, idle: stopped.
  cat > "$files/chip-gone.sh" << 'EOF'
log=/tmp/scanner.log
: > "$log"
(
  while ! grep -q 'idle: waiting for the button' "$log"; do sleep 0.2; done
  echo 9030000.pl061 > /sys/bus/amba/drivers/pl061_gpio/unbind
  echo "chip-gone: PL061 unbound: $(ls /dev | grep -c gpiochip) gpio chips"
  sleep 3
  echo 9030000.pl061 > /sys/bus/amba/drivers/pl061_gpio/bind
  echo "chip-gone: PL061 bound again: $(ls /dev | grep gpiochip)"
) &
FPP_VM_UNTIL_COPY=$log exec "$@"
EOF
  guest=(sh chip-gone.sh fpp-vm-until 3 '*idle: waiting for the button*' "${scanner_args[@]}")
  vm_args+=(--press-on 'button answers again' --presses 1)
elif [ "$button" -eq 1 ]; then
  # Stopped when back waiting after the first scan; one press only, so that
  # the second "waiting" line does not start another scan.
  guest=(fpp-vm-until 2 '*idle: waiting for the button*' "${scanner_args[@]}")
  vm_args+=(--press-on 'idle: waiting for the button' --presses 1)
else
  guest=("${scanner_args[@]}" --once)
fi
if [ "$fake_camera" -eq 1 ]; then
  # The camera answers on UDP port 3956 (GVCP) once it is up.
  cat > "$files/with-fake-camera.sh" << 'EOF'
delay=$1
shift
if [ "$delay" -gt 0 ]; then
  (sleep "$delay" && exec arv-fake-gv-camera-0.8 -i 127.0.0.1) &
  camera=$!
else
  arv-fake-gv-camera-0.8 -i 127.0.0.1 &
  camera=$!
  i=0
  while ! netstat -uln | grep -q ':3956 ' && [ $i -lt 100 ]; do sleep 0.1; i=$((i + 1)); done
fi
"$@"
status=$?
kill $camera
exit $status
EOF
  guest=(sh with-fake-camera.sh "$camera_delay" "${guest[@]}")
fi

echo "run_vm_scan: guest command: ${guest[*]}"
status=0
"$source_dir/toolchain/vm/run-vm.sh" "${vm_args[@]}" -- "${guest[@]}" 2> "$work/run-vm.err" || status=$?
# The results folder is temporary unless --keep was given.
if [ -n "$keep" ]; then cat "$work/run-vm.err"; else grep -v '^run-vm: results in' "$work/run-vm.err" || true; fi
show_console() { echo "--- guest console:"; grep -v '^fpp-vm-init: gpio line' "$out/console.log" || true; }
case "$status" in
  0) ;;
  124) show_console; fail "the VM did not finish within $timeout_s s" ;;
  125) show_console; fail "the VM could not run the scanner" ;;
  *) show_console; fail "$scanner exited with status $status in the guest" ;;
esac

# Exactly one scan folder, complete.
mapfile -t scans < <(find "$out/scans" -mindepth 1 -maxdepth 1 -type d -name 'scan-*' 2> /dev/null)
[ ${#scans[@]} -eq 1 ] || { show_console; fail "expected one scan folder in $out/scans, found ${#scans[@]}"; }
scan=${scans[0]}
[ -s "$scan/scan.json" ] || fail "$scan has no scan.json"
grep -q "\"mode\": \"$mode\"" "$scan/scan.json" || fail "$scan/scan.json is not of mode $mode"
if [ "$mode" = capture ]; then
  frames=$(sed -n 's/^ *"frames": \([0-9]*\),$/\1/p' "$scan/scan.json")
  pngs=$(find "$scan/capture" -name '*.png' | wc -l)
  if [ -z "$frames" ] || [ "$frames" -eq 0 ]; then fail "$scan/scan.json gives no frame count"; fi
  [ "$pngs" -eq "$frames" ] || fail "$scan/capture holds $pngs PNG frames, scan.json says $frames"
  [ -s "$scan/capture/capture.yaml" ] || fail "$scan/capture has no capture.yaml"
fi
if [ "$button" -eq 1 ]; then
  grep -q '^run-vm: button pressed' "$out/console.log" || fail "the button was never pressed"
fi
if [ "$chip_gone" -eq 1 ]; then
  for expected in 'chip-gone: PL061 unbound: 0 gpio chips' \
    "button: gpiochip0 line 3 ($board_name gpio.button_line): reading an edge failed: No such device" \
    'chip-gone: PL061 bound again: gpiochip1' 'button answers again'; do
    grep -qF "$expected" "$out/console.log" || { show_console; fail "no console line with '$expected'"; }
  done
fi
if [ "$camera_delay" -gt 0 ]; then
  grep -q 'camera 127.0.0.1.*waiting for it' "$out/console.log" ||
    { show_console; fail "the scanner did not say it was waiting for the camera"; }
  grep -q 'camera answered after' "$out/console.log" ||
    { show_console; fail "the scanner did not say the camera answered"; }
fi
total=$(awk -v a="$t_start" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.1f", b - a }')
echo "run_vm_scan: PASSED: $(basename "$scan") ($mode${frames:+, $frames frames}) in ${total} s"
