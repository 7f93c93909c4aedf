#!/usr/bin/env bash
# Builds the scanner's Debian package from a build folder and checks what a
# board would get: the binary for the right architecture with few runtime
# dependencies (no OpenCV, no GUI toolkit), the default board as a conffile,
# every board description, the hardened service (systemd-analyze verify) and
# its user and udev rule, and maintainer scripts that do not enable anything.
# Usage: check_deb.sh BUILD_DIR DEB_ARCH
set -euo pipefail
build="$1"
arch="$2"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

cpack --config "$build/CPackConfig.cmake" -B "$work/out" > "$work/cpack.log" 2>&1 ||
  { cat "$work/cpack.log" >&2; fail "cpack"; }
deb="$(ls "$work"/out/*.deb)"
echo "package: $(basename "$deb"), $(stat -c %s "$deb") bytes"

info="$(dpkg-deb -I "$deb")"
grep -q "^ Package: fpp-scanner$" <<< "$info" || fail "package name"
grep -q "^ Architecture: $arch$" <<< "$info" || fail "architecture is not $arch"
depends="$(grep "^ Depends:" <<< "$info")"
grep -qi "opencv\|gtk\|qt5\|qt6" <<< "$depends" && fail "heavy dependency: $depends"
grep -q "libaravis-0.8-0" <<< "$depends" || fail "aravis missing from $depends"

contents="$(dpkg-deb -c "$deb")"
for path in ./usr/bin/fpp-scanner ./etc/fpp-scanner/board.yaml \
            ./lib/systemd/system/fpp-scanner.service ./usr/lib/sysusers.d/fpp-scanner.conf \
            ./lib/udev/rules.d/60-fpp-scanner-gpio.rules \
            ./usr/share/fpp-scanner/boards/rpi5.yaml ./usr/share/fpp-scanner/boards/rock5b.yaml \
            ./usr/share/fpp-scanner/boards/sim.yaml ./usr/share/fpp-scanner/boards/sim/paper-rig-effects.yaml; do
  grep -q " $path$" <<< "$contents" || fail "$path not in the package"
done
grep -q "fpp-calib" <<< "$contents" && fail "the host tool does not belong on the device"

dpkg-deb -e "$deb" "$work/control"
grep -qx "/etc/fpp-scanner/board.yaml" "$work/control/conffiles" || fail "board.yaml is not a conffile"
grep -v "^[[:space:]]*#" "$work/control/postinst" | grep -q "systemctl enable" &&
  fail "postinst must not enable the service"

dpkg-deb -x "$deb" "$work/root"
binary="$work/root/usr/bin/fpp-scanner"
case "$arch" in
  arm64) file_arch="AArch64" ;;
  amd64) file_arch="X86-64" ;;
  *) file_arch="" ;;
esac
machine="$(readelf -h "$binary" | sed -n 's/^ *Machine: *//p')"
[[ -z "$file_arch" || "$machine" == *"$file_arch"* ]] || fail "binary is for $machine, not $arch"
needed="$(readelf -d "$binary" | sed -n 's/.*Shared library: \[\(.*\)\]/\1/p' | tr '\n' ' ')"
echo "fpp-scanner: $machine, $(stat -c %s "$binary") bytes; needs: $needed"
grep -qi "opencv\|gtk\|Qt" <<< "$needed" && fail "heavy runtime dependency: $needed"

# The unit as systemd reads it (the binary path pointed at the extracted one).
sed "s|/usr/bin/fpp-scanner|$binary|" "$work/root/lib/systemd/system/fpp-scanner.service" \
  > "$work/fpp-scanner.service"
if command -v systemd-analyze > /dev/null; then
  systemd-analyze verify "$work/fpp-scanner.service" || fail "systemd-analyze verify"
  systemd-analyze security --offline=true "$work/fpp-scanner.service" 2>/dev/null |
    tail -n 1 || true
fi
echo "OK"
