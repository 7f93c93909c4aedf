// The paper experiments' timings (see paper_stages.hpp): the relief's
// reconstruction times and Experiment 4, N x N windows of the plane scan,
// with the crops of a calibration, a table and a decode that the windows use
// (see paper_experiments.hpp).

#include "fpp/calib/paper_experiments.hpp"

#include "fpp/calib/plots.hpp"
#include "fpp/parallel.hpp"
#include "fpp/table_kernel.hpp"
#include "paper_stages.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace fpp::calib {

namespace paper {

namespace {

// Best wall time of `runs` calls (after one warm-up call that allocates).
template <class F> double best_seconds(int runs, F&& f) {
    f();
    double best = std::numeric_limits<double>::infinity();
    for (int r = 0; r < runs; ++r) {
        const auto start = Clock::now();
        f();
        best = std::min(best, seconds_since(start));
    }
    return best;
}

} // namespace

void Run::time_relief(const DecodeResult& decoded) {
    const int runs = options().timing_runs;
    ReliefSummary& relief = record_.relief;
    say("relief: timing the reconstructions, one thread each, best of " + std::to_string(runs));
    relief.seconds.assign(count(), kNaN);
    PointCloud cloud;
    SvOptions one;
    one.threads = 1;
    ThreadPool single(1);
    for (std::size_t m = 0; m < count(); ++m) {
        const Method& method = record_.methods[m];
        if (method.procedure == Procedure::reference)
            continue;
        if (method.is_table()) {
            relief.seconds[m] = best_seconds(
                runs, [&] { apply_table(method.table, decoded.proj_x, cloud, &single); });
        } else {
            const SvReconstructor sv(*method.calibration, one);
            relief.seconds[m] =
                best_seconds(runs, [&] { sv.reconstruct(decoded, ReconstructAxes::x, cloud); });
        }
        add("relief.time." + method.key, relief.seconds[m], "s");
    }
    SvOptions iteration = one;
    iteration.solver = XOnlySolver::plane_iteration;
    const SvReconstructor sv(paper_calibration_, iteration);
    relief.seconds_sv_plane_iteration =
        best_seconds(runs, [&] { sv.reconstruct(decoded, ReconstructAxes::x, cloud); });
    add("relief.time.sv_plane_iteration", relief.seconds_sv_plane_iteration, "s");
}

void Run::run_windows(const DecodeResult& decoded, const Reconstructions& full) {
    WindowSummary& windows = record_.windows;
    windows.methods.push_back(record_.find("sv-paper"));
    for (std::size_t m = 0; m < count(); ++m)
        if (record_.methods[m].procedure == Procedure::boards && record_.methods[m].is_table() &&
            record_.methods[m].key.starts_with("boards-"))
            windows.methods.push_back(m);
    const Size camera = decoded.camera;
    double cx = 0, cy = 0;
    std::size_t n = 0;
    for (int y = 0; y < camera.height; ++y)
        for (int x = 0; x < camera.width; ++x)
            if (full.common[std::size_t(y) * std::size_t(camera.width) + std::size_t(x)]) {
                cx += x;
                cy += y;
                ++n;
            }
    if (n == 0)
        throw std::runtime_error("windows: the plane scan has no points");
    cx /= double(n);
    cy /= double(n);
    const int largest = std::min(camera.width, camera.height);
    for (int k = 1; k <= kWindowSizes; ++k) {
        const int size = std::min(
            largest, std::max(8, static_cast<int>(std::lround(double(kWindowStepFullSize * k) /
                                                              double(options().binning)))));
        if (windows.sizes.empty() || size > windows.sizes.back())
            windows.sizes.push_back(size);
    }
    const int runs = options().timing_runs;
    say("windows: timing " + std::to_string(windows.sizes.size()) +
        " square windows of the plane scan, one thread each, best of " + std::to_string(runs));
    windows.seconds.assign(windows.methods.size(), {});
    ThreadPool single(1);
    SvOptions one;
    one.threads = 1;
    for (int size : windows.sizes) {
        const int x0 =
            std::clamp(static_cast<int>(std::lround(cx - size / 2.0)), 0, camera.width - size);
        const int y0 =
            std::clamp(static_cast<int>(std::lround(cy - size / 2.0)), 0, camera.height - size);
        const Size window{size, size};
        const DecodeResult cropped = crop_decode(decoded, x0, y0, window);
        std::size_t points = 0;
        for (std::size_t w = 0; w < windows.methods.size(); ++w) {
            const std::size_t m = windows.methods[w];
            const Method& method = record_.methods[m];
            PointCloud cloud;
            if (method.is_table()) {
                const CoefficientTable table = crop_table(method.table, x0, y0, window);
                windows.seconds[w].push_back(best_seconds(
                    runs, [&] { apply_table(table, cropped.proj_x, cloud, &single); }));
            } else {
                const SvReconstructor sv(crop_calibration(*method.calibration, x0, y0, window),
                                         one);
                windows.seconds[w].push_back(best_seconds(
                    runs, [&] { sv.reconstruct(cropped, ReconstructAxes::x, cloud); }));
            }
            // The window's reconstruction must be the full image's, pixel for pixel.
            for (int y = 0; y < size; ++y)
                for (int x = 0; x < size; ++x) {
                    const float* a = &cloud.xyz.at(x, y, 0);
                    const float* b = &full.clouds[m].xyz.at(x0 + x, y0 + y, 0);
                    const bool fa = finite_point(a), fb = finite_point(b);
                    if (w == 0 && fa)
                        ++points;
                    if (fa != fb) {
                        ++windows.crop_mismatched;
                        continue;
                    }
                    if (fa)
                        for (int c = 0; c < 3; ++c)
                            windows.crop_max_difference_mm =
                                std::max(windows.crop_max_difference_mm,
                                         std::abs(double(a[c]) - double(b[c])));
                }
        }
        windows.points.push_back(points);
    }
    for (std::size_t k = 0; k < windows.sizes.size(); ++k)
        for (std::size_t w = 0; w < windows.methods.size(); ++w)
            add("windows.n" + std::to_string(windows.sizes[k]) + ".time." +
                    record_.methods[windows.methods[w]].key,
                windows.seconds[w][k], "s");
    add("windows.crop_max_difference", windows.crop_max_difference_mm, "mm");
    add("windows.crop_mismatched", double(windows.crop_mismatched), "");
    std::vector<PlotSeries> series;
    for (std::size_t w = 0; w < windows.methods.size(); ++w)
        series.push_back(
            {record_.methods[windows.methods[w]].title, windows.seconds[w], series_colour(w)});
    png("windows-timing.png",
        timing_plot(windows.sizes, series,
                    "Experiment 4: reconstruction time of N x N windows (one thread)"));
}

} // namespace paper

