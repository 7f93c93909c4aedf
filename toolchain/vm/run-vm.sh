#!/usr/bin/env bash
# The virtual ARM board: boots Debian 12's arm64 kernel in qemu-system-aarch64
# (machine virt, Cortex-A72, TCG) with an initramfs holding the given arm64
# programs and files, runs one command in the guest and returns its exit
# status. The board has the devices the scanner drives:
#   /dev/dri/card0   virtio-gpu (DRM/KMS; flips are not paced by a vblank)
#   /dev/gpiochip0   the PL061 (8 lines); QEMU's power button is line 3,
#                    active high, a 100 ms pulse: --press-on / --press-after
#                    press it through the monitor (system_powerdown)
#   lo               loopback up (for Aravis's fake GigE camera)
#   /out             a host folder (virtio 9p): results written there, or
#                    copied there with --collect, are on the host afterwards
#   eth0             with --forward: QEMU's user network (restrict=on: the
#                    guest reaches nothing outside), 10.0.2.15/24, and the
#                    forwarded ports from the host's 127.0.0.1
#
# Usage: run-vm.sh [options] -- COMMAND [ARG...]
#   --build DIR       cross build folder: adds DIR/firmware/scanner/fpp-scanner,
#                     and fpp-scanner-sim when there (the same with the virtual
#                     scanner, for sim boards: a device build's has none)
#   --bin FILE        another arm64 executable for /fpp/bin (on PATH); repeatable
#   --lib-dir DIR     searched first for their shared libraries (e.g. a folder
#                     with the cross compiler's libasan: not its whole
#                     /usr/aarch64-linux-gnu/lib, whose libc beside the guest's
#                     loader hangs threaded programs); repeatable
#   --fake-camera     adds Aravis's fake GigE camera, arv-fake-gv-camera-0.8
#                     (start it in the guest: arv-fake-gv-camera-0.8 -i 127.0.0.1 &)
#   --files DIR       copied to /fpp/files, the command's working directory
#   --out DIR         host folder seen as /out in the guest (created; default a
#                     new folder under $TMPDIR, printed). The serial console
#                     is saved there as console.log
#   --collect PATH    guest path copied into /out after the command; repeatable
#   --tree H=G        host folder H copied to guest folder G; repeatable
#   --forward [HP:]GP the host's 127.0.0.1:HP reaches the guest's TCP port GP
#                     (on eth0, not the guest's loopback: listen on 0.0.0.0);
#                     without HP a free port is picked. Repeatable; each is
#                     written as a line "GP HP" to OUT/forwards before the
#                     VM starts, so that the caller (running this in the
#                     background) knows where to connect
#   --press-on REGEX  press the button when a console line printed by the
#                     command matches REGEX (bash ERE), each time it matches
#   --press-after S   press the button S seconds after the command started
#   --presses N       press at most N times (default: no limit)
#   --timeout S       whole run, boot included (default 240); then the VM is
#                     killed and the status is 124
#   --smp N           guest CPUs (default 2), --mem MB (default 1024)
#   --cache DIR       the kernel cache (default $FPP_VM_CACHE or /var/cache/fpp-vm,
#                     filled by fetch-deps.sh; nothing is downloaded here)
#   --quiet           do not echo the guest console to stdout
# The command runs under the guest's busybox sh (arguments are quoted for it).
# Exit status: the command's; 124 on timeout; 125 when the VM could not be
# built or booted, or the guest never reported the command's status.
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
cache="${FPP_VM_CACHE:-/var/cache/fpp-vm}"
build="" files="" out="" press_on="" press_after="" quiet=0 fake_camera=0
presses_max=-1 timeout_s=240 smp=2 mem=1024
bins=() collects=() lib_dirs=() trees=() forwards=()

usage() { awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; }
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --bin) bins+=("$2"); shift 2 ;;
    --fake-camera) fake_camera=1; shift ;;
    --lib-dir) lib_dirs+=("$2"); shift 2 ;;
    --files) files="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --collect) collects+=("$2"); shift 2 ;;
    --tree) trees+=("$2"); shift 2 ;;
    --forward)
      [[ "$2" =~ ^([0-9]+:)?[0-9]+$ ]] || { echo "run-vm: --forward takes [HOSTPORT:]GUESTPORT" >&2; exit 125; }
      forwards+=("$2"); shift 2 ;;
    --press-on) press_on="$2"; shift 2 ;;
    --press-after) press_after="$2"; shift 2 ;;
    --presses) presses_max="$2"; shift 2 ;;
    --timeout) timeout_s="$2"; shift 2 ;;
    --smp) smp="$2"; shift 2 ;;
    --mem) mem="$2"; shift 2 ;;
    --cache) cache="$2"; shift 2 ;;
    --quiet) quiet=1; shift ;;
    -h|--help) usage; exit 0 ;;
    --) shift; break ;;
    *) echo "run-vm: unknown argument '$1'" >&2; usage >&2; exit 125 ;;
  esac
