#include "cli_util.hpp"

#include "fpp/capture_set.hpp"
#include "fpp/error.hpp"
#include "fpp/image_io.hpp"
#include "fpp/sequences.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace fpp::calib {

Sequence sequence_from_argument(const std::string& name_or_path, Size projector) {
    if (std::filesystem::is_regular_file(name_or_path))
        return read_sequence(name_or_path);
    return standard_sequence(name_or_path, projector);
}

void check_output_path(const std::filesystem::path& path, const char* option) {
    const std::filesystem::path folder = path.parent_path();
    if (!folder.empty() && !std::filesystem::is_directory(folder))
        throw InputError(path, option, "the folder " + folder.string() + " does not exist");
    if (std::filesystem::is_directory(path))
        throw InputError(path, option, "is a folder");
}

CLI::Option* add_threads_option(CLI::App& cmd, int& threads) {
    return cmd.add_option("--threads", threads, "worker threads (0 = all cores)")
        ->capture_default_str();
}

CLI::Option* add_min_modulation_option(CLI::App& cmd, double& min_modulation) {
    return cmd
        .add_option("--min-modulation", min_modulation,
                    "minimum modulation as a fraction of full scale")
        ->capture_default_str();
}

std::string size_text(Size s) {
    return std::to_string(s.width) + "x" + std::to_string(s.height);
}

Size parse_size_text(const std::string& text, const char* option) {
    const std::size_t x = text.find_first_of("xX");
    try {
        if (x != std::string::npos) {
            std::size_t used_w = 0, used_h = 0;
            const int w = std::stoi(text.substr(0, x), &used_w);
            const int h = std::stoi(text.substr(x + 1), &used_h);
            if (used_w == x && used_h == text.size() - x - 1 && w > 0 && h > 0 && w <= 65535 &&
                h <= 65535)
                return {w, h};
        }
    } catch (const std::exception&) { // not a number, or out of int's range
    }
    throw InputError("command line", option,
                     "expected WIDTHxHEIGHT (e.g. 1920x1080), got '" + text + "'");
}

std::string seconds_text(double seconds) {
    char text[32];
    std::snprintf(text, sizeof text, "%.1f s", seconds);
    return text;
}

// RMS and maximum 3D error against a simulated capture's truth (pixels with
// both a point and a true surface).
std::string truth_comparison(const PointCloud& cloud, const CaptureSet& capture) {
    if (!capture.manifest.truth || capture.manifest.truth->xyz.empty())
        return {};
    const Image<float> truth = read_tiff_float(capture.folder / capture.manifest.truth->xyz);
    if (truth.size() != cloud.size() || truth.channels() != 3)
        return {};
    double sum = 0, worst = 0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < truth.pixel_count(); ++i) {
        const float* a = cloud.xyz.data() + 3 * i;
        const float* b = truth.data() + 3 * i;
        if (!std::isfinite(a[2]) || !std::isfinite(b[2]))
            continue;
        const double d = std::sqrt(double(a[0] - b[0]) * double(a[0] - b[0]) +
                                   double(a[1] - b[1]) * double(a[1] - b[1]) +
                                   double(a[2] - b[2]) * double(a[2] - b[2]));
        sum += d * d;
        worst = std::max(worst, d);
        ++n;
    }
    if (n == 0)
        return {};
    std::ostringstream s;
    s << "error against ground truth: RMS " << std::sqrt(sum / double(n)) << " mm, max " << worst
      << " mm over " << n << " points\n";
    return s.str();
}

} // namespace fpp::calib
