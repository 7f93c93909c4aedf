// SV reconstruction speed on a full 1600x1200 frame of the paper's rig (a
// plane filling the field at 480 mm; the decoded coordinates are the
// renderer's true projector coordinates, so every lit pixel is a point):
//   - x only (Newton along the epipolar line; and the paper's plane iteration),
//   - x and y (projector pixel undistorted, ray midpoint),
//   - the camera-ray table (once per calibration),
//   - PLY encoding,
// against a baseline measured in the same run: memcpy of the output bytes
// (xyz, quality, intensity: 20 bytes per pixel). Prints points per second
// and the paper's figure for comparison (SV: 683,047 points in 1.04 s).

#include "fpp/calib/simulated_rig.hpp"
#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/calib/sv_reconstruct.hpp"
#include "fpp/point_cloud.hpp"
#include "fpp/simulator/renderer.hpp"
#include "fpp/simulator/rig.hpp"
#include "fpp/simulator/scene.hpp"

#include "best_time_reporter.hpp"

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace {

using fpp::calib::ReconstructAxes;

struct Fixture {
    fpp::calib::StereoCalibration calibration;
    fpp::DecodeResult decoded;
    std::size_t points_x = 0;  // points of one x-only reconstruction
    std::size_t points_xy = 0; // of one x+y reconstruction

    static const Fixture& get() {
        static const Fixture f;
        return f;
    }

    // One reconstructor per (threads, solver), built on first use.
    const fpp::calib::SvReconstructor& reconstructor(int threads, bool paper_iteration) const {
        const int key = threads * 2 + (paper_iteration ? 1 : 0);
        auto& slot = cache_[key];
        if (!slot) {
            fpp::calib::SvOptions options;
            options.threads = threads;
            if (paper_iteration)
                options.solver = fpp::calib::XOnlySolver::plane_iteration;
            slot = std::make_unique<fpp::calib::SvReconstructor>(calibration, options);
        }
        return *slot;
    }

private:
    Fixture() {
        const fpp::sim::Rig rig = fpp::sim::Rig::paper();
        calibration = fpp::calib::calibration_from_rig(rig);
        const fpp::sim::Renderer renderer(rig, fpp::sim::named_scene("plane"));
        const auto& truth = renderer.truth_projector();
        constexpr float nan = std::numeric_limits<float>::quiet_NaN();
        decoded.camera = truth.size();
        decoded.proj_x = fpp::Image<float>(truth.size(), 1, nan);
        decoded.proj_y = fpp::Image<float>(truth.size(), 1, nan);
        decoded.modulation = fpp::Image<float>(truth.size(), 1, 100.0f);
        decoded.mean = fpp::Image<float>(truth.size(), 1, 120.0f);
        for (std::size_t i = 0; i < truth.pixel_count(); ++i) {
            decoded.proj_x.data()[i] = truth.data()[2 * i];
            decoded.proj_y.data()[i] = truth.data()[2 * i + 1];
        }
        fpp::PointCloud cloud;
        points_x = reconstructor(0, false).reconstruct(decoded, ReconstructAxes::x, cloud).points;
        points_xy = reconstructor(0, false).reconstruct(decoded, ReconstructAxes::xy, cloud).points;
    }
    mutable std::map<int, std::unique_ptr<fpp::calib::SvReconstructor>> cache_;
};

constexpr std::size_t kOutputBytesPerPixel = 5 * sizeof(float); // xyz, quality, intensity

void BM_MemcpyOutput(benchmark::State& state) {
    const auto& fx = Fixture::get();
    const std::size_t bytes = fx.decoded.camera.area() * kOutputBytesPerPixel;
    std::vector<char> src(bytes, 1), dst(bytes, 0);
    for (auto _ : state) {
        std::memcpy(dst.data(), src.data(), bytes);
        benchmark::DoNotOptimize(dst.data());
        benchmark::ClobberMemory();
    }
    state.SetBytesProcessed(std::int64_t(state.iterations()) * std::int64_t(bytes));
}

void run_sv(benchmark::State& state, ReconstructAxes axes, bool paper_iteration) {
    const auto& fx = Fixture::get();
    const int threads = static_cast<int>(state.range(0));
    const auto& sv = fx.reconstructor(threads, paper_iteration);
    fpp::PointCloud cloud;
    sv.reconstruct(fx.decoded, axes, cloud); // output images allocated outside the timing
    std::size_t points = 0;
    for (auto _ : state) {
        points = sv.reconstruct(fx.decoded, axes, cloud).points;
        benchmark::DoNotOptimize(cloud.xyz.data());
    }
    state.counters["points"] = double(points);
    state.counters["points_per_s"] =
        benchmark::Counter(double(points), benchmark::Counter::kIsIterationInvariantRate);
}

void BM_SvXOnly(benchmark::State& state) {
    run_sv(state, ReconstructAxes::x, false);
}
void BM_SvXOnlyPaperIteration(benchmark::State& state) {
    run_sv(state, ReconstructAxes::x, true);
}
void BM_SvXY(benchmark::State& state) {
    run_sv(state, ReconstructAxes::xy, false);
}

void BM_CameraRays(benchmark::State& state) {
    const auto& fx = Fixture::get();
    fpp::calib::SvOptions options;
    options.threads = static_cast<int>(state.range(0));
    for (auto _ : state) {
        fpp::calib::SvReconstructor sv(fx.calibration, options);
        benchmark::DoNotOptimize(sv.camera_rays().data());
    }
}

void BM_EncodePly(benchmark::State& state) {
    const auto& fx = Fixture::get();
    fpp::PointCloud cloud;
    fx.reconstructor(0, false).reconstruct(fx.decoded, ReconstructAxes::x, cloud);
    std::size_t bytes = 0;
    for (auto _ : state) {
        const std::string ply = fpp::encode_ply(cloud);
        bytes = ply.size();
        benchmark::DoNotOptimize(ply.data());
    }
    state.SetBytesProcessed(std::int64_t(state.iterations()) * std::int64_t(bytes));
}

// Threads: 1, and 0 = all cores.
BENCHMARK(BM_MemcpyOutput)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SvXOnly)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SvXOnlyPaperIteration)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SvXY)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_CameraRays)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_EncodePly)->Unit(benchmark::kMillisecond)->UseRealTime();

} // namespace

