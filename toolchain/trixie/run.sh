#!/usr/bin/env bash
# Runs a command in the Debian 13 root (toolchain/trixie/make-root.sh), in
# this checkout: the checkout is /src/fpp there and the shared datasets
# beside it (../shared, when present) /src/shared, fpp's compiler cache for
# Debian 13's compilers ~/.cache/fpp-ccache-trixie is the command's
# ~/.cache/fpp-ccache there, and /proc, /dev/shm and /dev/pts are mounted; all
# in a private mount namespace, so nothing stays mounted after it, whatever
# happens. Needs root (as install-deps.sh: directly, or through sudo); the
# command runs as the calling user (root, or sudo's SUDO_UID), so that the
# build folder stays theirs.
#
# Usage: toolchain/trixie/run.sh [--root DIR] [--as-root] -- COMMAND...
#   e.g. toolchain/trixie/run.sh -- cmake --workflow --preset trixie
set -euo pipefail

source_dir="$(cd "$(dirname "$0")/../.." && pwd)"
root="${FPP_TRIXIE_ROOT:-/var/cache/fpp-trixie/root}"
as_root=0
while [ $# -gt 0 ]; do
  case "$1" in
    --root) root="$2"; shift 2 ;;
    --as-root) as_root=1; shift ;;
    --) shift; break ;;
    *) echo "trixie/run: unknown argument '$1' (the command goes after --)" >&2; exit 2 ;;
  esac
done
[ $# -gt 0 ] || { echo "trixie/run: no command (after --)" >&2; exit 2; }
if [ ! -f "$root/.fpp-debootstrap-complete" ]; then
  echo "trixie/run: no Debian 13 root at $root (toolchain/install-deps.sh trixie makes it)" >&2
  exit 77
fi
if [ "$(id -u)" -ne 0 ]; then
  again=(--root "$root")
  [ "$as_root" -eq 0 ] || again+=(--as-root)
  exec sudo --preserve-env=FPP_TRIXIE_ROOT,CI "$0" "${again[@]}" -- "$@"
fi

user_id="${SUDO_UID:-0}" group_id="${SUDO_GID:-0}"
[ "$as_root" -eq 1 ] && user_id=0 group_id=0
home=/root
cache_home="${SUDO_USER:+$(getent passwd "$SUDO_USER" | cut -d: -f6)}"
cache="${cache_home:-${HOME:-/root}}/.cache/fpp-ccache-trixie"
mkdir -p "$cache"
[ "$user_id" -ne 0 ] && { home=/tmp/fpp-home; chown "$user_id:$group_id" "$cache"; }
shared="$(dirname "$source_dir")/shared"

# The mounts, then the command, inside a new mount namespace (unshare -m):
# they vanish with it. Arguments are passed through the environment, quoted.
# shellcheck disable=SC2016 # expanded by the inner shell
inner='
set -euo pipefail
mount --make-rprivate /
mkdir -p "$ROOT/src/fpp" "$ROOT/src/shared" "$ROOT$HOME_DIR/.cache/fpp-ccache"
mount --bind "$SOURCE" "$ROOT/src/fpp"
[ -d "$SHARED" ] && mount --bind -o ro "$SHARED" "$ROOT/src/shared"
mount --bind "$CACHE" "$ROOT$HOME_DIR/.cache/fpp-ccache"
[ "$USER_ID" -eq 0 ] || chown "$USER_ID:$GROUP_ID" "$ROOT$HOME_DIR" "$ROOT$HOME_DIR/.cache"
mount -t proc proc "$ROOT/proc"
mount -t tmpfs -o mode=1777 shm "$ROOT/dev/shm"
mkdir -p "$ROOT/dev/pts" && mount -t devpts -o newinstance,ptmxmode=0666 devpts "$ROOT/dev/pts"
cp /etc/resolv.conf "$ROOT/etc/resolv.conf" 2> /dev/null || true
exec chroot --userspec="$USER_ID:$GROUP_ID" "$ROOT" /usr/bin/env -i \
  PATH=/usr/local/bin:/usr/bin:/bin:/usr/sbin:/sbin HOME="$HOME_DIR" LANG=C.UTF-8 \
  CI="${CI:-}" DEBIAN_FRONTEND=noninteractive \
  /bin/bash -c "cd /src/fpp && exec \"\$@\"" fpp-trixie "$@"
'
ROOT="$root" SOURCE="$source_dir" SHARED="$shared" CACHE="$cache" USER_ID="$user_id" \
  GROUP_ID="$group_id" HOME_DIR="$home" \
  unshare -m /bin/bash -c "$inner" fpp-trixie-mounts "$@"