namespace {

template <class T> Image<T> crop_image(const Image<T>& image, int x0, int y0, Size size) {
    if (image.empty())
        return {};
    Image<T> out(size, image.channels());
    const std::size_t row_values = std::size_t(size.width) * std::size_t(image.channels());
    for (int y = 0; y < size.height; ++y) {
        const T* src = image.row(y0 + y) + std::size_t(x0) * std::size_t(image.channels());
        std::copy(src, src + row_values, out.row(y));
    }
    return out;
}

void check_window(Size camera, int x0, int y0, Size size, const char* what) {
    if (size.width <= 0 || size.height <= 0 || x0 < 0 || y0 < 0 || x0 + size.width > camera.width ||
        y0 + size.height > camera.height)
        throw std::invalid_argument(std::string(what) + ": window outside the camera image");
}

} // namespace

StereoCalibration crop_calibration(const StereoCalibration& calibration, int x0, int y0,
                                   Size size) {
    check_window(calibration.camera_size, x0, y0, size, "crop_calibration");
    if (!calibration.camera_correction.empty())
        throw std::invalid_argument("crop_calibration: a camera with a correction grid");
    StereoCalibration out = calibration;
    out.camera_size = size;
    // u = fu xd + skew yd + cu: the window's pixel u - x0 has principal point cu - x0.
    out.camera.cu -= double(x0);
    out.camera.cv -= double(y0);
    out.origin = calibration.origin + " (camera window " + std::to_string(size.width) + " x " +
                 std::to_string(size.height) + " at " + std::to_string(x0) + ", " +
                 std::to_string(y0) + ")";
    return out;
}

CoefficientTable crop_table(const CoefficientTable& table, int x0, int y0, Size size) {
    check_window(table.info().camera, x0, y0, size, "crop_table");
    TableInfo info = table.info();
    info.camera = size;
    CoefficientTable out(info);
    const int planes = table.planes();
    for (int y = 0; y < size.height; ++y)
        for (int x = 0; x < size.width; ++x)
            for (int p = 0; p < planes; ++p)
                out.set(p, x, y, table.get(p, x0 + x, y0 + y));
    return out;
}

DecodeResult crop_decode(const DecodeResult& decoded, int x0, int y0, Size size) {
    check_window(decoded.camera, x0, y0, size, "crop_decode");
    DecodeResult out;
    out.camera = size;
    out.proj_x = crop_image(decoded.proj_x, x0, y0, size);
    out.proj_y = crop_image(decoded.proj_y, x0, y0, size);
    out.modulation = crop_image(decoded.modulation, x0, y0, size);
    out.mean = crop_image(decoded.mean, x0, y0, size);
    out.mask = crop_image(decoded.mask, x0, y0, size);
    out.method_x = decoded.method_x;
    out.method_y = decoded.method_y;
    return out;
}

} // namespace fpp::calib
