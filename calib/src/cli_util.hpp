#pragma once
// Small helpers shared by the subcommands.

#include "fpp/capture_set.hpp"
#include "fpp/image.hpp"
#include "fpp/pattern_block.hpp"
#include "fpp/point_cloud.hpp"

#include <chrono>
#include <filesystem>
#include <string>

namespace fpp::calib {

// A standard sequence name (fpp/sequences.hpp) or the path of a YAML file
// holding a `sequence:` list.
Sequence sequence_from_argument(const std::string& name_or_path, Size projector);

// "error against ground truth: RMS .. mm, max .. mm over .. points\n": the
// 3D error of `cloud` against a simulated capture's truth_xyz (camera frame,
// mm; pixels with both a point and a true surface, nothing removed); "" when
// the capture has no truth or nothing to compare.
std::string truth_comparison(const PointCloud& cloud, const CaptureSet& capture);

// "2.3 s": a duration for progress lines.
std::string seconds_text(double seconds);
// A size as the command line writes it: WIDTHxHEIGHT.
std::string size_text(Size s);
// "1280x1024" (or 1280X1024) -> Size, each side 1..65535; throws
// InputError("command line", option, ...) otherwise.
Size parse_size_text(const std::string& text, const char* option);

class Stopwatch {
public:
    double seconds() const {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    }

private:
    std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

} // namespace fpp::calib
