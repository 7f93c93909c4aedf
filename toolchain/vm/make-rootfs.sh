#!/usr/bin/env bash
# Builds the virtual ARM board's Debian disk: Debian 13 (trixie, the release
# the board files name; or 12, bookworm, with --suite) arm64, minbase with
# systemd, booted by run-booted.sh with the cached kernel, on which
# tests/vm/run_vm_booted.sh installs the scanner's .deb as a user would. Run
# at install time (install-deps.sh vm, after fetch-deps.sh); the tests never
# build or download it.
#   1. debootstrap, both stages, on this machine: the packages downloaded
#      (kept in CACHE/rootfs-debs for the next build) and unpacked, and their
#      arm64 maintainer scripts run in the chroot through qemu-user (the
#      qemu-aarch64 binfmt_misc entry with its F flag, which install-deps.sh
#      cross registers)
#   2. the board's own files (below), its units enabled in the chroot
#   3. the disk image made from that folder with mkfs.ext4 -d (no mounts,
#      no loop devices), and the boot initramfs
# The disk holds every runtime dependency of the fpp-scanner package for
# that release (the Depends of board/CMakeLists.txt, read from it), because
# the guest reaches no mirror, and:
#   /usr/local/bin/arv-fake-gv-camera-0.8  Aravis's fake GigE camera, from
#        fetch-deps.sh's cache (its package would bring GTK and GStreamer)
#   /etc/systemd/network/10-fpp-vm.network  the wired card: 10.0.2.15/24
#        via 10.0.2.2, QEMU's user network (systemd-networkd)
#   fpp-vm-hook.service  at boot: mounts the host's folders (9p: fppin at
#        /fpp/in read-only, fppout at /out), runs /fpp/in/guest.sh (output on
#        the console and in /out/guest.log, "fpp-vm-hook: exit N"), powers off
# Output: CACHE/rootfs-SUITE/debian-arm64.img (ext4, 2 GiB sparse),
# boot-initrd.cpio (busybox, the modules the disk and the board need,
# boot-init.sh as /init) and stamp, written last: a hash of these scripts,
# the package list and the kernel release. A run with a matching stamp does
# nothing.
#
# Usage: toolchain/vm/make-rootfs.sh [--suite trixie|bookworm] [--cache DIR] [--force]
#   --suite S    the Debian release (default trixie)
#   --cache DIR  default: $FPP_VM_CACHE or /var/cache/fpp-vm (fetch-deps.sh's)
#   --force      build again even when the stamp matches
# FPP_VM_MIRROR: the Debian mirror (default http://deb.debian.org/debian).
# Needs root (debootstrap, chroot), debootstrap, e2fsprogs, cpio,
# qemu-user-static registered with binfmt_misc.
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
source_dir=$(cd "$here/../.." && pwd)
cache="${FPP_VM_CACHE:-/var/cache/fpp-vm}"
mirror="${FPP_VM_MIRROR:-http://deb.debian.org/debian}"
force=0 suite=trixie
while [ $# -gt 0 ]; do
  case "$1" in
    --suite) suite="$2"; shift 2 ;;
    --cache) cache="$2"; shift 2 ;;
    --force) force=1; shift ;;
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
    *) echo "make-rootfs: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
t_start=$EPOCHREALTIME
elapsed() { awk -v a="$t_start" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.0f", b - a }'; }

if [ ! -s "$cache/kernel-release" ]; then
  echo "make-rootfs: kernel cache $cache not filled (run toolchain/vm/fetch-deps.sh first)" >&2
  exit 1
fi
release=$(cat "$cache/kernel-release")
fake_camera="$cache/root/usr/bin/arv-fake-gv-camera-0.8"
[ -x "$fake_camera" ] || { echo "make-rootfs: no $fake_camera (fetch-deps.sh)" >&2; exit 1; }

case "$suite" in
  bookworm) gpiod_package=libgpiod2 ;; # libgpiod 1.6's library
  trixie) gpiod_package=libgpiod3 ;;   # libgpiod 2.2's
  *) echo "make-rootfs: --suite bookworm or trixie, not '$suite'" >&2; exit 2 ;;
