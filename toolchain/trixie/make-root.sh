#!/usr/bin/env bash
# Makes (once) and updates the Debian 13 "trixie" root that the test
# command's trixie phase builds and tests in (toolchain/trixie/run.sh): a
# minimal Debian 13 from debootstrap, then, inside it, this checkout's
# toolchain/install-deps.sh with the profiles the phase needs (main: the
# firmware, the virtual scanner and the host tool; device-tests: GoogleTest
# and what the tests placed 'device' run; cross: the arm64 cross compiler
# and libraries, for Debian 13's arm64 package, preset trixie-aarch64). Run
# at install time, as root (install-deps.sh's trixie profile); the phase
# itself downloads nothing.
# Idempotent: a complete root is only checked (install-deps.sh installs what
# a changed package list adds).
#
# Usage: toolchain/trixie/make-root.sh [--root DIR] [--force]
#   --root DIR  default: $FPP_TRIXIE_ROOT or /var/cache/fpp-trixie/root
#   --force     make the root again from nothing
set -euo pipefail

here="$(cd "$(dirname "$0")" && pwd)"
root="${FPP_TRIXIE_ROOT:-/var/cache/fpp-trixie/root}"
force=0
while [ $# -gt 0 ]; do
  case "$1" in
    --root) root="$2"; shift 2 ;;
    --force) force=1; shift ;;
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
    *) echo "make-root: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
mirror=http://deb.debian.org/debian
stamp="$root/.fpp-debootstrap-complete" # written last: without it the root is remade

if [ "$force" -eq 1 ] || [ ! -f "$stamp" ]; then
  command -v debootstrap > /dev/null ||
    { echo "make-root: debootstrap is missing (apt-get install debootstrap)" >&2; exit 1; }
  echo "make-root: debootstrap trixie into $root"
  rm -rf "$root"
  mkdir -p "$(dirname "$root")"
  log="$(dirname "$root")/debootstrap.log"
  if ! debootstrap --variant=minbase --include=ca-certificates trixie "$root" "$mirror" \
      > "$log" 2>&1; then
    tail -n 20 "$log" >&2
    echo "make-root: debootstrap failed (whole log: $log)" >&2
    exit 1
  fi
  touch "$stamp"
fi
echo "make-root: $root: Debian $(cat "$root/etc/debian_version")"
# The packages, by this checkout's own install script, run inside the root.
"$here/run.sh" --root "$root" --as-root -- ./toolchain/install-deps.sh main device-tests cross
# The downloaded packages are installed: their files (about 480 MB) not kept.
"$here/run.sh" --root "$root" --as-root -- apt-get clean
