#pragma once
// Test helpers: where test data lives, temporary folders.

#include <cstddef>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "fpp/image.hpp"

namespace fpp::test {

// The shared folder beside the checkout (env FPP_SHARED_DIR overrides).
std::filesystem::path shared_dir();
// shared_dir()/datasets/<name>; empty path if absent.
std::filesystem::path dataset(const std::string& relative);
// The source tree (for board/sim/*.yaml).
std::filesystem::path source_dir();
// True when running in CI (env CI=true): missing real data is then a failure.
bool in_ci();

// The programs the tests run, as this build made them (tests/CMakeLists.txt
// gives their paths to test_support.cpp alone, so that no other object holds
// the build folder's path): the host tool fpp-calib, and the scanner that
// runs sim boards (fpp-scanner, or fpp-scanner-sim where fpp-scanner is built
// without the virtual scanner). Each throws, naming the program, in a build
// that has none (the host tool is not cross-built).
std::string calib_exe();
std::string scanner_exe();

// The camera binning of full-size simulated captures: 2 where every pixel
// costs several times more (under the sanitizers; AArch64 builds, whose tests
// run under qemu-user here), 1 otherwise. The decoders' arithmetic is the
// same at either size; the ci preset runs them at full size.
constexpr int kSimulatedCaptureBinning =
#if defined(__SANITIZE_ADDRESS__) || defined(__aarch64__)
    2;
#else
    1;
#endif

// A fresh empty folder, removed with its contents on destruction.
class TempDir {
public:
    TempDir();
    ~TempDir();
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
    const std::filesystem::path& path() const { return path_; }
    std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

private:
    std::filesystem::path path_;
};

// A command-line tool run through the shell, as a person runs it.
struct ToolRun {
    int exit_code = -1; // -1 if it did not exit normally (signal)
    std::string output; // stdout and stderr
};

// The argument in single quotes for /bin/sh.
std::string shell_quote(const std::string& s);
inline std::string shell_quote(const std::filesystem::path& p) {
    return shell_quote(p.string());
}

// Runs `exe args` (args already quoted as needed), output captured through
// a log file in `scratch` that is removed afterwards.
ToolRun run_tool(const std::string& exe, const std::string& args,
                 const std::filesystem::path& scratch);

// A file's bytes ("" when it cannot be read).
std::string file_bytes(const std::filesystem::path& file);

// Every file and folder below `dir`, recursively ({} when `dir` is not
// there): what a failed write must not leave in a store.
std::vector<std::filesystem::path> entries_under(const std::filesystem::path& dir);

// A figures.csv written by fpp-calib (header name,value,unit): name -> value.
// Throws std::runtime_error naming the file if it is missing or malformed.
std::map<std::string, double> read_figures_csv(const std::filesystem::path& file);

// RMS 3D distance (mm) of a PLY's points (written by fpp::write_ply, with
// pixel indices) to `truth_xyz` (3-channel float, camera frame, NaN = no
// surface) at their pixels; `compared` gets the number of points that have a
// true surface (NaN when none has).
double ply_rms_against_truth(const std::filesystem::path& ply, const Image<float>& truth_xyz,
                             std::size_t& compared);

// The same comparison with the gross errors apart: a point farther than
// `gross_mm` from the truth is counted, not summed. One pixel decoded to a
// wrong fringe order (80 mm off) lifts the RMS of 100,000 points by 0.25 mm;
// one frame decoded under another pattern's name puts thousands off.
struct TruthErrors {
    std::size_t compared = 0; // points with a true surface
    std::size_t gross = 0;    // of them, farther than gross_mm
    double rms_mm = 0;        // RMS over all compared points
    double rms_without_gross_mm = 0;
};
TruthErrors ply_errors_against_truth(const std::filesystem::path& ply,
                                     const Image<float>& truth_xyz, double gross_mm);

} // namespace fpp::test

// Skips the test with a clear message when a real dataset is absent; in CI
// (where ../shared is always present) its absence is a failure instead.
#define FPP_REQUIRE_DATASET(path_expr)                                                             \
    do {                                                                                           \
        if (!std::filesystem::exists(path_expr)) {                                                 \
            if (::fpp::test::in_ci()) {                                                            \
                FAIL() << "real dataset missing in CI: " << (path_expr);                           \
            }                                                                                      \
            GTEST_SKIP() << "real dataset not found (set FPP_SHARED_DIR): " << (path_expr);        \
        }                                                                                          \
    } while (0)
