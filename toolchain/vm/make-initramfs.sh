#!/usr/bin/env bash
# Builds the virtual ARM board's initramfs (an uncompressed newc cpio: TCG
# would spend longer decompressing it than QEMU spends loading it):
#   /init                guest-init.sh
#   /bin/busybox         static arm64 busybox from the cache (fetch-deps.sh)
#   /usr/bin/gpio*       libgpiod's arm64 tools, when their libraries resolve
#   /lib/modules/        the kernel modules for virtio PCI, virtio-gpu DRM and
#                        9p, with load-order (dependencies first, read from
#                        each module's .modinfo "depends=")
#   /fpp/bin/            the given arm64 executables, and fpp-vm-until
#                        (guest-until.sh)
#   /lib, /usr/lib/aarch64-linux-gnu  their shared libraries (DT_NEEDED walked
#                        recursively: ldd does not work across architectures)
#                        and the dynamic loader
#   /fpp/files/          the extra files (board file, rig, scene, table)
#   /fpp/cmd, /fpp/collect  the guest command and the paths to bring back
#   /fpp/net             with --net: the virtio-net driver is loaded and
#                        guest-init.sh gives eth0 QEMU's user-network address
#   any folder           --tree HOSTDIR=GUESTDIR (e.g. three.js, a web page)
# With --init FILE, FILE is /init instead of guest-init.sh (make-rootfs.sh:
# boot-init.sh, which mounts the Debian disk and hands over to systemd).
#
# Usage: make-initramfs.sh --out FILE [--cache DIR] [--bin ELF]... [--files DIR]
#          [--cmd-file FILE] [--collect-file FILE] [--module NAME]...
#          [--lib-dir DIR]... [--net] [--tree HOSTDIR=GUESTDIR]... [--init FILE]
#   --lib-dir DIR  searched for libraries before the arm64 multiarch folders
#   --net          a network card (virtio-net-pci on QEMU's user network)
#   --tree H=G     host folder H copied to guest folder G (links dereferenced)
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
cache="${FPP_VM_CACHE:-/var/cache/fpp-vm}"
out=""
files=""
cmd_file=""
collect_file=""
init="$here/guest-init.sh"
bins=()
lib_dirs=()
trees=()
net=0
# virtio_pci: the PCI transport (virtio-gpu-pci, virtio-9p-pci);
# virtio-gpu: /dev/dri/card0; 9pnet_virtio and 9p: the /out share.
modules=(virtio_pci virtio-gpu 9pnet_virtio 9p)

