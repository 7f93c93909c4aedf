#!/usr/bin/env bash
# The scanner on the virtual ARM board, end to end: the host's fpp-scanner
# and fpp-calib record and calibrate (one checkerboard session on the
# simulated board, the stereo calibration and the hybrid table from it, as
# the README's "Calibrating a scanner"; camera binned 4 x 4); the arm64
# fpp-scanner then runs
# in the VM on tests/vm/vm-camera-only.yaml (virtio-gpu DRM flips, PL061
# lines, simulated camera over Aravis's fake GigE camera), waits for the
# button, which QEMU's power button presses, scans the composite scene with
# the table and is stopped by SIGTERM; the cloud it wrote is compared with
# the scene's ground truth on the host, and its flip log must show every
# pattern flipped in order with each frame exposed after its flip.
# Usage: tests/vm/run_vm_board_scan.sh HOST_BUILD [AARCH64_BUILD]
# Exit status: 0 passed, 1 failed, 77 skipped (as tests/vm/run_vm_scan.sh).
set -euo pipefail
source_dir=$(cd "$(dirname "$0")/../.." && pwd)
host="$1"
build="${2:-$source_dir/build/aarch64}"
calib="$host/calib/fpp-calib"
test_name=run_vm_board_scan
# shellcheck source=tests/vm/common.sh
source "$source_dir/tests/vm/common.sh"
scanner="$host/firmware/scanner/$(sim_scanner_name "$host")"
{ [ -x "$scanner" ] && [ -x "$calib" ]; } || skip "no host tools in $host"

work=$(mktemp -d "${TMPDIR:-/tmp}/fpp-vm-board.XXXXXX")
trap 'rm -rf "$work"' EXIT
# The session board of board/, binned 4 x 4, its rig found from here.
b=sim-checkerboard-session
sed -e 's/^\(  binning:\) 2$/\1 4/' -e "s|rig: sim/|rig: $source_dir/board/sim/|" \
  "$source_dir/board/$b.yaml" > "$work/$b.yaml"
grep -q '^  binning: 4$' "$work/$b.yaml" || fail "board/$b.yaml has no 'binning: 2' line"
"$scanner" --board "$work/$b.yaml" --mode capture --scans 30 \
  --store "$work/cb" > /dev/null 2> "$work/host.log" || fail "checkerboard session (see $work/host.log)"
"$calib" stereo "$work/cb" --out "$work/calib.yaml" > /dev/null 2>> "$work/host.log" || fail "stereo"
"$calib" hybrid "$work/cb" --calib "$work/calib.yaml" --out "$work/table.fpt" \
  > /dev/null 2>> "$work/host.log" || fail "hybrid"

# The guest's files: the board, its rig and scene, the table.
mkdir -p "$work/files"
cp "$source_dir/tests/vm/vm-camera-only.yaml" "$work/files/"
cp -r "$source_dir/board/sim" "$work/files/sim"
status=0
"$source_dir/tests/vm/run_vm_scan.sh" --build "$build" --board "$work/files/vm-camera-only.yaml" \
  --mode scan --table "$work/table.fpt" --button --keep "$work/vm" || status=$?
[ "$status" -eq 0 ] || exit "$status"
scan=$(find "$work/vm/scans" -mindepth 1 -maxdepth 1 -type d -name 'scan-*')
grep -q '"board": "vm-camera-only"' "$scan/scan.json" || fail "not the VM board's scan"

# Every pattern flipped through the kernel, in order, each frame after its flip.
flips=$(grep -c '"pattern": ' "$scan/scan.json" || true)
frames=$(sed -n 's/^ *"frames": \([0-9]*\),$/\1/p' "$scan/scan.json")
[ "$flips" -eq "$frames" ] || fail "$flips flips for $frames frames"
# scan.json has one key a line (firmware/core/formats/scan-json.md): a flip's
# pattern, flip_ns and frame_ns come on lines of their own. The flip-to-frame
# times (the settle, the camera's trigger and the start of its exposure) are
# printed, for the two GPIO backends side by side (README).
timing=$(awk '
     function value(key) { match($0, "\"" key "\": [0-9]+"); return substr($0, RSTART + length(key) + 4, RLENGTH - length(key) - 4) + 0 }
     /"pattern": / { p = value("pattern") }
     /"flip_ns": / { f = value("flip_ns") }
     /"frame_ns": / {
       e = value("frame_ns")
       if (p != n++ || f <= 0 || e < f) { print "pattern " p " out of order, or exposed before its flip"; bad = 1; exit 1 }
       sum += e - f; if (e - f > max) max = e - f
     }
     END { if (!bad && n > 0) printf "%d frames, flip to frame: mean %.2f ms, max %.2f ms", n, sum / n / 1e6, max / 1e6 }' \
  "$scan/scan.json") || fail "flip log: $timing"

# Against the truth of the same scene.
"$calib" simulate --rig "$source_dir/board/sim/paper-rig-effects.yaml" --scene composite \
  --sequence gray-x --binning 4 --out "$work/truth" > /dev/null 2>> "$work/host.log" || fail "truth"
"$calib" evaluate "$scan/cloud.ply" --truth "$work/truth" --out "$work/eval" \
  > /dev/null 2>> "$work/host.log" || fail "evaluate"
figure() { sed -n "s/^$1,\([^,]*\),.*$/\1/p" "$work/eval/figures.csv"; }
rms=$(figure cloud.truth.distance_rms)
mean=$(figure cloud.truth.dz_mean)
shape=$(figure cloud.truth.dz_shape_rms)
points=$(figure cloud.points)
echo "run_vm_board_scan: $points points from the VM, 3D RMS $rms mm against the truth" \
  "(Z mean $mean, shape $shape), $flips flips; $timing"
# The bounds of tests/cli/test_cli_scanner_calibration.cpp, which calibrates
# from the same session: at 400 x 300 the calibration's focal length is known
# to about 107 ppm (its reported sigma), 0.05 mm of depth at 480 mm.
awk -v r="$rms" -v m="$mean" -v s="$shape" -v n="$points" \
  'BEGIN { exit !(n > 50000 && s < 0.06 && (m < 0 ? -m : m) < 0.16 && r < 0.25) }' ||
  fail "cloud: $points points, 3D RMS $rms mm, Z mean $mean, shape $shape" \
    "(want > 50000 points, shape < 0.06, |mean| < 0.16, RMS < 0.25 mm)"
echo "run_vm_board_scan: PASSED"
