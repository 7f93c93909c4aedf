# The compiler cache. Every preset compiles through ccache when it is
# installed (install-deps' tests profile installs it; FPP_CCACHE=OFF goes
# without). The cache is fpp's own folder, FPP_CCACHE_DIR, kept under
# FPP_CCACHE_MAXSIZE by ccache itself; removing the folder clears it.
#
# A clone in another folder reuses this one's objects: paths under the
# source tree are hashed relative to it (base_dir), the build folder's name
# is left out of the hash (hash_dir off: debug info then names the folder of
# the build that filled the entry), and no compile definition holds the
# tree's path except in the few files that need one (rig.cpp,
# network_face.cpp, test_support.cpp). The sloppiness lets objects built
# with GCC's precompiled headers be cached. A corrupt entry is a miss
# (ccache checks each entry's checksum); a cache folder that cannot be
# written is skipped by the launcher, which runs the compiler alone;
# toolchain/run-tests.sh shows hits and misses per build.
option(FPP_CCACHE "Compile through ccache when it is installed" ON)
set(FPP_CCACHE_DIR "$ENV{HOME}/.cache/fpp-ccache" CACHE PATH "fpp's compiler cache (ccache)")
set(FPP_CCACHE_MAXSIZE "6G" CACHE STRING "Size limit of fpp's compiler cache")

if(FPP_CCACHE AND NOT CMAKE_CXX_COMPILER_LAUNCHER AND NOT "$ENV{HOME}" STREQUAL "")
  find_program(FPP_CCACHE_PROGRAM ccache)
  if(FPP_CCACHE_PROGRAM)
    # A launcher script rather than `cmake -E env`: a shell starts in about a
    # millisecond, CMake in tens, for each of a thousand compiles.
    set(launcher ${CMAKE_BINARY_DIR}/ccache-launch)
    file(CONFIGURE OUTPUT ${launcher} @ONLY CONTENT [[
#!/bin/sh
# Written by toolchain/ccache.cmake: the compiler, through fpp's ccache.
export CCACHE_DIR='@FPP_CCACHE_DIR@'
export CCACHE_MAXSIZE='@FPP_CCACHE_MAXSIZE@'
export CCACHE_BASEDIR='@CMAKE_SOURCE_DIR@'
export CCACHE_NOHASHDIR=1
export CCACHE_SLOPPINESS=pch_defines,time_macros,include_file_mtime,include_file_ctime
# A cache that cannot be written (a read-only or foreign folder) makes
# ccache fail the compile: then the compiler alone.
[ -w "$CCACHE_DIR" ] || mkdir -p "$CCACHE_DIR" 2>/dev/null && [ -w "$CCACHE_DIR" ] ||
  exec "$@"
exec '@FPP_CCACHE_PROGRAM@' "$@"
]])
    file(CHMOD ${launcher} PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE GROUP_READ
         GROUP_EXECUTE WORLD_READ WORLD_EXECUTE)
    set(CMAKE_CXX_COMPILER_LAUNCHER ${launcher})
  else()
    message(STATUS "ccache not found: compiling without the cache (install-deps.sh tests)")
  endif()
endif()
