#!/bin/sh
# fpp-vm-until COUNT PATTERN COMMAND [ARG...]: runs COMMAND in the guest with
# its output (stdout and stderr) passed on line by line, and sends it SIGTERM
# when the COUNT-th line matching the shell glob PATTERN appears; exits with
# COMMAND's status. For a program that waits for the button forever, e.g.
#   fpp-vm-until 2 '*idle: waiting for the button*' fpp-scanner --board b.yaml
# stops the scanner when it is back waiting after the first button scan
# (run-vm.sh --press-on 'idle: waiting for the button' --presses 1).
# With FPP_VM_UNTIL_COPY=FILE each line is also appended to FILE, for a
# watcher in the guest that acts on the command's log.
# Part of the virtual board's initramfs (/fpp/bin/fpp-vm-until).
if [ $# -lt 3 ]; then
  echo "usage: fpp-vm-until COUNT PATTERN COMMAND [ARG...]" >&2
  exit 2
fi
count=$1
pattern=$2
shift 2
fifo=/tmp/fpp-vm-until.$$
mkfifo "$fifo" || exit 2
"$@" > "$fifo" 2>&1 &
pid=$!
seen=0
while IFS= read -r line; do
  echo "$line"
  [ -z "${FPP_VM_UNTIL_COPY:-}" ] || echo "$line" >> "$FPP_VM_UNTIL_COPY"
  # shellcheck disable=SC2254 # the pattern is a glob on purpose
  case "$line" in
    $pattern)
      seen=$((seen + 1))
      if [ "$seen" -eq "$count" ]; then
        echo "fpp-vm-until: line $seen matched: stopping $1"
        kill -TERM "$pid"
      fi
      ;;
  esac
done < "$fifo"
wait "$pid"
status=$?
rm -f "$fifo"
exit $status