esac
# The package's runtime dependencies on the disk's release, as
# board/CMakeLists.txt declares them (FPP_DEB_DEPENDS_<suite>; the GPIO
# driver's library is the variable the driver's libgpiod picks).
depends=$(awk -v v="set(FPP_DEB_DEPENDS_$suite" 'index($0, v) { getline; print; exit }' \
  "$source_dir/board/CMakeLists.txt" | sed "s/^ *\"//; s/\"$//; s/\${gpiod_$suite}/$gpiod_package/")
if [[ "$depends" != libc6* ]] || [[ "$depends" == *"\${"* ]]; then
  echo "make-rootfs: no Debian $suite Depends found in board/CMakeLists.txt" >&2
  exit 1
fi
packages=(systemd systemd-sysv dbus udev kmod)
# Names only: the version constraints in parentheses dropped.
# shellcheck disable=SC2013 # words, not lines
for d in $(sed 's/([^)]*)//g; s/,/ /g' <<< "$depends"); do packages+=("$d"); done
mapfile -t packages < <(printf '%s\n' "${packages[@]}" | LC_ALL=C sort -u)
include=$(IFS=,; echo "${packages[*]}")

out="$cache/rootfs-$suite"
key=$( { cat "$here/make-rootfs.sh" "$here/boot-init.sh" "$here/make-initramfs.sh"
  echo "$include $release"; } | sha256sum | cut -d' ' -f1)
if [ "$force" -eq 0 ] && [ "$(cat "$out/stamp" 2> /dev/null)" = "$key" ] &&
  [ -s "$out/debian-arm64.img" ] && [ -s "$out/boot-initrd.cpio" ]; then
  echo "make-rootfs: $out/debian-arm64.img up to date"
  exit 0
fi
for tool in debootstrap mkfs.ext4 cpio chroot; do
  command -v "$tool" > /dev/null ||
    { echo "make-rootfs: $tool not found (toolchain/install-deps.sh vm installs it)" >&2; exit 1; }
done
[ "$(id -u)" -eq 0 ] || { echo "make-rootfs: debootstrap needs root" >&2; exit 1; }
binfmt=/proc/sys/fs/binfmt_misc/qemu-aarch64
if [ "$(head -n 1 "$binfmt" 2> /dev/null)" != enabled ] || ! grep -q '^flags: .*F' "$binfmt"; then
  echo "make-rootfs: arm64 programs do not run here: no qemu-aarch64 entry with the F flag in" \
    "binfmt_misc (toolchain/install-deps.sh cross registers it)" >&2
  exit 1
fi

work="$cache/rootfs-$suite.new"
rm -rf "$work"
mkdir -p "$work" "$cache/rootfs-debs"
# $work stays after a failure, for its logs (the next run removes it).
tree="$work/tree"

# --- 1. debootstrap, both stages -------------------------------------------------
echo "make-rootfs: debootstrap $suite arm64 from $mirror, with ${packages[*]}"
if ! debootstrap --arch=arm64 --variant=minbase --cache-dir="$cache/rootfs-debs" \
  --include="$include" "$suite" "$tree" "$mirror" > "$work/debootstrap.log" 2>&1; then
  tail -n 30 "$work/debootstrap.log" >&2
  echo "make-rootfs: debootstrap failed (log above; the target's: $tree/debootstrap/debootstrap.log)" >&2
  exit 1
fi
echo "make-rootfs: debootstrap done at $(elapsed) s"

