#!/bin/busybox sh
# shellcheck shell=dash
# /init of the virtual ARM board's initramfs (made by make-initramfs.sh).
# Loads the modules listed in /lib/modules/load-order (virtio PCI, virtio-gpu
# DRM, 9p), mounts the host's result folder at /out (virtio 9p, tag fppout),
# prints what the kernel shows of DRM and GPIO, runs /fpp/cmd in /fpp/files
# and powers off. run-vm.sh reads the lines starting with "fpp-vm-init:" on
# the serial console: "run" when the command starts, "exit N" with its status.
# The gpio-keys driver is not loaded, so that the power button's line (PL061
# line 3) stays free for libgpiod. With /fpp/net (run-vm.sh --forward) eth0
# gets QEMU's user-network address, 10.0.2.15/24 through 10.0.2.2, where the
# host's forwarded ports arrive.
/bin/busybox --install -s /bin
export PATH=/fpp/bin:/usr/bin:/bin HOME=/tmp TERM=dumb
umask 022

say() { echo "fpp-vm-init: $*"; }
uptime_s() { cut -d' ' -f1 /proc/uptime; }

mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev
mkdir -p /dev/shm /tmp && mount -t tmpfs shm /dev/shm
say "init at $(uptime_s) s (kernel $(uname -r))"

while read -r module; do
  insmod "/lib/modules/$module" || say "insmod $module failed"
done < /lib/modules/load-order
ifconfig lo 127.0.0.1 up || say "no loopback"
if [ -e /fpp/net ]; then
  i=0
  while [ ! -e /sys/class/net/eth0 ] && [ $i -lt 50 ]; do sleep 0.1; i=$((i + 1)); done
  if ifconfig eth0 10.0.2.15 netmask 255.255.255.0 up && route add default gw 10.0.2.2; then
    say "net eth0 10.0.2.15/24 via 10.0.2.2"
  else
    say "net: no eth0"
  fi
fi
if ! mount -t 9p -o trans=virtio,version=9p2000.L,msize=262144 fppout /out; then
  say "cannot mount the result share at /out"
fi
# virtio-gpu registers its DRM device asynchronously after insmod.
i=0
while [ ! -e /dev/dri/card0 ] && [ $i -lt 50 ]; do sleep 0.1; i=$((i + 1)); done
say "devices ready at $(uptime_s) s"

for c in /sys/class/drm/card*-*; do
  [ -e "$c/status" ] || continue
  say "drm ${c##*/}: $(cat "$c/status"), modes $(head -n 3 "$c/modes" | tr '\n' ' ')"
done
[ -e /dev/dri/card0 ] || say "drm: no /dev/dri/card0"
if command -v gpiodetect > /dev/null && gpiodetect > /tmp/gpio.txt 2>&1; then
  while read -r line; do say "gpio $line"; done < /tmp/gpio.txt
  gpioinfo > /tmp/gpio.txt 2>&1
  while read -r line; do say "gpio $line"; done < /tmp/gpio.txt
else
  for chip in /sys/bus/gpio/devices/gpiochip*; do
    [ -e "$chip" ] && say "gpio ${chip##*/} at $(readlink -f "$chip" | sed 's|/sys/devices/||')"
  done
fi
[ -e /dev/gpiochip0 ] || say "gpio: no /dev/gpiochip0"

cd /fpp/files || cd /
say "run at $(uptime_s) s"
sh /fpp/cmd < /dev/null
status=$?
say "command done at $(uptime_s) s"
# Guest paths the host asked for (one a line), copied into /out.
if [ -s /fpp/collect ]; then
  while read -r path; do
    [ -n "$path" ] || continue
    cp -a "$path" /out/ || say "cannot collect $path"
  done < /fpp/collect
fi
sync
umount /out 2> /dev/null
say "exit $status"
poweroff -f
