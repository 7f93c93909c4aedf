#!/usr/bin/env bash
# Builds the scanner's Debian package from a build folder and checks what a
# board would get: the binary for the right architecture with few runtime
# dependencies (no OpenCV, no GUI toolkit), the default board as a conffile,
# every board description, the HTTP API's page (firmware/scanner/web) with
# the libraries and three.js it needs, the hardened service (systemd-analyze
# verify, exposure at most 2.0, the API's port the only one it may bind) and
# its user and udev rule, and maintainer scripts that do not enable anything
# and make the API's token once (run with DPKG_ROOT in a scratch root, the
# commands that would touch this machine replaced by stubs). The sim boards
# and their rigs are shipped only with a binary that has the virtual scanner
# (FPP_SCANNER_SIM ON: with-sim); the device build (without-sim) has none.
# Usage: check_deb.sh BUILD_DIR DEB_ARCH [with-sim|without-sim]
set -euo pipefail
build="$1"
arch="$2"
sim="${3:-with-sim}"
source_dir="$(cd "$(dirname "$0")/../.." && pwd)"
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
for dep in libaravis-0.8-0 libmicrohttpd12 libarchive13 libjs-three; do
  grep -q "\b$dep" <<< "$depends" || fail "$dep missing from $depends"
done
# libgpiod's package is the one whose library the scanner links: libgpiod2
# ships libgpiod.so.2 (libgpiod 1.x), libgpiod3 libgpiod.so.3 (2.x).
soname=$(readelf -d "$build/firmware/scanner/fpp-scanner" |
  sed -n 's/.*(NEEDED).*\[libgpiod\.so\.\([0-9]*\)\]/\1/p')
if [ -n "$soname" ]; then
  grep -q "\blibgpiod$soname\b" <<< "$depends" ||
    fail "fpp-scanner links libgpiod.so.$soname, the package does not depend on libgpiod$soname: $depends"
fi
# Every package it depends on exists, for its architecture, in this
# machine's release (the names differ between Debian 12 and 13): apt would
# refuse the package otherwise.
mapfile -t names < <(sed 's/^ Depends: //; s/([^)]*)//g; s/,/\n/g' <<< "$depends" | tr -d ' ')
# (A build against libgpiod 2 from outside this machine's index, preset
# aarch64-gpiod2, names libgpiod3 on Debian 12: that one is only checked
# against what fpp-scanner links, above.)
outside="$(sed -n 's/^FPP_LIBGPIOD2_PREFIX:[A-Z]*=\(..*\)$/libgpiod3/p' "$build/CMakeCache.txt")"
for name in "${names[@]}"; do
  [ -n "$name" ] && [ "$name" != "$outside" ] || continue
  # (the whole record first: grep -q's early exit would fail apt-cache under pipefail)
  # (name:arch for another architecture's records; the plain name for
  # Architecture: all, which has no name:arch)
  # (apt-cache show NAME:ARCH prints nothing, successfully, for those)
  record="$(apt-cache show "$name:$arch" "$name" 2> /dev/null || true)"
  grep -qx "Architecture: \($arch\|all\)" <<< "$record" ||
    fail "Depends names $name, which this machine's package index has not for $arch" \
         "($(. /etc/os-release && echo "$VERSION_CODENAME"))"
done
echo "Depends: ${#names[@]} packages, each in this release's index for $arch"

contents="$(dpkg-deb -c "$deb")"
for path in ./usr/bin/fpp-scanner ./etc/fpp-scanner/board.yaml \
            ./lib/systemd/system/fpp-scanner.service ./usr/lib/sysusers.d/fpp-scanner.conf \
            ./lib/udev/rules.d/60-fpp-scanner-gpio.rules \
            ./usr/share/fpp-scanner/boards/rpi5.yaml ./usr/share/fpp-scanner/boards/rock5b.yaml; do
  grep -q " $path$" <<< "$contents" || fail "$path not in the package"
done
sim_boards="./usr/share/fpp-scanner/boards/sim.yaml ./usr/share/fpp-scanner/boards/sim/paper-rig-effects.yaml"
case "$sim" in
  with-sim)
    for path in $sim_boards; do
      grep -q " $path$" <<< "$contents" || fail "$path not in the package"
    done ;;
  without-sim)
    grep -q " ./usr/share/fpp-scanner/boards/sim" <<< "$contents" &&
      fail "sim boards in the package of a binary without the virtual scanner"
    echo "no sim boards (fpp-scanner built without the virtual scanner)" ;;
  *) fail "third argument: with-sim or without-sim, not '$sim'" ;;
esac
grep -q "fpp-calib" <<< "$contents" && fail "the host tool does not belong on the device"
# The page, file for file as in the source tree, where the daemon looks for
# it (<bindir>/../share/fpp-scanner/web).
web="$source_dir/firmware/scanner/web"
[ -f "$web/index.html" ] || fail "no page in $web (index.html)"
pages=0
while IFS= read -r -d '' f; do
  path="./usr/share/fpp-scanner/web/${f#"$web"/}"
  grep -qF " $path" <<< "$contents" || fail "$path not in the package"
  pages=$((pages + 1))
