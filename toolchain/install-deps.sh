#!/usr/bin/env bash
# Installs fpp's dependencies from Debian packages, by profile: each of the
# README's commands installs only what it runs. Debian 12 (bookworm) and 13
# (trixie) are known: where their package names differ, the release's own
# are picked (release_packages below).
#   main   the main job: build the firmware, the virtual scanner and the host
#          tool (preset release: no tests, no benchmarks)
#   tests  main, plus what the tests and benchmarks need (presets ci, dev,
#          asan, fuzz): GoogleTest, Google Benchmark, OpenCV's contrib
#          modules, a browser and WebDriver, the point-cloud viewers,
#          Aravis's fake camera, clang and its libFuzzer, ccache
#   cross  the cross build for the scanner's target, AArch64 (Debian arm64):
#          the cross compiler, qemu-user to run the arm64 tests, and the arm64
#          packages of the firmware (preset aarch64)
#   vm     the virtual ARM board (tests/vm): qemu-system-aarch64 and the
#          guest's Debian packages, fetched into a cache now, Debian 13's
#          arm64 libgpiod 2 for the second GPIO backend's cross build, and
#          the board's Debian disk with systemd, built there now (about 10
#          minutes once)
#   trixie a Debian 13 root in which the test command builds and tests again
#          (toolchain/trixie): debootstrap, then this script inside it with
#          main device-tests
#   device-tests  GoogleTest, ccache and systemd (the package test verifies the
#          unit with its systemd-analyze): what the tests placed 'device'
#          need beyond main (the trixie root's)
#   all    every profile (the default with no argument)
# Non-interactive and idempotent: packages already present are left alone.
# Usage: toolchain/install-deps.sh [PROFILE...]   (--native-only = main tests)
set -euo pipefail

want_main=0 want_tests=0 want_cross=0 want_vm=0 want_trixie=0 want_device_tests=0
usage() { echo "usage: $0 [main|tests|cross|vm|trixie|device-tests|all|--native-only]..." >&2; exit 2; }
[ $# -eq 0 ] && set -- all
for profile in "$@"; do
  case "$profile" in
    main) want_main=1 ;;
    tests) want_main=1 want_tests=1 ;;
    cross) want_cross=1 ;;
    vm) want_vm=1 ;;
    trixie) want_trixie=1 ;;
    device-tests) want_device_tests=1 ;;
    all) want_main=1 want_tests=1 want_cross=1 want_vm=1 want_trixie=1 ;;
    --native-only) want_main=1 want_tests=1 ;;
    *) usage ;;
  esac
done

# Where Debian 12 and 13 name things differently: yaml-cpp's library (0.7,
# 0.8), and clang-format 14, the version that formats this tree (the ci
# preset's FormatCheck; Debian 13 has none, and 19 formats 14 files
# otherwise: there the check is left out, tests/CMakeLists.txt).
codename="$(. /etc/os-release 2> /dev/null && echo "${VERSION_CODENAME:-}")"
case "$codename" in
  bookworm) yaml_cpp_library=libyaml-cpp0.7 format_packages=(clang-format-14) archive_library=libarchive13 ;;
  trixie) yaml_cpp_library=libyaml-cpp0.8 format_packages=() archive_library=libarchive13t64 ;;
  *)
    echo "install-deps: Debian 12 (bookworm) and 13 (trixie) are known, not" \
         "'${codename:-?}': trying Debian 12's package names" >&2
    yaml_cpp_library=libyaml-cpp0.7 format_packages=(clang-format-14) archive_library=libarchive13 ;;
esac

