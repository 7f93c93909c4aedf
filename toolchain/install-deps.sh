#!/usr/bin/env bash
# Installs every build and test dependency of fpp from Debian 12 packages.
# Non-interactive and idempotent: packages already present are left alone.
set -euo pipefail

packages=(
  # build
  cmake g++ ninja-build pkg-config
  # core and virtual scanner
  libpng-dev libtiff-dev libyaml-cpp-dev
  # host tool
  libopencv-dev libeigen3-dev libcli11-dev
  # device drivers: Aravis 0.8 (its pkg-config file requires libusb-1.0),
  # libdrm (KMS display), libgpiod 1.6 (trigger, button, LED); aravis-tools and
  # gpiod give the fake GigE camera and the command-line GPIO tools
  libaravis-dev aravis-tools libusb-1.0-0-dev libdrm-dev libgpiod-dev gpiod
  # tests and benchmarks (OpenCV's structured_light module is the speed baseline)
  libgtest-dev libgmock-dev libbenchmark-dev libopencv-contrib-dev
  # PLY interoperability tests: the viewers' own readers, headless
  # (MeshLab's meshlabserver needs an X server for its OpenGL context)
  python3-open3d cloudcompare meshlab xvfb xauth
)

as_root() {
  if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi
}

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
as_root apt-get update -q
as_root apt-get install -y -q --no-install-recommends "${missing[@]}"
