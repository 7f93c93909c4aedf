#!/usr/bin/env bash
# Boots the virtual ARM board's Debian disk (make-rootfs.sh): the same
# machine as run-vm.sh (qemu-system-aarch64 -M virt, Cortex-A72, TCG,
# virtio-gpu, the PL061 GPIO chip), Debian 12's arm64 kernel (6.1, also
# under the Debian 13 disk: a board brings its own kernel) and the boot
# initramfs from the cache, the disk as /dev/vda, systemd as PID 1, until the
# guest powers off. The disk image is not written: QEMU keeps the guest's
# writes in a temporary overlay that goes with it (snapshot=on), so that
# every boot starts from the cached image as make-rootfs.sh left it.
#   /fpp/in    a host folder, read-only (virtio 9p, tag fppin): the disk's
#              fpp-vm-hook.service runs /fpp/in/guest.sh when there, with
#              its output on the console and in /out/guest.log, then powers
#              the guest off (make-rootfs.sh)
#   /out       a host folder, read-write (tag fppout); the console is saved
#              there as console.log
#   network    with --forward: QEMU's user network (restrict=on: the guest
#              reaches nothing outside), the guest's 10.0.2.15 (systemd-
#              networkd), the host's 127.0.0.1:HP forwarded to guest port GP
#
# Usage: run-booted.sh --in DIR --out DIR [--forward [HP:]GP]... [--timeout S]
#          [--smp N] [--mem MB] [--cache DIR] [--image F] [--quiet]
#   --forward   as run-vm.sh's: "GP HP" lines in OUT/forwards before QEMU starts
#   --timeout S the whole run (default 600); then QEMU is killed: status 124
#   --image F   the disk (default CACHE/rootfs-trixie/debian-arm64.img; its
#               boot-initrd.cpio beside it)
# Exit status: 0 when the guest powered off (the hook's own result is what
# guest.sh wrote to /out), 124 on timeout, 125 when QEMU could not run.
set -euo pipefail

cache="${FPP_VM_CACHE:-/var/cache/fpp-vm}"
in="" out="" timeout_s=600 smp=2 mem=1024 quiet=0 image=""
forwards=()
usage() { awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; }
while [ $# -gt 0 ]; do
  case "$1" in
    --in) in="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --forward)
      [[ "$2" =~ ^([0-9]+:)?[0-9]+$ ]] || { echo "run-booted: --forward takes [HOSTPORT:]GUESTPORT" >&2; exit 125; }
      forwards+=("$2"); shift 2 ;;
    --timeout) timeout_s="$2"; shift 2 ;;
    --smp) smp="$2"; shift 2 ;;
    --mem) mem="$2"; shift 2 ;;
    --cache) cache="$2"; shift 2 ;;
    --image) image="$2"; shift 2 ;;
    --quiet) quiet=1; shift ;;
    -h|--help) usage; exit 0 ;;
    *) echo "run-booted: unknown argument '$1'" >&2; usage >&2; exit 125 ;;
  esac
done
for n in "$timeout_s" "$smp" "$mem"; do
  [[ "$n" =~ ^[0-9]+$ ]] || { echo "run-booted: '$n' is not a number" >&2; exit 125; }
done
[ -n "$out" ] || { echo "run-booted: --out DIR is required" >&2; exit 125; }
command -v qemu-system-aarch64 > /dev/null ||
  { echo "run-booted: qemu-system-aarch64 not found (apt-get install qemu-system-arm)" >&2; exit 125; }
[ -s "$cache/kernel-release" ] ||
  { echo "run-booted: kernel cache $cache not filled (toolchain/vm/fetch-deps.sh)" >&2; exit 125; }
release=$(cat "$cache/kernel-release")
image="${image:-$cache/rootfs-trixie/debian-arm64.img}"
initrd="$(dirname "$image")/boot-initrd.cpio"
for f in "$image" "$initrd"; do
  [ -s "$f" ] || { echo "run-booted: no $f (toolchain/vm/make-rootfs.sh)" >&2; exit 125; }
done
mkdir -p "$out"
out=$(cd "$out" && pwd)
# shellcheck disable=SC2054 # QEMU's option lists, one element each
share_args=(-fsdev "local,id=fppout,path=$out,security_model=none"
  -device virtio-9p-pci,fsdev=fppout,mount_tag=fppout)
if [ -n "$in" ]; then
  in=$(cd "$in" && pwd)
  # shellcheck disable=SC2054
  share_args+=(-fsdev "local,id=fppin,path=$in,security_model=none,readonly=on"
    -device virtio-9p-pci,fsdev=fppin,mount_tag=fppin)
fi

# The user network with the forwarded ports (toolchain/vm/forwards.sh).
# shellcheck source=toolchain/vm/forwards.sh
. "$(dirname "$0")/forwards.sh"
forwarded_network run-booted "$out" "${forwards[@]}"

# cache=unsafe: QEMU ignores the guest's flushes (dpkg syncs every file it
# unpacks, each a sync of the overlay here); the overlay is thrown away.
drive="file=$image,format=raw,if=virtio,cache=unsafe,snapshot=on"
append="console=ttyAMA0 root=/dev/vda quiet panic=-1"

t_start=$EPOCHREALTIME
console_log="$out/console.log"
: > "$console_log"
status=0
# The console through a pipe into the log (and stdout unless --quiet).
if [ "$quiet" -eq 1 ]; then tee_out=/dev/null; else tee_out=/dev/stdout; fi
set +e
timeout --kill-after=10 "$timeout_s" qemu-system-aarch64 -M virt -cpu cortex-a72 -smp "$smp" -m "$mem" \
  -nodefaults -display none -no-reboot \
  -kernel "$cache/root/boot/vmlinuz-$release" -initrd "$initrd" -append "$append" \
  -chardev stdio,id=console,signal=off -serial chardev:console \
  -device virtio-gpu-pci \
  -drive "$drive" \
  "${share_args[@]}" "${net_args[@]}" \
  < /dev/null 2> "$out/qemu.err" | sed -u 's/\r$//' | tee -a "$console_log" > "$tee_out"
status=${PIPESTATUS[0]}
set -e
t_total=$(awk -v a="$t_start" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.1f", b - a }')
if [ -s "$out/qemu.err" ]; then sed 's/^/run-booted: qemu: /' "$out/qemu.err" >&2; fi
echo "run-booted: QEMU ran ${t_total} s (status $status)" >&2
case "$status" in
  0) exit 0 ;;
  124|137) echo "run-booted: timeout after ${timeout_s} s: VM killed" >&2; exit 124 ;;
  *) exit 125 ;;
esac