done < <(find "$web" -type f -print0)
echo "page: $pages files in /usr/share/fpp-scanner/web"
grep -q " ./etc/fpp-scanner/token" <<< "$contents" && fail "the token must be made on the board, not shipped"

dpkg-deb -e "$deb" "$work/control"
grep -qx "/etc/fpp-scanner/board.yaml" "$work/control/conffiles" || fail "board.yaml is not a conffile"
grep -v "^[[:space:]]*#" "$work/control/postinst" | grep -q "systemctl enable" &&
  fail "postinst must not enable the service"

# postinst configure makes /etc/fpp-scanner/token once: 64 hex digits,
# root:fpp-scanner 0640; an upgrade keeps it; postrm purge removes it, and
# the state folder (scans, table, settings) that remove keeps.
stubs="$work/stubs"
mkdir -p "$stubs" "$work/pkgroot/etc/fpp-scanner"
for c in systemd-sysusers udevadm systemctl chown; do
  printf '#!/bin/sh\necho "%s $*" >> "%s/calls"\n' "$c" "$work" > "$stubs/$c"
done
printf '#!/bin/sh\n[ "$*" = "group fpp-scanner" ] && echo fpp-scanner:x:999: && exit 0\nexit 2\n' \
  > "$stubs/getent"
chmod +x "$stubs"/*
maint() { PATH="$stubs:$PATH" DPKG_ROOT="$work/pkgroot" sh "$work/control/$1" "${@:2}"; }
token="$work/pkgroot/etc/fpp-scanner/token"
maint postinst configure "" || fail "postinst configure (first install)"
[ -f "$token" ] || fail "postinst made no token"
{ grep -Eqx '[0-9a-f]{64}' "$token" && [ "$(wc -l < "$token")" -eq 1 ]; } ||
  fail "token is not one line of 64 hex digits: $(cat "$token")"
[ "$(stat -c %a "$token")" = 640 ] || fail "token mode $(stat -c %a "$token"), not 640"
grep -qx "chown root:fpp-scanner $token.dpkg-new" "$work/calls" ||
  fail "token not given to group fpp-scanner: $(cat "$work/calls")"
grep -q "^systemctl\|^udevadm" "$work/calls" && fail "postinst with DPKG_ROOT touched this machine"
first="$(cat "$token")"
maint postinst configure 0.0.9 || fail "postinst configure (upgrade)"
[ "$(cat "$token")" = "$first" ] || fail "an upgrade replaced the token"
maint postrm remove || fail "postrm remove"
[ -f "$token" ] || fail "postrm remove took the token (only purge may)"
wants="$work/pkgroot/etc/systemd/system/multi-user.target.wants/fpp-scanner.service"
mkdir -p "$(dirname "$wants")"
ln -s /lib/systemd/system/fpp-scanner.service "$wants"
state="$work/pkgroot/var/lib/fpp-scanner"
mkdir -p "$state/scans/scan-1" && touch "$state/table.fpt" "$state/scans/scan-1/cloud.ply"
maint postrm remove || fail "postrm remove (with a store)"
[ -f "$state/scans/scan-1/cloud.ply" ] || fail "postrm remove took the scans (only purge may)"
maint postrm purge || fail "postrm purge"
[ ! -e "$token" ] || fail "postrm purge left the token"
[ ! -L "$wants" ] || fail "postrm purge left the enabled service's link"
[ ! -e "$state" ] || fail "postrm purge left the state folder: $(find "$state" | head -3)"
echo "postinst: token made once (64 hex digits, root:fpp-scanner 0640), kept on upgrade, purged" \
  "with the service's enablement link and its state folder"

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
  exposure="$(systemd-analyze security --offline=true "$work/fpp-scanner.service" 2> /dev/null |
    sed -n 's/^.*Overall exposure level for [^:]*: \([0-9.]*\).*$/\1/p')"
  echo "systemd-analyze security: exposure ${exposure:-?}"
  [ -z "$exposure" ] || awk -v e="$exposure" 'BEGIN { exit !(e <= 2.0) }' ||
    fail "the service's exposure is $exposure (at most 2.0)"
fi
# The default board's API port is the one TCP port the unit lets it bind;
# UDP is Aravis's (GigE Vision sockets bound to port 0).
port="$(sed -n 's/^  listen: .*:\([0-9]*\)$/\1/p' "$work/root/etc/fpp-scanner/board.yaml")"
[ -n "$port" ] || fail "the default board has no http.listen"
grep -qx "SocketBindAllow=tcp:$port" "$work/fpp-scanner.service" ||
  fail "the unit does not let the service bind the board's port $port"
grep -qx "SocketBindAllow=udp" "$work/fpp-scanner.service" ||
  fail "the unit does not let Aravis bind its UDP sockets"
grep -qx "token_file: /etc/fpp-scanner/token" <<< "$(sed 's/^ *//' "$work/root/etc/fpp-scanner/board.yaml")" ||
  fail "the default board does not read the package's token"
echo "OK"