int main(int argc, char** argv) {
    fpp::bench::BestTimeReporter reporter;
    if (!fpp::bench::run_benchmarks(argc, argv, reporter))
        return 1;

    const auto& fx = Fixture::get();
    const double copy = reporter.seconds("BM_MemcpyOutput/real_time");
    std::printf("\nSV reconstruction of a 1600x1200 frame (%zu points x only, %zu x+y):\n",
                fx.points_x, fx.points_xy);
    const struct {
        const char* name;
        const char* label;
        std::size_t points;
    } rows[] = {
        {"BM_SvXOnly/1/real_time", "x only, Newton, 1 thread", fx.points_x},
        {"BM_SvXOnly/0/real_time", "x only, Newton, all cores", fx.points_x},
        {"BM_SvXOnlyPaperIteration/1/real_time", "x only, plane iteration, 1 thread", fx.points_x},
        {"BM_SvXOnlyPaperIteration/0/real_time", "x only, plane iteration, all cores", fx.points_x},
        {"BM_SvXY/1/real_time", "x+y, ray midpoint, 1 thread", fx.points_xy},
        {"BM_SvXY/0/real_time", "x+y, ray midpoint, all cores", fx.points_xy}};
    for (const auto& r : rows) {
        const double s = reporter.seconds(r.name);
        if (s <= 0)
            continue;
        std::printf("  %-36s %8.2f ms  %7.1f Mpoints/s  %6.1f ns/point  %5.1fx the output memcpy\n",
                    r.label, s * 1e3, double(r.points) / s * 1e-6, s / double(r.points) * 1e9,
                    copy > 0 ? s / copy : 0.0);
    }
    std::printf("  paper's SV model: 683047 points in 1.04 s = %.2f Mpoints/s\n",
                683047.0 / 1.04 * 1e-6);
    return 0;
}