# --- 2. The board's files --------------------------------------------------------
echo fpp-vm > "$tree/etc/hostname"
printf '127.0.0.1 localhost\n127.0.1.1 fpp-vm\n::1 localhost ip6-localhost ip6-loopback\n' > "$tree/etc/hosts"
# boot-init.sh mounts the disk read-write; no fsck at boot.
echo "/dev/vda / ext4 rw,errors=remount-ro 0 0" > "$tree/etc/fstab"
mkdir -p "$tree/usr/local/bin" "$tree/usr/local/sbin" "$tree/etc/systemd/system"
install -m 0755 "$fake_camera" "$tree/usr/local/bin/arv-fake-gv-camera-0.8"
mkdir -p "$tree/etc/systemd/network"
cat > "$tree/etc/systemd/network/10-fpp-vm.network" << 'UNIT'
# QEMU's user network (run-booted.sh --forward): forwarded ports arrive here.
[Match]
Type=ether

[Network]
Address=10.0.2.15/24
Gateway=10.0.2.2
LinkLocalAddressing=no
IPv6AcceptRA=no
UNIT
cat > "$tree/usr/local/sbin/fpp-vm-hook" << 'HOOK'
#!/bin/sh
# fpp-vm-hook.service (the virtual ARM board's Debian disk, make-rootfs.sh):
# mounts the host's folders, runs the host's /fpp/in/guest.sh as root, with
# its output on the console and in /out/guest.log, and powers off.
say() { echo "fpp-vm-hook: $*"; }
opts=trans=virtio,version=9p2000.L,msize=262144
mkdir -p /fpp/in /out
mount -t 9p -o "$opts" fppout /out || say "cannot mount the host's /out (fppout)"
status=0
if mount -t 9p -o "$opts,ro" fppin /fpp/in 2> /dev/null && [ -f /fpp/in/guest.sh ]; then
  say "guest.sh at $(cut -d' ' -f1 /proc/uptime) s"
  { sh /fpp/in/guest.sh < /dev/null 2>&1; echo $? > /run/fpp-vm-hook.status; } | tee /out/guest.log
  status=$(cat /run/fpp-vm-hook.status)
else
  say "no /fpp/in/guest.sh"
fi
sync
say "exit $status"
systemctl poweroff --no-block
HOOK
chmod 0755 "$tree/usr/local/sbin/fpp-vm-hook"
cat > "$tree/etc/systemd/system/fpp-vm-hook.service" << 'UNIT'
# The host's /fpp/in/guest.sh once the system is up, then power off
# (/usr/local/sbin/fpp-vm-hook). Type=exec: the boot is finished without it.
[Unit]
Description=fpp virtual ARM board: the host's guest.sh, then power off
After=basic.target network.target systemd-networkd.service

[Service]
Type=exec
ExecStart=/usr/local/sbin/fpp-vm-hook
StandardOutput=journal+console
StandardError=inherit

[Install]
WantedBy=multi-user.target
UNIT
# The units enabled, nothing left half configured, the package files gone.
chroot "$tree" systemctl enable systemd-networkd.service fpp-vm-hook.service
chroot "$tree" dpkg --audit
chroot "$tree" apt-get clean
echo "make-rootfs: Debian $(cat "$tree/etc/debian_version"), $(chroot "$tree" systemctl --version | head -n 1)"

image="$work/debian-arm64.img"
truncate -s 2G "$image"
mkfs.ext4 -q -L fpp-vm -d "$tree" "$image"
echo "make-rootfs: image made at $(elapsed) s"

# --- The boot initramfs -----------------------------------------------------------
"$here/make-initramfs.sh" --cache "$cache" --out "$work/boot-initrd.cpio" --init "$here/boot-init.sh" \
  --module virtio_blk --module crc32c_generic --module ext4 --net > /dev/null

rm -rf "$out"
mkdir -p "$out"
mv "$image" "$work/boot-initrd.cpio" "$out/"
echo "$key" > "$out/stamp"
rm -rf "$work"
echo "make-rootfs: $out ready in $(elapsed) s: disk $(du -h "$out/debian-arm64.img" | cut -f1) used" \
  "of $(du -h --apparent-size "$out/debian-arm64.img" | cut -f1), packages cached" \
  "$(du -sh "$cache/rootfs-debs" | cut -f1)"