done
[ $# -gt 0 ] || { echo "run-vm: no guest command (after --)" >&2; exit 125; }
for n in "$timeout_s" "$smp" "$mem"; do
  [[ "$n" =~ ^[0-9]+$ ]] || { echo "run-vm: '$n' is not a number" >&2; exit 125; }
done
[ "$presses_max" = -1 ] || [[ "$presses_max" =~ ^[0-9]+$ ]] ||
  { echo "run-vm: --presses takes a count" >&2; exit 125; }
[ -z "$press_after" ] || [[ "$press_after" =~ ^[0-9]+([.][0-9]+)?$ ]] ||
  { echo "run-vm: --press-after takes seconds" >&2; exit 125; }

if ! command -v qemu-system-aarch64 > /dev/null; then
  echo "run-vm: qemu-system-aarch64 not found (apt-get install qemu-system-arm)" >&2
  exit 125
fi
if [ ! -s "$cache/kernel-release" ]; then
  echo "run-vm: kernel cache $cache not filled (toolchain/vm/fetch-deps.sh)" >&2
  exit 125
fi
release=$(cat "$cache/kernel-release")
if [ -n "$build" ]; then
  scanner="$build/firmware/scanner/fpp-scanner"
  [ -x "$scanner" ] || { echo "run-vm: $scanner not found (build the cross build first)" >&2; exit 125; }
  bins=("$scanner" "${bins[@]}")
  [ ! -x "$scanner-sim" ] || bins=("$scanner-sim" "${bins[@]}")
fi
[ "$fake_camera" -eq 0 ] || bins+=("$cache/root/usr/bin/arv-fake-gv-camera-0.8")

now() { echo "$EPOCHREALTIME"; }
seconds_since() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.2f", b - a }'; }
t_start=$(now)

if [ -z "$out" ]; then out=$(mktemp -d "${TMPDIR:-/tmp}/fpp-vm-out.XXXXXX"); fi
mkdir -p "$out"
out=$(cd "$out" && pwd)
work=$(mktemp -d "${TMPDIR:-/tmp}/fpp-vm.XXXXXX")
qemu_pid=""
drain_pid=""
# shellcheck disable=SC2317 # called by the EXIT trap
cleanup() {
  if [ -n "$qemu_pid" ] && kill -0 "$qemu_pid" 2> /dev/null; then kill "$qemu_pid" 2> /dev/null || true; fi
  if [ -n "$drain_pid" ]; then kill "$drain_pid" 2> /dev/null || true; fi
  rm -rf "$work"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# The guest command as one busybox sh line, every argument single-quoted.
{
  line=""
  for a in "$@"; do line+="'${a//\'/\'\\\'\'}' "; done
  echo "$line"
} > "$work/cmd"
: > "$work/collect"
for c in "${collects[@]}"; do printf '%s\n' "$c" >> "$work/collect"; done

initramfs_args=(--cache "$cache" --out "$work/initramfs.cpio" --cmd-file "$work/cmd"
  --collect-file "$work/collect")
for b in "${bins[@]}"; do initramfs_args+=(--bin "$b"); done
for d in "${lib_dirs[@]}"; do initramfs_args+=(--lib-dir "$d"); done
for t in "${trees[@]}"; do initramfs_args+=(--tree "$t"); done
[ ${#forwards[@]} -eq 0 ] || initramfs_args+=(--net)
[ -z "$files" ] || initramfs_args+=(--files "$files")
if ! "$here/make-initramfs.sh" "${initramfs_args[@]}" >&2; then
  echo "run-vm: cannot build the initramfs" >&2
  exit 125
fi
t_initramfs=$(seconds_since "$t_start")

# The user network with the forwarded ports (toolchain/vm/forwards.sh).
# shellcheck source=toolchain/vm/forwards.sh
. "$here/forwards.sh"
forwarded_network run-vm "$out" "${forwards[@]}"

# The console comes through a FIFO so that every line is seen as it is
# printed; the monitor is a pair of FIFOs (monitor.in, monitor.out).
mkfifo "$work/console" "$work/monitor.in" "$work/monitor.out"
console_log="$out/console.log"
: > "$console_log"
# coreutils timeout: a last guard, should this script be killed outright.
timeout --kill-after=10 "$((timeout_s + 30))" qemu-system-aarch64 -M virt -cpu cortex-a72 -smp "$smp" -m "$mem" \
  -nodefaults -display none -no-reboot \
  -kernel "$cache/root/boot/vmlinuz-$release" -initrd "$work/initramfs.cpio" \
  -append "console=ttyAMA0 rdinit=/init quiet panic=-1" \
  -chardev stdio,id=console,signal=off -serial chardev:console \
  -chardev pipe,id=monitor,path="$work/monitor" -mon chardev=monitor,mode=readline \
  -device virtio-gpu-pci \
  -fsdev local,id=fppout,path="$out",security_model=none \
  -device virtio-9p-pci,fsdev=fppout,mount_tag=fppout \
  "${net_args[@]}" \
  < /dev/null > "$work/console" 2> "$work/qemu.err" &
qemu_pid=$!
exec 3< "$work/console"
# Both monitor FIFOs are opened read-write, which never blocks, so that
# neither side waits for a QEMU that failed to start or has exited.
exec 4<> "$work/monitor.in"
cat 0<> "$work/monitor.out" > "$work/monitor.log" &
drain_pid=$!

presses=0
press_button() {
  if [ "$presses_max" -ge 0 ] && [ "$presses" -ge "$presses_max" ]; then return; fi
  presses=$((presses + 1))
  echo "system_powerdown" >&4
  echo "run-vm: button pressed ($1) at $(seconds_since "$t_start") s" | tee -a "$console_log" >&2
}

t_init="" t_run="" t_run_abs="" t_done="" guest_status="" timed_out=0 pressed_after=0
handle_line() {
  local l=${1%$'\r'}
  printf '%s\n' "$l" >> "$console_log"
  [ "$quiet" -eq 1 ] || printf '%s\n' "$l"
  case "$l" in
    "fpp-vm-init: init at "*) t_init=$(seconds_since "$t_start") ;;
    "fpp-vm-init: run at "*) t_run=$(seconds_since "$t_start"); t_run_abs=$(now) ;;
    "fpp-vm-init: command done at "*) t_done=$(seconds_since "$t_start") ;;
    "fpp-vm-init: exit "*) guest_status=${l#fpp-vm-init: exit } ;;
    *)
      if [ -n "$press_on" ] && [ -n "$t_run" ] && [ -z "$t_done" ] && [[ "$l" =~ $press_on ]]; then
        press_button "console matched"
      fi
      ;;
  esac
}

