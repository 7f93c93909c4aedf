#!/usr/bin/env bash
# Bad board files on the virtual ARM board's real kernel devices, in one
# boot: a GPIO line the chip does not have, a line another process holds, a
# display mode the connector does not offer, a DRM card, a connector and a
# GPIO chip that do not exist, and a line the chip named by its label does
# not have.
# Each must stop fpp-scanner at start with exit 1 and an error naming what is
# wrong; then the good board must still scan (nothing was left claimed).
# These boards simulate the camera (sim.camera_only): where fpp-scanner is
# the device binary without the virtual scanner (preset aarch64) they run
# on fpp-scanner-sim, and fpp-scanner itself must refuse the good board
# (exit 1, the board file named) before it claims anything.
# Usage: tests/vm/run_vm_bad_boards.sh [AARCH64_BUILD]
# Exit status: 0 passed, 1 failed, 77 skipped (as tests/vm/run_vm_scan.sh).
set -euo pipefail
source_dir=$(cd "$(dirname "$0")/../.." && pwd)
build="${1:-$source_dir/build/aarch64}"
test_name=run_vm_bad_boards
# shellcheck source=tests/vm/common.sh
source "$source_dir/tests/vm/common.sh"
require_vm
require_arm64_scanner "$build"
require_libgpiod "$build"

work=$(mktemp -d "${TMPDIR:-/tmp}/fpp-vm-bad.XXXXXX")
trap 'rm -rf "$work"' EXIT
files="$work/files"
mkdir -p "$files" "$work/out"
cp -r "$source_dir/board/sim" "$files/sim"
good="$source_dir/tests/vm/vm-camera-only.yaml"
cp "$good" "$files/good.yaml"
variant() { # NAME FROM TO
  sed "s|$2|$3|" "$good" > "$files/$1.yaml"
  cmp -s "$good" "$files/$1.yaml" && fail "vm-camera-only.yaml has no '$2'"
  return 0
}
variant no-such-line '  led_line: 1' '  led_line: 9'
variant line-held '  led_line: 1' '  led_line: 5'
variant no-such-mode 'mode: 1280x800' 'mode: 1234x567'
variant no-such-card 'card: auto' 'card: /dev/dri/card7'
variant no-such-connector 'connector: auto' 'connector: HDMI-A-9'
variant no-such-chip '  chip: gpiochip0' '  chip: gpiochip7'
# The chip named by its label (the PL061's), with a line it does not have:
# the error names the line, so the chip was found (1.x looks labels up
# itself, the 2.x backend by hand).
sed -e 's|  led_line: 1|  led_line: 9|' -e 's|  chip: gpiochip0|  chip: 9030000.pl061|' "$good" \
  > "$files/label-no-such-line.yaml"
grep -q 'chip: 9030000.pl061' "$files/label-no-such-line.yaml" || fail "vm-camera-only.yaml has no chip line"
scanner=$(sim_scanner_name "$build")
echo "scanner=$scanner" > "$files/bad-boards.sh"
cat >> "$files/bad-boards.sh" << 'GUEST'
# In the guest: each case's exit status and first error line, then the good
# board's capture scan.
run() { # NAME [holder command...]
  name=$1; shift
  if [ $# -gt 0 ]; then
    "$@" & holder=$!
    # until the holder has the line (emulated CPUs are slow to start it)
    i=0
    while ! gpioinfo gpiochip0 | grep -q '"gpioset"' && [ $i -lt 100 ]; do sleep 0.1; i=$((i + 1)); done
  fi
  $scanner --board "$name.yaml" --once --mode capture --store /out/scans-$name \
    > /dev/null 2> /out/$name.log
  echo "$name $? $(grep -m 1 '^error: ' /out/$name.log)" >> /out/results.txt
  if [ -n "${holder:-}" ]; then kill $holder; wait $holder 2> /dev/null; holder=; fi
}
run no-such-line
run line-held gpioset --mode=signal gpiochip0 5=0
run no-such-mode
run no-such-card
run no-such-connector
run no-such-chip
run label-no-such-line
if [ "$scanner" != fpp-scanner ]; then
  fpp-scanner --board good.yaml --once --mode capture --store /out/scans-device > /dev/null 2> /out/device.log
  echo "device $? $(grep -m 1 '^error: ' /out/device.log)" >> /out/results.txt
fi
$scanner --board good.yaml --once --mode capture --store /out/scans-good > /dev/null 2> /out/good.log
echo "good $?" >> /out/results.txt
GUEST
status=0
"$source_dir/toolchain/vm/run-vm.sh" --build "$build" --files "$files" --out "$work/out" \
  --timeout 240 --quiet -- sh bad-boards.sh 2> "$work/run-vm.err" || status=$?
[ "$status" -eq 0 ] || { cat "$work/run-vm.err" "$work/out/console.log"; fail "the VM run ended with $status"; }
results="$work/out/results.txt"
[ -s "$results" ] || fail "no results from the guest"
cat "$results"
expect() { # NAME TEXT...: exit 1 and an error line holding every TEXT
  local line
  line=$(grep "^$1 " "$results") || fail "$1: no result"
  [ "$(cut -d ' ' -f 2 <<< "$line")" = 1 ] || fail "$1: exit status is not 1: $line"
  shift
  for text in "$@"; do
    grep -qF -- "$text" <<< "$line" || fail "'$text' not in: $line"
  done
  for d in "$work"/out/scans-*; do
    [ "$d" = "$work/out/scans-good" ] || [ ! -d "$d" ] || [ -z "$(ls -A "$d")" ] ||
      fail "a failed start left files in $d"
  done
}
# The GPIO messages are the same whichever libgpiod the driver is built on
# (drivers/gpiod/src/gpio_line_v1.cpp and gpio_line_v2.cpp).
expect no-such-line "gpiochip0 line 9 (no-such-line.yaml gpio.led_line): no such line on the chip"
expect line-held "gpiochip0 line 5 (line-held.yaml gpio.led_line): cannot request the line (held by another process?)"
expect no-such-mode "1234x567"
expect no-such-card "/dev/dri/card7"
expect no-such-connector "HDMI-A-9"
expect no-such-chip "gpiochip7 line 1 (no-such-chip.yaml gpio.led_line): cannot open the chip"
expect label-no-such-line "9030000.pl061 line 9 (label-no-such-line.yaml gpio.led_line): no such line on the chip"
[ "$scanner" = fpp-scanner ] ||
  expect device "good.yaml: sim: " "built without the virtual scanner"
grep -qx "good 0" "$results" || { cat "$work/out/good.log"; fail "the good board did not scan after the failures"; }
echo "run_vm_bad_boards: PASSED"
