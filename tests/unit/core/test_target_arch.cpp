// The test programs are built for, and run as, the architecture they say:
// on the cross build (preset aarch64, FPP_EXPECT_ARCH=aarch64) each is an
// AArch64 ELF file that this x86-64 machine runs under qemu-user, and so are
// the programs a test starts itself (fpp-scanner through /bin/sh, fork/exec),
// which the kernel hands to qemu through binfmt_misc. On a native build all
// three views name the build machine's architecture.

#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <string_view>

#include <elf.h>
#include <sys/utsname.h>

namespace {

// The architecture the compiler generated code for (as `uname -m` names it).
constexpr const char* compiled_for() {
#if defined(__aarch64__)
    return "aarch64";
#elif defined(__x86_64__)
    return "x86_64";
#else
    return "";
#endif
}

// The ELF machine that `compiled_for()` implies.
constexpr std::uint16_t elf_machine_for(const std::string_view arch) {
    return arch == "aarch64"  ? std::uint16_t{EM_AARCH64}
           : arch == "x86_64" ? std::uint16_t{EM_X86_64}
                              : std::uint16_t{EM_NONE};
}

// This program's file (under qemu-user /proc/self/exe is the emulated
// program, not qemu).
std::filesystem::path own_program() {
    return std::filesystem::read_symlink("/proc/self/exe");
}

// e_machine of a 64-bit little-endian ELF file; EM_NONE if it is not one.
std::uint16_t elf_machine(const std::filesystem::path& file) {
    std::ifstream in(file, std::ios::binary);
    unsigned char header[EI_NIDENT + 4] = {};
    if (!in.read(reinterpret_cast<char*>(header), sizeof header))
        return EM_NONE;
    if (header[EI_MAG0] != ELFMAG0 || header[EI_MAG1] != ELFMAG1 || header[EI_MAG2] != ELFMAG2 ||
        header[EI_MAG3] != ELFMAG3 || header[EI_CLASS] != ELFCLASS64 ||
        header[EI_DATA] != ELFDATA2LSB)
        return EM_NONE;
    // e_type (2 bytes) then e_machine (2 bytes, little-endian) follow e_ident.
    return static_cast<std::uint16_t>(header[EI_NIDENT + 2] | (header[EI_NIDENT + 3] << 8));
}

} // namespace

TEST(TargetArch, ProgramIsBuiltForAndRunsAsItsArchitecture) {
    const std::string arch = compiled_for();
    if (arch.empty())
        GTEST_SKIP() << "an architecture this test does not know";
    utsname host{};
    ASSERT_EQ(uname(&host), 0);
    const std::uint16_t machine = elf_machine(own_program());
    std::printf("compiled for %s; %s is an ELF file for machine %u; uname -m: %s\n", arch.c_str(),
                own_program().c_str(), static_cast<unsigned>(machine), host.machine);

    // The preset that cross-builds says which architecture it expects.
    if (const char* expected = std::getenv("FPP_EXPECT_ARCH"); expected && *expected) {
        EXPECT_EQ(arch, expected);
    }
    EXPECT_EQ(machine, elf_machine_for(arch));
    // qemu-user reports the emulated machine, as the device's kernel would.
    EXPECT_EQ(std::string(host.machine), arch);
}

TEST(TargetArch, ProgramsStartedByTestsRunToo) {
    // This program again, through /bin/sh as run_tool starts fpp-scanner:
    // an AArch64 program runs on this machine only through binfmt_misc.
    if (std::string_view(compiled_for()).empty())
        GTEST_SKIP() << "an architecture this test does not know";
    fpp::test::TempDir scratch;
    const auto run = fpp::test::run_tool(
        own_program().string(),
        "--gtest_filter=TargetArch.ProgramIsBuiltForAndRunsAsItsArchitecture", scratch.path());
    EXPECT_EQ(run.exit_code, 0)
        << "this test program cannot start itself; on a cross build, register qemu-user with "
           "binfmt_misc (toolchain/install-deps.sh does)\n"
        << run.output;
    EXPECT_NE(run.output.find("compiled for " + std::string(compiled_for())), std::string::npos)
        << run.output;
    EXPECT_NE(run.output.find("[  PASSED  ] 1 test"), std::string::npos) << run.output;
}
