# Cross build for the scanner's target: AArch64, Debian 12 arm64 (preset
# aarch64; toolchain/install-deps.sh installs what it needs).
#
# Debian multiarch: the arm64 packages are installed beside the amd64 ones in
# the build machine's own root, so the target "sysroot" is / and what keeps
# the two apart is the multiarch folder: arm64 libraries, .pc and CMake
# package files live in /usr/lib/aarch64-linux-gnu (amd64's in
# /usr/lib/x86_64-linux-gnu), arch-specific headers in
# /usr/include/aarch64-linux-gnu; /usr/include and /usr/share are common.
# Debian's cross compiler searches exactly those folders.
#
# The test binaries run under qemu-user (CMAKE_CROSSCOMPILING_EMULATOR), which
# gtest_discover_tests and ctest use.

set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)

set(FPP_CROSS_TRIPLET aarch64-linux-gnu)
set(CMAKE_C_COMPILER ${FPP_CROSS_TRIPLET}-gcc)
set(CMAKE_CXX_COMPILER ${FPP_CROSS_TRIPLET}-g++)

# find_library and find_package search /usr/lib/aarch64-linux-gnu.
set(CMAKE_LIBRARY_ARCHITECTURE ${FPP_CROSS_TRIPLET})
# Never the build machine's own (amd64) libraries and headers, nor the amd64
# CMake package files of the packages used here (find_package's config mode
# ignores a listed folder itself, not its subfolders).
set(CMAKE_IGNORE_PATH
  /usr/lib/x86_64-linux-gnu /lib/x86_64-linux-gnu /usr/include/x86_64-linux-gnu
  /usr/lib/x86_64-linux-gnu/cmake/GTest /usr/lib/x86_64-linux-gnu/cmake/yaml-cpp)
# No re-rooting (the target's root is /): programs (pkg-config, qemu) are the
# build machine's, libraries and packages are told apart by the folder above.
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)

# yaml-cpp and libarchive: their arm64 -dev packages cannot sit beside the
# amd64 ones (libyaml-cpp-dev is not multiarch; Debian 13's libarchive-dev
# depends on libext2fs-dev, which is not), so install-deps.sh unpacks them
# here instead, their .pc files pointing here.
set(FPP_CROSS_EXTRA_PREFIX /opt/fpp-cross/${FPP_CROSS_TRIPLET}/usr)

# pkg-config reads only the arm64 .pc files (those unpacked above first) and
# the architecture-independent ones (never /usr/lib/x86_64-linux-gnu/pkgconfig
# nor a user's PKG_CONFIG_PATH). Set here, the toolchain file being read
# again whenever CMake re-runs.
set(ENV{PKG_CONFIG_LIBDIR} "${FPP_CROSS_EXTRA_PREFIX}/lib/${FPP_CROSS_TRIPLET}/pkgconfig:/usr/lib/${FPP_CROSS_TRIPLET}/pkgconfig:/usr/share/pkgconfig")
set(ENV{PKG_CONFIG_PATH} "")
set(ENV{PKG_CONFIG_SYSTEM_LIBRARY_PATH} "/usr/lib/${FPP_CROSS_TRIPLET}:/lib/${FPP_CROSS_TRIPLET}")

set(yaml-cpp_DIR ${FPP_CROSS_EXTRA_PREFIX}/lib/${FPP_CROSS_TRIPLET}/cmake/yaml-cpp
  CACHE PATH "yaml-cpp's arm64 CMake package (toolchain/install-deps.sh)")
if(NOT EXISTS ${yaml-cpp_DIR}/yaml-cpp-config.cmake)
  message(FATAL_ERROR "${yaml-cpp_DIR}: no arm64 yaml-cpp; run toolchain/install-deps.sh")
endif()

# qemu-user runs the arm64 binaries. "-L /": the arm64 loader and libraries
# are Debian's multiarch ones (libc6:arm64 and the rest, in
# /usr/lib/aarch64-linux-gnu, the versions the device runs). Not
# "-L /usr/aarch64-linux-gnu": that folder's loader (libc6-arm64-cross, the
# compiler's own glibc, another Debian revision) would be mixed with
# libc6:arm64's libc.so.6, and a program that starts a thread then hangs.
# The programs that tests start themselves (fpp-scanner) reach qemu through
# binfmt_misc (toolchain/install-deps.sh registers it), with the same libraries.
find_program(FPP_QEMU_AARCH64 qemu-aarch64-static)
if(NOT FPP_QEMU_AARCH64)
  message(WARNING "qemu-aarch64-static not found (qemu-user-static): the arm64 tests cannot run here")
  return()
endif()
set(CMAKE_CROSSCOMPILING_EMULATOR ${FPP_QEMU_AARCH64} -L /)

# As root, Aravis receives its GigE Vision stream through a packet socket
# ring (AF_PACKET with CAP_NET_RAW), whose socket options (SOL_PACKET)
# qemu-user does not emulate: the stream thread then stops and no frame
# arrives. Without CAP_NET_RAW, dropped from the bounding set of the test
# and of every program it starts, Aravis receives over a plain UDP socket,
# as it does for any other user. (Tests keep CAP_SYS_ADMIN and CAP_NET_ADMIN
# for their private network namespace.)
execute_process(COMMAND id -u OUTPUT_VARIABLE FPP_CONFIGURING_UID OUTPUT_STRIP_TRAILING_WHITESPACE)
if(FPP_CONFIGURING_UID STREQUAL "0")
  find_program(FPP_SETPRIV setpriv REQUIRED)
  list(PREPEND CMAKE_CROSSCOMPILING_EMULATOR ${FPP_SETPRIV} --bounding-set=-net_raw)
endif()
