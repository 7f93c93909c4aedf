#!/usr/bin/env bash
# Checks the virtual ARM board itself (toolchain/vm/run-vm.sh), without the
# firmware's cross build: cross-compiles tests/vm/vm_probe.cpp against the
# arm64 libdrm and libgpiod, boots the board with it and checks that it lit
# the virtio-gpu display and flipped pages, pulsed a PL061 line on each flip
# (the flip-to-trigger latency, printed and bounded), and saw the button edge
# that the harness made with QEMU's system_powerdown; then, in the same boot,
# tests/vm/vm_gpiod_driver.cpp runs the scanner's GPIO driver (drivers/gpiod,
# compiled with it: gpio_line_v1.cpp, or gpio_line_v2.cpp with --libgpiod2)
# on the same lines: trigger pulses timed, the LED's states, a press waited
# for and two queued presses drained; then the PL061 unbound and bound again
# (its chip gone and back): the driver reports it and works again.
# Usage: tests/vm/run_vm_probe.sh [--libgpiod2 [PREFIX]] [--sanitize] [--keep DIR]
#          [--timeout S]
#   --libgpiod2 PREFIX  the probe built against the libgpiod 2 unpacked there
#                       (default: the VM cache's libgpiod2/root, filled by
#                       toolchain/vm/fetch-libgpiod2.sh); its libgpiod.so.3
#                       goes into the guest. Without it: the system's 1.6.
#   --sanitize          only the driver's run (vm_gpiod_driver.cpp), built
#                       with AddressSanitizer and UndefinedBehaviorSanitizer
#                       (the cross compiler's runtimes go into the guest);
#                       any report fails it. Its timings are not checked.
# Exit status: 0 passed, 1 failed, 77 skipped (no qemu-system-aarch64, no
# kernel cache, no cross compiler or arm64 libdrm/libgpiod development files).
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
source_dir=$(cd "$here/../.." && pwd)
keep="" timeout_s=120 gpiod2=0 gpiod2_prefix="" sanitize=0
while [ $# -gt 0 ]; do
  case "$1" in
    --libgpiod2)
      gpiod2=1
      if [ $# -gt 1 ] && [ "${2#--}" = "$2" ]; then gpiod2_prefix="$2"; shift; fi
      shift ;;
    --sanitize) sanitize=1; shift ;;
    --keep) keep="$2"; shift 2 ;;
    --timeout) timeout_s="$2"; shift 2 ;;
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
    *) echo "run_vm_probe: unknown argument '$1'" >&2; exit 2 ;;
  esac
done

test_name=run_vm_probe
# shellcheck source=tests/vm/common.sh
source "$source_dir/tests/vm/common.sh"
require_vm
command -v aarch64-linux-gnu-g++ > /dev/null || skip "no aarch64-linux-gnu-g++ (g++-aarch64-linux-gnu)"
for f in /usr/lib/aarch64-linux-gnu/libdrm.so /usr/lib/aarch64-linux-gnu/libgpiod.so \
  /usr/include/libdrm/drm.h /usr/include/gpiod.h; do
  [ -e "$f" ] || skip "no $f (libdrm-dev:arm64, libgpiod-dev:arm64)"
done
gpiod_flags=() api=1 line_source=gpio_line_v1.cpp
if [ "$gpiod2" -eq 1 ]; then
  gpiod2_prefix="${gpiod2_prefix:-$cache/libgpiod2/root}"
  lib="$gpiod2_prefix/usr/lib/aarch64-linux-gnu"
  if [ ! -e "$lib/libgpiod.so.3" ] || [ ! -f "$gpiod2_prefix/usr/include/gpiod.h" ]; then
    skip "no libgpiod 2 in $gpiod2_prefix (toolchain/vm/fetch-libgpiod2.sh fills it at install time)"
  fi
  # Its header before the system's 1.6 one; the RUNPATH tells make-initramfs.sh
  # where libgpiod.so.3 is.
  gpiod_flags=(-DFPP_PROBE_LIBGPIOD2=1 -I"$gpiod2_prefix/usr/include" -L"$lib" "-Wl,-rpath,$lib")
  api=2 line_source=gpio_line_v2.cpp
fi

t_start=$EPOCHREALTIME
work=$(mktemp -d "${TMPDIR:-/tmp}/fpp-vm-probe.XXXXXX")
trap 'rm -rf "$work"' EXIT
out="${keep:-$work/out}"
mkdir -p "$out"
if [ "$sanitize" -eq 0 ]; then
  aarch64-linux-gnu-g++ -std=c++20 -O2 -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wold-style-cast \
    -Wdouble-promotion -Werror -I/usr/include/libdrm -I"$source_dir/firmware/core/include" "${gpiod_flags[@]}" \
    "$here/vm_probe.cpp" -o "$work/vm-probe" -ldrm -lgpiod ||
    fail "cannot cross-compile vm_probe.cpp"
fi
# The driver with the project's warnings (CMakeLists.txt's fpp_warnings),
# and with the asan preset's sanitizers when asked.
sanitizer_flags=()
[ "$sanitize" -eq 0 ] ||
  sanitizer_flags=(-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer -g)
