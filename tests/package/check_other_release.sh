#!/usr/bin/env bash
# A package built for the other Debian release (12 <-> 13: their library
# names differ) is refused by apt on this one, for a library it cannot find,
# with apt's reason, and nothing is installed: the scanner's package built
# from BUILD_DIR with the other release's dependency list
# (board/CMakeLists.txt), then `apt-get install --simulate ./PACKAGE.deb`,
# which resolves the dependencies exactly as the real install does.
# Usage: check_other_release.sh BUILD_DIR OTHER_RELEASE "OTHER_DEPENDS" MISSING
#   MISSING: a package of the other release's list that this one has not
set -euo pipefail
build="$1" other="$2" depends="$3" missing="$4"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

# The build's CPack configuration with the other list set after it (cpack's
# -D comes before the configuration file on newer CMake, which then wins).
cat > "$work/other-release.cmake" << CONFIG
include("$(cd "$build" && pwd)/CPackConfig.cmake")
set(CPACK_DEBIAN_PACKAGE_DEPENDS "$depends")
CONFIG
cpack --config "$work/other-release.cmake" -B "$work/out" > "$work/cpack.log" 2>&1 ||
  { cat "$work/cpack.log" >&2; fail "cpack"; }
deb="$(ls "$work"/out/*.deb)"
info="$(dpkg-deb -I "$deb")" # whole, then searched: grep -q's early exit fails a pipe
grep -q "Depends: .*$missing" <<< "$info" || fail "the package does not name $missing"
before="$(dpkg-query -W -f='${Status}' fpp-scanner 2> /dev/null || echo "not installed")"
status=0
apt-get install --simulate -q --no-install-recommends "$deb" > "$work/apt.log" 2>&1 || status=$?
cat "$work/apt.log"
[ "$status" -ne 0 ] || fail "apt accepted a package built for $other"
grep -q "unmet dependencies" "$work/apt.log" || fail "apt refused it, but not for its dependencies"
grep -q "Depends: $missing" "$work/apt.log" || fail "apt's reason does not name $missing"
after="$(dpkg-query -W -f='${Status}' fpp-scanner 2> /dev/null || echo "not installed")"
[ "$before" = "$after" ] || fail "fpp-scanner's state changed: $before -> $after"
echo "refused on $(. /etc/os-release && echo "$VERSION_CODENAME"): a package for $other, for $missing"