while [ $# -gt 0 ]; do
  case "$1" in
    --out) out="$2"; shift 2 ;;
    --cache) cache="$2"; shift 2 ;;
    --bin) bins+=("$2"); shift 2 ;;
    --files) files="$2"; shift 2 ;;
    --cmd-file) cmd_file="$2"; shift 2 ;;
    --collect-file) collect_file="$2"; shift 2 ;;
    --module) modules+=("$2"); shift 2 ;;
    --lib-dir) lib_dirs+=("$2"); shift 2 ;;
    --net) net=1; shift ;;
    --init) init="$2"; shift 2 ;;
    --tree)
      case "$2" in
        /*=/*) trees+=("$2") ;;
        *) echo "make-initramfs: --tree takes HOSTDIR=GUESTDIR, both absolute: '$2'" >&2; exit 2 ;;
      esac
      shift 2 ;;
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
    *) echo "make-initramfs: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
[ -n "$out" ] || { echo "make-initramfs: --out FILE is required" >&2; exit 2; }
if [ ! -s "$cache/kernel-release" ]; then
  echo "make-initramfs: cache $cache is not filled (run toolchain/vm/fetch-deps.sh)" >&2
  exit 1
fi
release=$(cat "$cache/kernel-release")
root="$cache/root"
module_tree="$root/lib/modules/$release/kernel"
lib_dirs+=(/lib/aarch64-linux-gnu /usr/lib/aarch64-linux-gnu)
# virtio_net: eth0 (its dependencies net_failover and failover follow).
[ "$net" -eq 0 ] || modules+=(virtio_net)

stage=$(mktemp -d "${TMPDIR:-/tmp}/fpp-vm-initramfs.XXXXXX")
trap 'rm -rf "$stage"' EXIT
mkdir -p "$stage"/{bin,dev,proc,sys,tmp,out,etc,usr/bin,lib/modules,fpp/bin,fpp/files}
chmod 1777 "$stage/tmp"

install -m 0755 "$init" "$stage/init"
install -m 0755 "$root/bin/busybox" "$stage/bin/busybox"
install -m 0755 "$here/guest-until.sh" "$stage/fpp/bin/fpp-vm-until"

# --- Kernel modules, dependencies first -------------------------------------
declare -A module_seen=()
load_order=()
module_file() {
  # Module names use _ and - interchangeably.
  local a=${1//-/_} b=${1//_/-}
  find "$module_tree" \( -name "$a.ko" -o -name "$b.ko" -o -name "$a.ko.xz" -o -name "$b.ko.xz" \) \
    -print -quit
}
add_module() {
  local file deps dep
  file=$(module_file "$1")
  if [ -z "$file" ]; then
    echo "make-initramfs: module $1 not found under $module_tree" >&2
    return 1
  fi
  [ -z "${module_seen[$file]:-}" ] || return 0
  module_seen[$file]=1
  local plain
  plain="$stage/lib/modules/$(basename "${file%.xz}")"
  # busybox insmod takes plain .ko files only.
  case "$file" in
    *.xz) xz -dc "$file" > "$plain" ;;
    *) cp "$file" "$plain" ;;
  esac
  deps=$(readelf -p .modinfo "$plain" | sed -n 's/.*depends=//p' | tr ',' ' ')
  for dep in $deps; do add_module "$dep"; done
  load_order+=("$(basename "$plain")")
}
for m in "${modules[@]}"; do add_module "$m"; done
printf '%s\n' "${load_order[@]}" > "$stage/lib/modules/load-order"

# --- Executables and their shared libraries ---------------------------------
declare -A lib_seen=()
missing_libs=()
find_lib() {
  local d
  for d in "$@"; do
    if [ -e "$d/$lib" ]; then echo "$d/$lib"; return 0; fi
  done
  return 1
}
# Copies the libraries that ELF file $1 needs (recursively), each to the
# multiarch folder it came from (dereferenced: the initramfs holds no links).
add_needed() {
  local elf=$1 lib path runpath dirs=()
  runpath=$(readelf -d "$elf" | sed -n 's/.*(\(RUNPATH\|RPATH\)).*\[\(.*\)\]/\2/p' | tr ':' ' ')
  # $ORIGIN in a build tree's RUNPATH is the executable's own folder.
  for path in $runpath; do dirs+=("${path//\$ORIGIN/$(dirname "$elf")}"); done
  dirs+=("${lib_dirs[@]}")
  for lib in $(readelf -d "$elf" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p'); do
    [ -z "${lib_seen[$lib]:-}" ] || continue
    lib_seen[$lib]=1
    if ! path=$(find_lib "${dirs[@]}"); then
      missing_libs+=("$lib (needed by $(basename "$elf"))")
      continue
    fi
    local dest=/usr/lib/aarch64-linux-gnu
    case "$path" in /lib/aarch64-linux-gnu/*) dest=/lib/aarch64-linux-gnu ;; esac
    mkdir -p "$stage$dest"
    cp -L "$path" "$stage$dest/$lib"
    add_needed "$path"
  done
}
add_executable() {
  local elf=$1 dest=$2 interp
  if ! readelf -h "$elf" 2> /dev/null | grep -q 'Machine:.*AArch64'; then
    echo "make-initramfs: $elf is not an AArch64 executable" >&2
    return 1
  fi
  cp -L "$elf" "$dest"
  chmod 0755 "$dest"
  interp=$(readelf -l "$elf" | sed -n 's/.*Requesting program interpreter: \(.*\)\]/\1/p')
  if [ -n "$interp" ] && [ ! -e "$stage$interp" ]; then
    mkdir -p "$stage$(dirname "$interp")"
    cp -L "$interp" "$stage$interp"
  fi
  add_needed "$elf"
}
for b in "${bins[@]}"; do add_executable "$b" "$stage/fpp/bin/$(basename "$b")"; done
if [ ${#missing_libs[@]} -gt 0 ]; then
  echo "make-initramfs: libraries not found (arm64 packages missing?):" >&2
  printf '  %s\n' "${missing_libs[@]}" >&2
  exit 1
fi
# libgpiod's tools print the guest's GPIO chips; optional, so only when
# every library they need is there.
for tool in gpiodetect gpioinfo gpioget gpioset gpiomon; do
  [ -x "$root/usr/bin/$tool" ] || continue
  add_executable "$root/usr/bin/$tool" "$stage/usr/bin/$tool"
done
if [ ${#missing_libs[@]} -gt 0 ]; then
  echo "make-initramfs: libgpiod tools left out: ${missing_libs[*]}" >&2
  rm -f "$stage"/usr/bin/gpio*
fi

# --- Files, command, minimal /etc --------------------------------------------
if [ -n "$files" ]; then cp -rL "$files/." "$stage/fpp/files/"; fi
for t in "${trees[@]}"; do
  host_dir=${t%%=*} guest_dir=${t#*=}
  [ -d "$host_dir" ] || { echo "make-initramfs: no folder $host_dir (--tree)" >&2; exit 1; }
  mkdir -p "$stage$guest_dir"
  cp -rL "$host_dir/." "$stage$guest_dir/"
done
[ "$net" -eq 0 ] || : > "$stage/fpp/net"
if [ -n "$cmd_file" ]; then cp "$cmd_file" "$stage/fpp/cmd"; else echo "true" > "$stage/fpp/cmd"; fi
if [ -n "$collect_file" ]; then cp "$collect_file" "$stage/fpp/collect"; else : > "$stage/fpp/collect"; fi
echo "root:x:0:0:root:/tmp:/bin/sh" > "$stage/etc/passwd"
echo "root:x:0:" > "$stage/etc/group"
printf '127.0.0.1 localhost\n::1 localhost\n' > "$stage/etc/hosts"
printf 'passwd: files\ngroup: files\nhosts: files\n' > "$stage/etc/nsswitch.conf"

mkdir -p "$(dirname "$out")"
(cd "$stage" && find . -print0 | LC_ALL=C sort -z | cpio --null -o -H newc -R 0:0 --quiet) > "$out.tmp"
mv "$out.tmp" "$out"
echo "make-initramfs: $out: $(du -h "$out" | cut -f1), kernel $release, modules ${load_order[*]}"
