#!/usr/bin/env bash
# Fills the libgpiod 2 prefix of the second GPIO backend's cross build
# (preset aarch64-gpiod2, drivers/gpiod/src/gpio_line_v2.cpp): Debian 13
# (trixie)'s arm64 libgpiod-dev and libgpiod3, downloaded as .debs with a
# private apt configuration and unpacked with dpkg-deb -x. This machine's
# apt sources, index and installed libgpiod (1.6, which the normal builds
# use; a multiarch package has one version on every architecture) are left
# alone. libgpiod3 needs glibc 2.33, so the guest's Debian 12 glibc runs it;
# trixie's gpiod tools need 2.38 and are not fetched (the guest keeps
# Debian 12's). Run at install time (install-deps.sh vm); nothing at build
# or test time downloads.
#
# Usage: toolchain/vm/fetch-libgpiod2.sh [--cache DIR] [--force]
#   --cache DIR  the VM cache (default: $FPP_VM_CACHE or /var/cache/fpp-vm);
#                the prefix is DIR/libgpiod2/root (its usr/include/gpiod.h,
#                usr/lib/aarch64-linux-gnu/libgpiod.so.3 and pkgconfig)
#   --force      download again even when the prefix is complete
# FPP_LIBGPIOD2_SUITE=bookworm-backports takes 2.1.3 from there instead.
set -euo pipefail

. "$(dirname "$0")/cache_options.sh"
parse_cache_options fetch-libgpiod2 "$@"
suite="${FPP_LIBGPIOD2_SUITE:-trixie}"
mirror=http://deb.debian.org/debian
keyring=/usr/share/keyrings/debian-archive-keyring.gpg
dir="$cache/libgpiod2"
lib=usr/lib/aarch64-linux-gnu

complete() {
  [ -s "$dir/version" ] && [ -f "$dir/root/usr/include/gpiod.h" ] &&
    [ -e "$dir/root/$lib/libgpiod.so.3" ] && [ -f "$dir/root/$lib/pkgconfig/libgpiod.pc" ]
}
if [ "$force" -eq 0 ] && complete; then
  echo "fetch-libgpiod2: $dir complete (libgpiod $(cat "$dir/version"))"
  exit 0
fi

# The private apt state: its own sources list, index and package cache, arm64
# only, no dpkg status (nothing is installed, apt only downloads).
state=$(mktemp -d "${TMPDIR:-/tmp}/fpp-libgpiod2-apt.XXXXXX")
trap 'rm -rf "$state"' EXIT
mkdir -p "$state/lists/partial" "$state/cache/archives/partial" "$state/debs"
echo "deb [arch=arm64 signed-by=$keyring] $mirror $suite main" > "$state/sources.list"
apt_opts=(-q -o "Dir::Etc::SourceList=$state/sources.list" -o Dir::Etc::SourceParts=/dev/null
  -o "Dir::State::Lists=$state/lists" -o "Dir::Cache=$state/cache" -o Dir::State::status=/dev/null
  -o APT::Architecture=arm64 -o APT::Architectures::=arm64 -o Acquire::Languages=none
  -o Debug::NoLocking=1)
# As root apt downloads as its own user, _apt.
if [ "$(id -u)" -eq 0 ] && id -u _apt > /dev/null 2>&1; then
  chown -R _apt "$state/lists" "$state/cache" "$state/debs"
fi
echo "fetch-libgpiod2: libgpiod-dev and libgpiod3 (arm64) from $mirror $suite"
if ! apt-get "${apt_opts[@]}" update > "$state/apt.log" 2>&1 ||
  ! (cd "$state/debs" && apt-get "${apt_opts[@]}" download libgpiod-dev:arm64 libgpiod3:arm64) \
    >> "$state/apt.log" 2>&1; then
  cat "$state/apt.log" >&2
  echo "fetch-libgpiod2: download failed (is $keyring new enough to carry $suite's key?)" >&2
  exit 1
fi

rm -rf "$dir.new"
mkdir -p "$dir.new/debs" "$dir.new/root"
cp "$state"/debs/*.deb "$dir.new/debs/"
for deb in "$dir.new"/debs/*.deb; do dpkg-deb -x "$deb" "$dir.new/root"; done
version=$(dpkg-deb -f "$dir.new"/debs/libgpiod-dev_*_arm64.deb Version)
echo "$version" > "$dir.new/version"
rm -rf "$dir"
mv "$dir.new" "$dir"
if ! complete; then
  echo "fetch-libgpiod2: the unpacked packages lack gpiod.h, libgpiod.so.3 or libgpiod.pc" >&2
  exit 1
fi
echo "fetch-libgpiod2: $dir ready: libgpiod $version, $(du -sh "$dir" | cut -f1)"