deadline=$(awk -v a="$t_start" -v t="$timeout_s" 'BEGIN { printf "%.6f", a + t }')
partial=""
while :; do
  chunk=""
  if IFS= read -r -t 0.5 chunk <&3; then
    handle_line "$partial$chunk"
    partial=""
  else
    rc=$?
    if [ "$rc" -le 128 ]; then # end of the console: QEMU exited
      [ -z "$partial$chunk" ] || handle_line "$partial$chunk"
      break
    fi
    partial+="$chunk" # a timed-out read keeps what it had read of the line
  fi
  if [ -n "$press_after" ] && [ -n "$t_run_abs" ] && [ "$pressed_after" -eq 0 ] &&
    awk -v a="$t_run_abs" -v s="$press_after" -v n="$(now)" 'BEGIN { exit !(n - a >= s) }'; then
    pressed_after=1
    press_button "after ${press_after} s"
  fi
  if awk -v d="$deadline" -v n="$(now)" 'BEGIN { exit !(n >= d) }'; then
    timed_out=1
    echo "run-vm: timeout after ${timeout_s} s: stopping the VM" | tee -a "$console_log" >&2
    kill "$qemu_pid" 2> /dev/null || true
    break
  fi
done
exec 3<&-
qemu_status=0
wait "$qemu_pid" || qemu_status=$?
qemu_pid=""
kill "$drain_pid" 2> /dev/null || true
wait "$drain_pid" 2> /dev/null || true
drain_pid=""
exec 4>&-
t_total=$(seconds_since "$t_start")

if [ -s "$work/qemu.err" ]; then sed 's/^/run-vm: qemu: /' "$work/qemu.err" >&2; fi
echo "run-vm: initramfs ${t_initramfs} s, guest /init at ${t_init:-?} s, command from ${t_run:-?} s" \
  "to ${t_done:-?} s, total ${t_total} s (wall clock from the start of run-vm)" >&2
echo "run-vm: results in $out" >&2
if [ "$timed_out" -eq 1 ]; then exit 124; fi
if ! [[ "$guest_status" =~ ^[0-9]+$ ]]; then
  echo "run-vm: the guest did not report the command's status (QEMU status $qemu_status," \
    "see $console_log)" >&2
  exit 125
fi
exit "$guest_status"
