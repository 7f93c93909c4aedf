#!/usr/bin/env bash
# Fills the virtual ARM board's cache: Debian 12's arm64 kernel (vmlinuz and
# its modules), a static arm64 busybox, the arm64 libgpiod command-line tools
# and Aravis's arm64 fake GigE camera (aravis-tools), downloaded with apt-get download and unpacked with dpkg-deb -x.
# Nothing is installed. Run at install time (it needs the package index and
# the arm64 architecture: dpkg --add-architecture arm64 && apt-get update);
# the harness itself (run-vm.sh) never downloads.
#
# Usage: toolchain/vm/fetch-deps.sh [--cache DIR] [--force]
#   --cache DIR  default: $FPP_VM_CACHE or /var/cache/fpp-vm
#   --force      download again even when the cache is complete
# Cache layout: DIR/debs/*.deb (the packages), DIR/root/ (their files),
# DIR/kernel-release (e.g. 6.1.0-56-arm64), written last: with it and every
# file the harness takes from the cache present, the cache is complete.
# The kernel package is the one linux-image-arm64 currently depends on;
# FPP_VM_KERNEL_PACKAGE=linux-image-6.1.0-NN-arm64 picks another.
set -euo pipefail

. "$(dirname "$0")/cache_options.sh"
parse_cache_options fetch-deps "$@"

# What the harness takes from the cache besides the kernel release's files.
cached_files=(bin/busybox usr/bin/gpiodetect usr/bin/arv-fake-gv-camera-0.8)
complete() {
  [ -s "$cache/kernel-release" ] || return 1
  local release f
  release=$(cat "$cache/kernel-release")
  [ -f "$cache/root/boot/vmlinuz-$release" ] && [ -d "$cache/root/lib/modules/$release" ] || return 1
  for f in "${cached_files[@]}"; do [ -e "$cache/root/$f" ] || return 1; done
}
if [ "$force" -eq 0 ] && complete; then
  echo "fetch-deps: cache $cache complete (kernel $(cat "$cache/kernel-release"))"
  exit 0
fi

if ! dpkg --print-foreign-architectures | grep -qx arm64; then
  echo "fetch-deps: the arm64 architecture is not enabled:" >&2
  echo "  dpkg --add-architecture arm64 && apt-get update" >&2
  exit 1
fi

kernel_package="${FPP_VM_KERNEL_PACKAGE:-}"
if [ -z "$kernel_package" ]; then
  # The versioned image package that the metapackage's candidate depends on.
  candidate=$(apt-cache policy linux-image-arm64:arm64 | awk '/Candidate:/ {print $2}')
  if [ -z "$candidate" ] || [ "$candidate" = "(none)" ]; then
    echo "fetch-deps: linux-image-arm64:arm64 is not in the package index (apt-get update?)" >&2
    exit 1
  fi
  kernel_package=$(apt-cache show "linux-image-arm64:arm64=$candidate" |
    sed -n 's/^Depends: //p' | head -n 1 | grep -o 'linux-image-[0-9.]*-[0-9]*-arm64' | head -n 1)
  if [ -z "$kernel_package" ]; then
    echo "fetch-deps: cannot tell which kernel linux-image-arm64 $candidate depends on" >&2
    exit 1
  fi
fi

packages=("$kernel_package:arm64" busybox-static:arm64 gpiod:arm64 aravis-tools:arm64)
echo "fetch-deps: downloading ${packages[*]} into $cache/debs"
rm -rf "$cache/debs.new" "$cache/root.new" "$cache/kernel-release"
mkdir -p "$cache/debs.new" "$cache/root.new"
# apt-get download writes into the current folder (as root it warns that the
# _apt user cannot write there, which is harmless).
if ! (cd "$cache/debs.new" && apt-get download -q "${packages[@]}") > "$cache/download.log" 2>&1; then
  cat "$cache/download.log" >&2
  echo "fetch-deps: apt-get download failed" >&2
  exit 1
fi
rm -f "$cache/download.log"
for p in "${packages[@]}"; do
  name=${p%%:*}
  if ! compgen -G "$cache/debs.new/${name}_*_arm64.deb" > /dev/null; then
    echo "fetch-deps: download of $p failed" >&2
    exit 1
  fi
done
for deb in "$cache"/debs.new/*.deb; do
  dpkg-deb -x "$deb" "$cache/root.new"
done

release=$(find "$cache/root.new/lib/modules" -mindepth 1 -maxdepth 1 -name '*-arm64' -printf '%f\n' | head -n 1)
rm -rf "$cache/debs" "$cache/root"
mv "$cache/debs.new" "$cache/debs"
mv "$cache/root.new" "$cache/root"
echo "$release" > "$cache/kernel-release"
if ! complete; then
  rm -f "$cache/kernel-release"
  echo "fetch-deps: the unpacked packages lack vmlinuz-$release, its modules or one of" \
    "${cached_files[*]}" >&2
  exit 1
fi
echo "fetch-deps: cache $cache ready: kernel $release, $(du -sh "$cache" | cut -f1)"
