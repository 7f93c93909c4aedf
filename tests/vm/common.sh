# shellcheck shell=bash disable=SC2154
# Sourced by the tests/vm scripts after they set `test_name`: how they fail
# and skip, and the checks every one of them makes before booting the VM.
# Exit status: 0 passed, 1 failed, 77 skipped; in CI (CI=true) everything the
# VM needs is installed, so a skip is a failure there.
cache="${FPP_VM_CACHE:-/var/cache/fpp-vm}"
fail() { echo "$test_name: FAILED: $*"; exit 1; }
skip() {
  [ "${CI:-}" != true ] || fail "(CI) $*"
  echo "$test_name: SKIPPED: $*"; exit 77
}
# QEMU and the arm64 kernel cache (toolchain/vm/fetch-deps.sh).
require_vm() {
  command -v qemu-system-aarch64 > /dev/null ||
    skip "qemu-system-aarch64 not installed (apt-get install qemu-system-arm)"
  [ -s "$cache/kernel-release" ] ||
    skip "no arm64 kernel in $cache (toolchain/vm/fetch-deps.sh fills it at install time)"
}
# The cross-built scanner of the AArch64 build folder $1.
require_arm64_scanner() {
  local scanner="$1/firmware/scanner/fpp-scanner"
  [ -x "$scanner" ] || skip "no cross-built $scanner (cmake --workflow --preset aarch64)"
  readelf -h "$scanner" | grep -q 'Machine:.*AArch64' || skip "$scanner is not an AArch64 build"
}
# The name, in build folder $1, of the scanner that runs sim boards:
# fpp-scanner, or fpp-scanner-sim where fpp-scanner is the device binary
# built without the virtual scanner (FPP_SCANNER_SIM OFF, preset aarch64;
# toolchain/vm/run-vm.sh --build puts both in the guest's /fpp/bin).
sim_scanner_name() {
  if [ -x "$1/firmware/scanner/fpp-scanner-sim" ]; then echo fpp-scanner-sim; else echo fpp-scanner; fi
}
# With FPP_VM_EXPECT_LIBGPIOD set (e.g. libgpiod.so.3: the aarch64-gpiod2
# build, tests/CMakeLists.txt), the scanner of build folder $1 must link that
# libgpiod: a build of the other backend would pass the same tests unseen.
require_libgpiod() {
  [ -n "${FPP_VM_EXPECT_LIBGPIOD:-}" ] || return 0
  local scanner="$1/firmware/scanner/fpp-scanner" linked
  linked=$(readelf -d "$scanner" | sed -n 's/.*(NEEDED).*\[\(libgpiod\.so\.[0-9]*\)\]/\1/p')
  [ "$linked" = "$FPP_VM_EXPECT_LIBGPIOD" ] ||
    fail "$scanner links '${linked:-no libgpiod}', not $FPP_VM_EXPECT_LIBGPIOD"
  echo "$test_name: $scanner links $linked"
}
