#!/usr/bin/env bash
# The long fuzzing run of issue 17 (10 minutes per harness by default): every
# harness of the fuzz preset on its corpus, run as the preset's tests run it
# (run-harness.sh: 5 s per input, 1 GB), new inputs kept in the build folder.
# Prints one line per harness: executions, coverage (libFuzzer's cov: and
# ft:), result.
# A finding leaves its input in BUILD/fuzz-long/artifacts/ for a reproducer.
# Usage: tests/fuzz/run-long.sh [--seconds N] [--jobs J] [--build DIR] [HARNESS...]
#   (build first: cmake --preset fuzz && cmake --build --preset fuzz)
set -euo pipefail

source_dir=$(cd "$(dirname "$0")/../.." && pwd)
seconds=600 jobs=1 build="$source_dir/build/fuzz"
harnesses=()
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) seconds=$2; shift 2 ;;
    --jobs) jobs=$2; shift 2 ;;
    --build) build=$2; shift 2 ;;
    -h|--help) sed -n '2,8p' "$0"; exit 0 ;;
    *) harnesses+=("$1"); shift ;;
  esac
done
if [ ${#harnesses[@]} -eq 0 ]; then
  for d in "$source_dir"/tests/fuzz/corpus/*/; do harnesses+=("$(basename "$d")"); done
fi
out="$build/fuzz-long"
mkdir -p "$out/artifacts"

run_one() {
  local h=$1 bin="$build/tests/fuzz/$1"
  [ -x "$bin" ] || { echo "$h: $bin is not built" >&2; return 1; }
  mkdir -p "$out/corpus/$h"
  # The repository's corpus is read, never written (new inputs: the first folder).
  "$source_dir/tests/fuzz/run-harness.sh" "$bin" "$seconds" "$out/corpus/$h" \
    "$source_dir/tests/fuzz/corpus/$h" "$out/artifacts" >"$out/$h.log" 2>&1
  echo $? >"$out/$h.status"
}
export -f run_one
export build out seconds source_dir

status=0
printf '%s\n' "${harnesses[@]}" | xargs -P "$jobs" -I{} bash -c 'run_one {}' || status=1

printf '%-26s %12s %8s %8s %s\n' harness executions cov ft result
for h in "${harnesses[@]}"; do
  log="$out/$h.log"
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  last=$(grep -E '^#[0-9]+' "$log" | tail -1 || true)
  cov=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$last")
  ft=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$last")
  if [ "$(cat "$out/$h.status" 2>/dev/null)" != 0 ]; then
    result="FINDING (see $log)"; status=1
  else
    result=ok
  fi
  printf '%-26s %12s %8s %8s %s\n' "$h" "${execs:-?}" "${cov:-?}" "${ft:-?}" "$result"
done
exit $status
