#!/usr/bin/env bash
# Installs what the tests need, builds and runs every test: the README's test
# command, and CI's gate (.ci/run). In order, stopping at the first failure:
#   install   toolchain/install-deps.sh tests cross vm trixie
#   aarch64   the firmware cross-built for the scanner, its tests under
#             qemu-user (first: the ci preset's virtual ARM board runs it)
#   aarch64-gpiod2  the same against libgpiod 2 (the scanner and the GPIO
#             driver's tests only), for the ci preset's VM.Gpiod2 runs
#   trixie    the firmware, the virtual scanner and the host tool built on
#             Debian 13 (GCC 14, libgpiod 2), the tests placed 'device' run
#             there, in the Debian 13 root (toolchain/trixie/run.sh); then
#             the scanner cross-built there for arm64 and its Debian 13
#             package made (trixie-aarch64), for the ci preset's booted board
#   ci        the optimised build, its tests and the benchmarks' smoke runs
#   asan      the tests under AddressSanitizer and UndefinedBehaviorSanitizer
#   fuzz      every file reader and the HTTP API's handlers under libFuzzer
# Each preset is configured and built, then tested (CMakePresets.json; a
# test runs in the presets its labels name, tests/CMakeLists.txt). At the
# end, also after a failure, a table of each phase's wall time, what the
# compiler cache served to each build (toolchain/ccache.cmake), and the total.
# Usage: toolchain/run-tests.sh
set -uo pipefail
cd "$(dirname "$0")/.."

presets=(aarch64 aarch64-gpiod2 trixie ci asan fuzz)
rows=()          # one line of the table per phase
# fpp's compiler cache and its limit: toolchain/ccache.cmake's defaults, or
# what a build's CMakeCache.txt says (FPP_CCACHE_DIR, FPP_CCACHE_MAXSIZE).
cache_dir="${HOME:-}/.cache/fpp-ccache"
cache_max=6G
started=$EPOCHREALTIME
log=$(mktemp)

seconds_since() { awk -v a="$1" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.0f", b - a }'; }

# The compiler cache's counters: "hits misses other cleanups" (other: what
# ccache could not cache: its own errors (a full disk shows as preprocessor
# errors), a precompiled header it could not use; a corrupt entry is a miss).
cache_counters() {
  [ -n "$cache_dir" ] && command -v ccache >/dev/null || { echo "- - - -"; return; }
  CCACHE_DIR="$cache_dir" ccache --print-stats 2>/dev/null | awk '
    $1 == "direct_cache_hit" || $1 == "preprocessed_cache_hit" { hits += $2 }
    $1 == "cache_miss" { misses += $2 }
    $1 == "cleanups_performed" { cleanups += $2 }
    $1 ~ /^(internal_error|bad_output_file|missing_cache_file|error_hashing_extra_file|could_not_use_precompiled_header|unsupported_compiler_option|compiler_check_failed|remote_storage_error|preprocessor_error)$/ { other += $2 }
    END { printf "%d %d %d %d\n", hits, misses, other, cleanups }'
}

print_table() {
  local total
  total=$(seconds_since "$started")
  printf '\n%-26s %8s   %-34s %s\n' "phase" "wall" "compiler cache: hits/misses/other" "result"
  printf '%s\n' "${rows[@]}"
  printf '%-26s %7ss   (%d min %02d s)\n' "total" "$total" $((total / 60)) $((total % 60))
  if [ -n "$cache_dir" ] && command -v ccache >/dev/null; then
    CCACHE_DIR="$cache_dir" CCACHE_MAXSIZE="$cache_max" ccache --show-stats 2>/dev/null |
      awk -v dir="$cache_dir" '/Cache size/ { sub(/^ */, ""); print "compiler cache " dir ": " $0 }'
  fi
}

# run_phase NAME CACHE(yes|no) COMMAND...: runs and times one phase, adds its row.
run_phase() {
  local name=$1 cached=$2 before after status t0 cache="" result
  shift 2
  echo "=== $name: $*"
  before=$(cache_counters)
  t0=$EPOCHREALTIME
  "$@" 2>&1 | tee "$log"
  status=${PIPESTATUS[0]}
  if [ "$cached" = yes ]; then
    after=$(cache_counters)
    cache=$(awk -v b="$before" -v a="$after" 'BEGIN {
      split(b, x); split(a, y)
      if (x[1] == "-" || y[1] == "-") { print "not used"; exit }
      printf "%d/%d/%d", y[1] - x[1], y[2] - x[2], y[3] - x[3]
      if (y[4] > x[4]) printf " (%d cleanups: full)", y[4] - x[4]
    }')
  fi
  result=$([ "$status" -eq 0 ] && echo ok || echo "FAILED (exit $status)")
  # ctest's summary: "100% tests passed, 0 tests failed out of 523"
  local summary
  summary=$(grep -Eo '[0-9]+ tests failed out of [0-9]+' "$log" | tail -1)
  [ -n "$summary" ] && result="$result, $summary"
  rows+=("$(printf '%-26s %7ss   %-34s %s' "$name" "$(seconds_since "$t0")" "$cache" "$result")")
  return "$status"
}

finish() {
  local status=$?
  rm -f "$log"
  print_table
  exit "$status"
}
trap finish EXIT

run_phase install no ./toolchain/install-deps.sh tests cross vm trixie || exit
for preset in "${presets[@]}"; do
  if [ "$preset" = trixie ]; then
    # Inside the Debian 13 root, with its own compiler cache (not counted here).
    run_phase "trixie configure+build" no toolchain/trixie/run.sh -- \
      sh -c "cmake --preset trixie && cmake --build --preset trixie" || exit
    run_phase "trixie tests" no toolchain/trixie/run.sh -- ctest --preset trixie || exit
    run_phase "trixie-aarch64 + .deb" no toolchain/trixie/run.sh -- \
      sh -c "cmake --workflow --preset trixie-aarch64 && rm -rf build/trixie-aarch64/deb &&
             cpack --config build/trixie-aarch64/CPackConfig.cmake -B build/trixie-aarch64/deb" || exit
    continue
  fi
  configured=$(sed -n 's/^FPP_CCACHE_DIR:PATH=//p' "build/$preset/CMakeCache.txt" 2>/dev/null)
  cache_dir=${configured:-$cache_dir}
  configured=$(sed -n 's/^FPP_CCACHE_MAXSIZE:STRING=//p' "build/$preset/CMakeCache.txt" 2>/dev/null)
  cache_max=${configured:-$cache_max}
  run_phase "$preset configure+build" yes \
    sh -c "cmake --preset $preset && cmake --build --preset $preset" || exit
  run_phase "$preset tests" no ctest --preset "$preset" || exit
done
