#!/bin/busybox sh
# shellcheck shell=dash
# /init of the initramfs that boots the virtual ARM board's Debian disk
# (make-rootfs.sh builds both; run-booted.sh boots them). Debian's kernel has
# virtio-blk, ext4, virtio-gpu, 9p and virtio-net as modules and the disk
# carries none, so they are loaded here (the list in /lib/modules/load-order,
# dependencies first) and stay loaded for the booted system. Then the disk
# (root=, default /dev/vda) is mounted read-write and /sbin/init (systemd)
# runs on it as PID 1. The gpio-keys driver is not
# loaded, so that the power button's PL061 line 3 stays free for libgpiod.
/bin/busybox --install -s /bin
export PATH=/usr/bin:/bin
say() { echo "fpp-vm-boot: $*"; }
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev
say "initramfs at $(cut -d' ' -f1 /proc/uptime) s (kernel $(uname -r))"
while read -r module; do
  insmod "/lib/modules/$module" || say "insmod $module failed"
done < /lib/modules/load-order
root=/dev/vda
init=/sbin/init
for arg in $(cat /proc/cmdline); do
  case "$arg" in
    root=*) root=${arg#root=} ;;
  esac
done
i=0
while [ ! -b "$root" ] && [ $i -lt 100 ]; do sleep 0.1; i=$((i + 1)); done
mkdir -p /newroot
if ! mount -t ext4 -o rw "$root" /newroot; then
  say "cannot mount $root"
  poweroff -f
fi
# (-L: /sbin/init is an absolute link, which resolves on the disk only.)
if [ ! -x "/newroot$init" ] && [ ! -L "/newroot$init" ]; then
  say "no $init on $root"
  umount /newroot
  poweroff -f
fi
say "switching to $root, $init at $(cut -d' ' -f1 /proc/uptime) s"
umount /dev /sys /proc
exec switch_root /newroot "$init"