gpiod_src="$source_dir/drivers/gpiod/src"
aarch64-linux-gnu-g++ "${sanitizer_flags[@]}" -std=c++20 -O2 -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion \
  -Wnon-virtual-dtor -Wold-style-cast -Wcast-align -Woverloaded-virtual -Wdouble-promotion \
  -Wimplicit-fallthrough -Werror -I"$source_dir/drivers/gpiod/include" -I"$source_dir/drivers/include" \
  -I"$source_dir/firmware/core/include" "${gpiod_flags[@]}" "$here/vm_gpiod_driver.cpp" \
  "$gpiod_src/gpiod_lines.cpp" "$gpiod_src/reopening_line.cpp" "$gpiod_src/$line_source" -o "$work/vm-gpiod" -lgpiod -pthread ||
  fail "cannot cross-compile vm_gpiod_driver.cpp with $line_source"

status=0
if [ "$sanitize" -eq 0 ]; then
  vm_args=(--bin "$work/vm-probe" --presses 5)
  guest='vm-probe --wait-ms 30000 && vm-gpiod'
else
  # libasan and libubsan from the cross compiler, alone: its whole lib
  # folder would bring its libc beside the guest's loader, and a program
  # mixing them hangs in its first pthread_create. A report ends the run
  # with status 1 (halt_on_error) and its text on the console.
  mkdir -p "$work/sanitizer-libs"
  cp -P /usr/aarch64-linux-gnu/lib/libasan.so* /usr/aarch64-linux-gnu/lib/libubsan.so* "$work/sanitizer-libs/" ||
    skip "no arm64 libasan/libubsan in /usr/aarch64-linux-gnu/lib (g++-aarch64-linux-gnu)"
  vm_args=(--lib-dir "$work/sanitizer-libs" --presses 4)
  guest='ASAN_OPTIONS=detect_leaks=1:halt_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 vm-gpiod'
fi
"$source_dir/toolchain/vm/run-vm.sh" "${vm_args[@]}" --bin "$work/vm-gpiod" --out "$out" \
  --timeout "$timeout_s" --quiet --press-on '^vm-(probe: waiting for the button|gpiod: press now)' \
  -- sh -c "$guest" 2> "$work/run-vm.err" || status=$?
# The results folder is temporary unless --keep was given.
if [ -n "$keep" ]; then cat "$work/run-vm.err"; else grep -v '^run-vm: results in' "$work/run-vm.err" || true; fi
grep -E '^(fpp-vm-init: (drm|gpio gpiochip)|vm-probe: .*(OK|FAIL)|vm-gpiod: (OK|FAIL|button|chip))' \
  "$out/console.log" || true
if [ "$status" -ne 0 ]; then
  echo "--- guest console:"
  cat "$out/console.log"
  fail "run-vm.sh returned $status"
fi
if [ "$sanitize" -eq 1 ]; then
  ! grep -qE 'ERROR: (AddressSanitizer|LeakSanitizer)|runtime error:' "$out/console.log" ||
    { cat "$out/console.log"; fail "a sanitizer report (above)"; }
  for expected in '^vm-gpiod: OK trigger: 200 pulses' '^vm-gpiod: OK led' \
    '^vm-gpiod: OK button: 1 press waited for, 2 queued presses drained, none left' \
    '^vm-gpiod: OK chip gone and back'; do
    grep -q "$expected" "$out/console.log" || fail "no line matching '$expected' on the console"
  done
  total=$(awk -v a="$t_start" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.1f", b - a }')
  echo "run_vm_probe: PASSED under ASan and UBSan (libgpiod $api) in ${total} s"
  exit 0
fi
for expected in "^vm-probe: libgpiod $api\\." '^vm-probe: display OK' '^vm-probe: trigger OK' \
  '^vm-probe: gpio OK: button rising edge' '^run-vm: button pressed' '^vm-gpiod: OK trigger: 200 pulses' \
  '^vm-gpiod: OK led' '^vm-gpiod: OK button: 1 press waited for, 2 queued presses drained, none left' \
  '^vm-gpiod: OK chip gone and back'; do
  grep -q "$expected" "$out/console.log" || fail "no line matching '$expected' on the console"
done
# A pulse on every flip, the line set high within a bound far above what the
# emulated board shows (README: "The two libgpiod backends").
figures=$(sed -n 's/^vm-probe: trigger OK: \([0-9]*\) pulses; .*median \([0-9]*\) us, .*max \([0-9]*\) us; .*/\1 \2 \3/p' \
  "$out/console.log")
read -r pulses median max <<< "$figures" || fail "cannot read the trigger figures"
[ "$pulses" -eq 120 ] || fail "$pulses trigger pulses for 120 flips"
if ! [ "$median" -gt 0 ] || ! [ "$median" -lt 20000 ]; then
  fail "flip to trigger line high: median $median us (want 0 < median < 20000)"
fi
echo "run_vm_probe: libgpiod $api: $pulses pulses, flip to trigger line high median $median us, max $max us"
# The driver's pulses last at least their width (100 us).
pulse=$(sed -n 's/^vm-gpiod: OK trigger: 200 pulses of 100 us took median \([0-9]*\) us.*/\1/p' "$out/console.log")
if [ -z "$pulse" ] || ! [ "$pulse" -ge 100 ] || ! [ "$pulse" -lt 20000 ]; then
  fail "the driver's 100 us trigger pulse took a median of '$pulse' us (want 100 to 20000)"
fi
echo "run_vm_probe: libgpiod $api: the driver's 100 us trigger pulse took a median of $pulse us"
total=$(awk -v a="$t_start" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.1f", b - a }')
echo "run_vm_probe: PASSED in ${total} s"
