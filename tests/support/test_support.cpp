#include "test_support.hpp"

#include "fpp/point_cloud.hpp"

#include <sys/wait.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>

namespace fpp::test {

std::filesystem::path shared_dir() {
    if (const char* env = std::getenv("FPP_SHARED_DIR"); env && *env)
        return env;
    return FPP_SHARED_DIR_DEFAULT;
}

std::filesystem::path dataset(const std::string& relative) {
    return shared_dir() / "datasets" / relative;
}

std::filesystem::path source_dir() {
    return FPP_SOURCE_DIR;
}

bool in_ci() {
    const char* env = std::getenv("CI");
    return env && std::string(env) == "true";
}

std::string calib_exe() {
#ifdef FPP_CALIB_EXE
    return FPP_CALIB_EXE;
#else
    throw std::runtime_error("this build has no fpp-calib (FPP_BUILD_HOST_TOOLS is OFF)");
#endif
}

std::string scanner_exe() {
#ifdef FPP_SCANNER_EXE
    return FPP_SCANNER_EXE;
#else
    throw std::runtime_error("this build gave the tests no scanner (tests/CMakeLists.txt)");
#endif
}

TempDir::TempDir() {
    std::random_device rd;
    const auto base = std::filesystem::temp_directory_path();
    for (int attempt = 0; attempt < 100; ++attempt) {
        auto candidate = base / ("fpp-test-" + std::to_string(rd()));
        if (std::filesystem::create_directory(candidate)) {
            path_ = candidate;
            return;
        }
    }
    throw std::runtime_error("cannot create a temporary folder in " + base.string());
}

TempDir::~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
}

std::string shell_quote(const std::string& s) {
    std::string q = "'";
    for (char c : s)
        q += (c == '\'') ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

std::string file_bytes(const std::filesystem::path& file) {
    std::ifstream in(file, std::ios::binary);
    std::ostringstream bytes;
    bytes << in.rdbuf();
    return bytes.str();
}

std::vector<std::filesystem::path> entries_under(const std::filesystem::path& dir) {
    std::vector<std::filesystem::path> entries;
    if (std::filesystem::exists(dir))
        for (const auto& entry : std::filesystem::recursive_directory_iterator(dir))
            entries.push_back(entry.path());
    return entries;
}

ToolRun run_tool(const std::string& exe, const std::string& args,
                 const std::filesystem::path& scratch) {
    const std::filesystem::path log = scratch / "tool.log";
    const std::string cmd =
        shell_quote(exe) + " " + args + " > " + shell_quote(log.string()) + " 2>&1";
    const int status = std::system(cmd.c_str());
    ToolRun run;
    run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    {
        std::ifstream in(log);
        std::stringstream ss;
        ss << in.rdbuf();
        run.output = ss.str();
    }
    std::filesystem::remove(log); // the folder holds only what the tool wrote
    return run;
}

std::map<std::string, double> read_figures_csv(const std::filesystem::path& file) {
    std::ifstream in(file);
    std::string line;
    if (!in || !std::getline(in, line) || line != "name,value,unit")
        throw std::runtime_error(file.string() + ": missing, or not a figures.csv");
    std::map<std::string, double> figures;
    while (std::getline(in, line)) {
        const auto a = line.find(','), b = line.rfind(',');
        if (a == std::string::npos || a == b)
            throw std::runtime_error(file.string() + ": malformed line '" + line + "'");
        figures[line.substr(0, a)] = std::stod(line.substr(a + 1, b - a - 1));
    }
    return figures;
}

TruthErrors ply_errors_against_truth(const std::filesystem::path& ply,
                                     const Image<float>& truth_xyz, double gross_mm) {
    const PlyPoints pts = read_ply(ply);
    const auto width = static_cast<std::uint32_t>(truth_xyz.width());
    double sum = 0, sum_fine = 0;
    TruthErrors e;
    for (std::size_t i = 0; i < pts.size(); ++i) {
        const float* t = &truth_xyz.at(static_cast<int>(pts.pixel[i] % width),
                                       static_cast<int>(pts.pixel[i] / width), 0);
        if (!std::isfinite(t[2]))
            continue;
        const double dx = pts.x[i] - t[0], dy = pts.y[i] - t[1], dz = pts.z[i] - t[2];
        const double d2 = dx * dx + dy * dy + dz * dz;
        sum += d2;
        ++e.compared;
        if (d2 > gross_mm * gross_mm)
            ++e.gross;
        else
            sum_fine += d2;
    }
    const std::size_t fine = e.compared - e.gross;
    e.rms_mm = e.compared ? std::sqrt(sum / static_cast<double>(e.compared)) : std::nan("");
    e.rms_without_gross_mm = fine ? std::sqrt(sum_fine / static_cast<double>(fine)) : std::nan("");
    return e;
}

double ply_rms_against_truth(const std::filesystem::path& ply, const Image<float>& truth_xyz,
                             std::size_t& compared) {
    const TruthErrors e = ply_errors_against_truth(ply, truth_xyz, HUGE_VAL);
    compared = e.compared;
    return e.rms_mm;
}

} // namespace fpp::test
