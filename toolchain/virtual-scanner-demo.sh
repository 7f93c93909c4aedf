#!/usr/bin/env bash
# The main job on the virtual scanner, as a person runs it on a real one:
#   1. fpp-scanner records a calibration session: a checkerboard on a white
#      board at 30 poses (capture mode, one scan per pose);
#   2. fpp-calib calibrates the camera-projector pair (stereo, the camera
#      first) and fits the hybrid coefficient table from the same session
#      (each board placed by the camera), in one command (`calibrate`);
#   3. fpp-scanner loads the table and scans the composite scene (a button
#      press), writing the point cloud;
#   4. fpp-calib compares the cloud with the scene's ground truth.
# Usage: toolchain/virtual-scanner-demo.sh [BUILD_DIR] [OUT_DIR]
#        (defaults build/release and demo-out; OUT_DIR must not exist)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-build/release}"
out="${2:-demo-out}"
scanner="$build/firmware/scanner/fpp-scanner"
calib="$build/calib/fpp-calib"
for tool in "$scanner" "$calib"; do
  [[ -x "$tool" ]] || { echo "error: $tool not found: build first (cmake --workflow --preset release)" >&2; exit 1; }
done
[[ -e "$out" ]] && { echo "error: $out exists: give another output folder" >&2; exit 1; }
mkdir -p "$out"
log="$out/demo.log" # the tools' progress and the scanner's log lines
trap 'echo "error: a step failed; see $log" >&2' ERR

echo "== 1. recording the calibration session with fpp-scanner (capture mode)"
"$scanner" --board "$root/board/sim-checkerboard-session.yaml" --mode capture --scans 30 \
  --store "$out/session" > /dev/null 2>> "$log"

echo "== 2. calibrating with fpp-calib: stereo, then the hybrid table, from the same session"
"$calib" calibrate "$out/session" --out "$out/calib.yaml" --table "$out/table.fpt" \
  --stereo-report "$out/stereo-report" --hybrid-report "$out/hybrid-report" 2>> "$log" \
  | grep -E "^(calibrated from|wrote|pixels modelled|poses:)"

echo "== 3. a scan on fpp-scanner with that table"
scan="$("$scanner" --board "$root/board/sim.yaml" --once --store "$out/scans" --table "$out/table.fpt" 2>> "$log")"

echo "== 4. the cloud against the ground truth"
"$calib" simulate --rig "$root/board/sim/paper-rig-effects.yaml" --scene composite --sequence gray-x \
  --binning 2 --out "$out/truth" > /dev/null 2>> "$log"
"$calib" evaluate "$scan/cloud.ply" --truth "$out/truth" --out "$out/report" > /dev/null 2>> "$log"
grep -E "Z error, RMS|3D distance, RMS|coverage" "$out/report/summary.md"

echo
echo "point cloud:  $scan/cloud.ply (scan metadata: $scan/scan.json)"
echo "report:       $out/report/summary.md (calibration: $out/stereo-report, $out/hybrid-report)"
echo "log:          $log"