main_packages=(
  # build
  cmake g++ ninja-build pkg-config
  # core and virtual scanner
  libpng-dev libtiff-dev libyaml-cpp-dev
  # host tool
  libopencv-dev libeigen3-dev libcli11-dev
  # device drivers: Aravis 0.8 (its pkg-config file requires libusb-1.0),
  # libdrm (KMS display), libgpiod 1.6 (trigger, button, LED)
  libaravis-dev libusb-1.0-0-dev libdrm-dev libgpiod-dev
  # the scanner's HTTP API and page: libmicrohttpd, nlohmann-json, libarchive
  # (tar downloads), three.js for the page's viewer; libcurl: fpp-calib's
  # client of that API
  libmicrohttpd-dev nlohmann-json3-dev libarchive-dev libjs-three libcurl4-openssl-dev
)
test_packages=(
  # tests and benchmarks (OpenCV's structured_light module is the speed baseline)
  libgtest-dev libgmock-dev libbenchmark-dev libopencv-contrib-dev
  # Aravis's fake GigE camera and the command-line GPIO tools
  aravis-tools gpiod
  # the scanner's page in a real browser, driven through WebDriver
  chromium chromium-driver python3-selenium
  # PLY interoperability tests: the viewers' own readers, headless
  # (MeshLab's meshlabserver needs an X server for its OpenGL context)
  python3-open3d cloudcompare meshlab xvfb xauth
  # the asan and fuzz presets: the release's clang (clang++: 14 on Debian 12,
  # 19 on 13) with libFuzzer and the sanitizers' runtimes (Debian ships them
  # in libclang-rt-dev, not with clang)
  clang libclang-rt-dev
  # the ci preset's FormatCheck (tests/format/check-format.sh)
  "${format_packages[@]}"
  # the compiler cache of every preset (toolchain/ccache.cmake)
  ccache
  # the Python package fpp (calib/python, FPP_BUILD_PYTHON: presets ci and
  # dev) and its tests (tests/python, pytest); Open3D for to_open3d is above
  pybind11-dev python3-dev python3-numpy python3-pytest
  # the README's example script, run by tests/python/test_readme_example.py
  # (matplotlib's headless Agg backend draws its depth map)
  python3-matplotlib
  # packet loss on the GigE link in a test's network namespace
  # (iptables-legacy's statistic match)
  iptables
)

# --- Cross build for AArch64 (toolchain/aarch64-linux-gnu.cmake) -------------
# Only what the firmware needs: the host tool (OpenCV) and the benchmarks are
# not cross-built (OpenCV's arm64 -dev package cannot be co-installed with the
# amd64 one). The arm64 packages are Debian multiarch packages that sit beside
# the amd64 ones in /usr/lib/aarch64-linux-gnu; a Multi-Arch: same package
# must have the same version on both architectures, which apt keeps by
# installing both from the same package index.
cross_arch=arm64
cross_packages=(
  # cross compiler (aarch64-linux-gnu-g++, binutils) and qemu-aarch64-static
  # to run the arm64 test binaries
  g++-aarch64-linux-gnu qemu-user-static
  # core and virtual scanner; yaml-cpp: the library only, see below
  libpng-dev:arm64 libtiff-dev:arm64 "$yaml_cpp_library:arm64"
  # device drivers (as above)
  libaravis-dev:arm64 libusb-1.0-0-dev:arm64 libdrm-dev:arm64 libgpiod-dev:arm64
  # HTTP API (nlohmann-json is headers only, the same for every architecture);
  # libarchive: the library only, see below
  libmicrohttpd-dev:arm64 "$archive_library:arm64"
  # tests (static libraries and CMake package files)
  libgtest-dev:arm64
)
# Two -dev packages cannot be installed for arm64 beside their amd64 twins,
# which the native build needs: libyaml-cpp-dev is not multiarch, and Debian
# 13's libarchive-dev depends on libext2fs-dev, which is not (apt REMOVES
# the amd64 package to install the arm64 one). Their arm64 files (headers,
# .pc, CMake package, static library) are unpacked instead into this
# folder, which the toolchain file reads; the arm64 libraries themselves
# are installed as packages (above).
cross_extra_prefix=/opt/fpp-cross/aarch64-linux-gnu

as_root() {
  if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi
}

