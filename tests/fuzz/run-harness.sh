#!/usr/bin/env bash
# One harness for a bounded time on its corpus, as the fuzz preset's tests and
# run-long.sh run it: seed 1, 5 s per input, 1 GB, new inputs into WORK
# (emptied first when --fresh), findings kept as ARTIFACTS/HARNESS-<kind>-<sha>.
#
# libFuzzer's per-input limit is wall-clock time, so a machine that stalls
# (a busy CI host, swap) can report a timeout for an input that is fast. A
# timeout is therefore judged again on the input alone: still over 5 s, it is
# a hang (the run fails); under, it was a stall, kept as .stall, and fuzzing
# goes on for the time left (at most five stalls). Every other finding fails
# the run as it is.
# Usage: run-harness.sh [--fresh] BINARY SECONDS WORK CORPUS ARTIFACTS
set -uo pipefail

fresh=0
if [ "${1:-}" = --fresh ]; then fresh=1; shift; fi
[ $# -eq 5 ] || { sed -n '2,12p' "$0" >&2; exit 2; }
bin=$1 seconds=$2 work=$3 corpus=$4 artifacts=$5
name=$(basename "$bin")
per_input=5

if [ $fresh -eq 1 ]; then rm -rf "$work"; fi
mkdir -p "$work" "$artifacts"
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1

# Timeouts left by an earlier run are not this run's (stalls stay, marked).
shopt -s nullglob
for old in "$artifacts/$name-timeout-"*; do
  [[ $old == *.stall ]] || rm -f "$old"
done
deadline=$((SECONDS + seconds))
for _ in 1 2 3 4 5; do
  "$bin" -seed=1 -max_total_time=$((deadline > SECONDS ? deadline - SECONDS : 1)) \
    -rss_limit_mb=1024 -timeout=$per_input -print_final_stats=1 \
    -artifact_prefix="$artifacts/$name-" "$work" "$corpus"
  status=$?
  [ $status -eq 0 ] && exit 0

  timeouts=()
  for t in "$artifacts/$name-timeout-"*; do [[ $t == *.stall ]] || timeouts+=("$t"); done
  others=("$artifacts/$name-"{crash,leak,oom,slow-unit}-*)
  if [ ${#timeouts[@]} -ne 1 ] || [ ${#others[@]} -ne 0 ]; then exit $status; fi

  input=${timeouts[0]}
  echo "run-harness: libFuzzer reported a timeout; running $input alone"
  alone=$("$bin" -timeout=$per_input -rss_limit_mb=1024 "$input" 2>&1)
  again=$?
  echo "$alone"
  took=$(sed -n 's/^Executed .* in \([0-9]*\) ms$/\1/p' <<<"$alone")
  if [ $again -ne 0 ]; then
    echo "run-harness: the input fails alone too (exit $again): a finding"
    exit $again
  fi
  echo "run-harness: the input takes ${took:-?} ms alone: the machine stalled, not the" \
    "reader (input kept as $input.stall); fuzzing on"
  mv "$input" "$input.stall"
  [ $SECONDS -ge $deadline ] && exit 0
done
echo "run-harness: five stalls: the machine is too busy to judge; no finding"
exit 0