# Prints, one a line, the given packages that are not installed. A name
# without an architecture means this machine's (or "all"): a multiarch
# package installed for arm64 alone (the cross build's) does not count.
not_installed() {
  local p status native
  native="$(dpkg --print-architecture)"
  for p in "$@"; do
    status="$(dpkg-query -W -f='${Status} ${Architecture}\n' "$p" 2>/dev/null || true)"
    if [[ "$p" == *:* ]]; then
      [[ "$status" == *"install ok installed"* ]] || echo "$p"
    else
      grep -Eq "^install ok installed ($native|all)\$" <<< "$status" || echo "$p"
    fi
  done
}

export DEBIAN_FRONTEND=noninteractive
updated=0
# apt-get update once, and only when something is to be installed.
apt_install() {
  if [ "$updated" -eq 0 ]; then as_root apt-get update -q; updated=1; fi
  as_root apt-get install -y -q --no-install-recommends "$@"
}

# Installs those of the packages (after the description) that are missing.
ensure_installed() {
  local what="$1" missing
  shift
  mapfile -t missing < <(not_installed "$@")
  if [ ${#missing[@]} -eq 0 ]; then
    echo "install-deps: all $# $what present"
  else
    echo "install-deps: installing ${missing[*]}"
    apt_install "${missing[@]}"
  fi
}

# The arm64 architecture, for the cross build's packages and the VM's guest
# packages (after the native ones: an arm64 package and its amd64 twin then
# come from the same index).
arch_added=0
add_cross_architecture() {
  if ! dpkg --print-foreign-architectures | grep -qx "$cross_arch"; then
    echo "install-deps: adding the $cross_arch architecture"
    as_root dpkg --add-architecture "$cross_arch"
    updated=0 # the index must now be read for arm64 too
    arch_added=1
  fi
}

# unpack_cross_dev DEV LIBRARY SONAME: DEV's arm64 package unpacked into
# cross_extra_prefix (see there), the version of the installed arm64
# LIBRARY package; redone when that changes. Its library links point at the
# system's arm64 SONAME, and its .pc file at the folder it is unpacked in.
unpack_cross_dev() {
  local dev=$1 library=$2 soname=$3 version stamp download libdir shared
  version="$(dpkg-query -W -f='${Version}' "$library:$cross_arch")"
  stamp="$cross_extra_prefix/$dev.version"
  if [ "$(cat "$stamp" 2>/dev/null)" = "$version" ]; then
    echo "install-deps: $dev:$cross_arch $version unpacked in $cross_extra_prefix"
    return
  fi
  echo "install-deps: unpacking $dev:$cross_arch $version into $cross_extra_prefix"
  [ "$updated" -eq 1 ] || { as_root apt-get update -q; updated=1; }
  download="$(mktemp -d)"
  chmod 755 "$download"
  # apt downloads as its own user _apt when run as root
  if [ "$(id -u)" -eq 0 ] && id -u _apt > /dev/null 2>&1; then chown _apt "$download"; fi
  (cd "$download" && apt-get download -q "$dev:$cross_arch=$version")
  as_root mkdir -p "$cross_extra_prefix"
  as_root dpkg-deb -x "$download/${dev}_"*"_$cross_arch.deb" "$cross_extra_prefix"
  rm -rf "$download"
  libdir="$cross_extra_prefix/usr/lib/aarch64-linux-gnu"
  shared="$(readlink -f "/usr/lib/aarch64-linux-gnu/$soname")"
  as_root ln -sf "$shared" "$libdir/$(basename "$shared")"
  [ "$(basename "$shared")" = "$soname" ] || as_root ln -sf "$(basename "$shared")" "$libdir/$soname"
  as_root find "$libdir/pkgconfig" -name '*.pc' -exec sed -i "s|^prefix=/usr\$|prefix=$cross_extra_prefix/usr|" {} +
  echo "$version" | as_root tee "$stamp" > /dev/null
}

install_cross() {
  add_cross_architecture
  ensure_installed "$cross_arch cross-build packages" "${cross_packages[@]}"

  unpack_cross_dev libyaml-cpp-dev "$yaml_cpp_library" "libyaml-cpp.so.${yaml_cpp_library#libyaml-cpp}"
  unpack_cross_dev libarchive-dev "$archive_library" libarchive.so.13
  ensure_qemu_binfmt
}

# The arm64 programs that tests start themselves (fpp-scanner through
# /bin/sh, fork/exec) and the board disk's debootstrap (make-rootfs.sh) run
# on this machine only if the kernel hands arm64 ELF files to qemu: register
# qemu-user-static's binfmt_misc entry, as systemd-binfmt does at boot on a
# Debian system (not inside a container). Its "F" flag opens qemu now, so
# that it also works in other mount namespaces and chroots.
ensure_qemu_binfmt() {
  binfmt=/proc/sys/fs/binfmt_misc
  register_qemu_binfmt() {
    mountpoint -q "$binfmt" || as_root mount -t binfmt_misc binfmt_misc "$binfmt" || return 1
    if [ -e "$binfmt/qemu-aarch64" ]; then # registered but disabled
      echo 1 | as_root tee "$binfmt/qemu-aarch64" > /dev/null
    else
      as_root tee "$binfmt/register" < /usr/lib/binfmt.d/qemu-aarch64.conf > /dev/null
    fi
  }
  if [ "$(head -n 1 "$binfmt/qemu-aarch64" 2>/dev/null)" = enabled ]; then
    echo "install-deps: qemu-aarch64 registered with binfmt_misc"
  elif register_qemu_binfmt; then
    echo "install-deps: registered qemu-aarch64 with binfmt_misc"
  else
    echo "install-deps: warning: cannot register qemu-aarch64 with binfmt_misc: the aarch64" \
         "tests that start programs (fpp-scanner) and the board's disk (make-rootfs.sh) will fail" >&2
  fi
}

# --- The virtual ARM board (toolchain/vm, tests/vm) --------------------------
# qemu-system-aarch64 and cpio from packages; the arm64 kernel, busybox and
# the guest's tools are downloaded as Debian packages into a cache now, by
# toolchain/vm/fetch-deps.sh (idempotent), so that no test downloads. Then
# the board's Debian 13 disk with systemd (toolchain/vm/make-rootfs.sh:
# debootstrap, its arm64 second stage through qemu-user; e2fsprogs' mkfs.ext4
# -d makes the image), cached beside it and rebuilt only when its scripts or
# the package's Depends change.
install_vm() {
  add_cross_architecture
  ensure_installed "virtual ARM board packages" qemu-system-arm qemu-user-static cpio debootstrap \
    e2fsprogs
  ensure_qemu_binfmt
  # fetch-deps.sh reads the arm64 package index
  if [ "$arch_added" -eq 1 ] && [ "$updated" -eq 0 ]; then as_root apt-get update -q; updated=1; fi
  as_root "$(dirname "$0")/vm/fetch-deps.sh"
  # libgpiod 2 unpacked beside the cache (preset aarch64-gpiod2): this
  # machine keeps Debian 12's libgpiod 1.6 for every other build.
  as_root "$(dirname "$0")/vm/fetch-libgpiod2.sh"
  as_root "$(dirname "$0")/vm/make-rootfs.sh"
}

[ "$want_main" -eq 1 ] && ensure_installed "main-job packages" "${main_packages[@]}"
[ "$want_tests" -eq 1 ] && ensure_installed "test packages" "${test_packages[@]}"
[ "$want_cross" -eq 1 ] && install_cross
[ "$want_vm" -eq 1 ] && install_vm
[ "$want_device_tests" -eq 1 ] && ensure_installed "device-test packages" libgtest-dev libgmock-dev ccache systemd
if [ "$want_trixie" -eq 1 ]; then
  ensure_installed "Debian 13 root packages" debootstrap
  as_root "$(dirname "$0")/trixie/make-root.sh"
fi
exit 0
