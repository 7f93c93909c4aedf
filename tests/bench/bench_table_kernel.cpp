// Speed of the hybrid model's reconstruction kernel (apply_table) on a full
// 1600x1200 frame, both models, on one thread and on all threads, against a
// plain copy of the bytes the kernel must read (phase image + table) measured
// in the same run: the kernel streams the table once, so the copy is the
// memory-bandwidth floor. Target: a full frame in 10 ms or less on one core.
// Also with the predicted depth sigma (a coordinate-sigma image in, sigma_z
// out: 15 MB more memory traffic at this size), reported as a ratio to the
// kernel without it.
// Run with --benchmark_repetitions=N on a shared machine: the summary takes
// the best of the repetitions.

#include "fpp/coefficient_table.hpp"
#include "fpp/parallel.hpp"
#include "fpp/table_kernel.hpp"

#include "best_time_reporter.hpp"

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <unistd.h>

namespace {

namespace fs = std::filesystem;

constexpr fpp::Size kCamera{1600, 1200};

// A table of realistic content: every pixel modelled, centre phase across the
// projector, Z about 800 mm (values do not change the work, only the counts).
fpp::CoefficientTable make_table(fpp::TableModel model) {
    fpp::TableInfo info;
    info.camera = kCamera;
    info.model = model;
    info.projector = {1280, 800};
    fpp::CoefficientTable table(info);
    namespace tp = fpp::table_plane;
    for (int y = 0; y < kCamera.height; ++y) {
        for (int x = 0; x < kCamera.width; ++x) {
            const float xn = static_cast<float>(x - 800) / 1800.0f;
            const float yn = static_cast<float>(y - 600) / 1800.0f;
            const float z[4] = {800.0f, -120.0f, 6.0f, -1.5f};
            table.set(tp::centre, x, y, 0.8f * static_cast<float>(x));
            table.set(tp::inv_half_range, x, y, 1.0f / 150.0f);
            for (int k = 0; k < 4; ++k) {
                if (model == fpp::TableModel::polynomial) {
                    table.set(tp::poly_x + k, x, y, xn * z[k]);
                    table.set(tp::poly_y + k, x, y, yn * z[k]);
                    table.set(tp::poly_z + k, x, y, z[k]);
                } else {
                    table.set(tp::ray_z + k, x, y, z[k]); // = rational_z + k
                }
            }
            if (model == fpp::TableModel::ray) {
                table.set(tp::ray_xn, x, y, xn);
                table.set(tp::ray_yn, x, y, yn);
            } else if (model == fpp::TableModel::rational) {
                table.set(tp::rational_d, x, y, 0.1f);
                table.set(tp::rational_xn, x, y, xn);
                table.set(tp::rational_yn, x, y, yn);
            }
        }
    }
    return table;
}

// Phase within each pixel's range except a band of undecoded (NaN) pixels
// and some out of range, as on a real scene.
fpp::Image<float> make_phase() {
    fpp::Image<float> phase(kCamera, 1);
    for (int y = 0; y < kCamera.height; ++y) {
        float* row = phase.row(y);
        for (int x = 0; x < kCamera.width; ++x) {
            const float s = std::sin(0.01f * static_cast<float>(x + 2 * y));
            row[x] = y % 97 < 5 ? std::nanf("") : 0.8f * static_cast<float>(x) + 160.0f * s;
        }
    }
    return phase;
}

// A coordinate sigma per pixel (projector px), as fpp::coordinate_sigma gives.
fpp::Image<float> make_sigma() {
    fpp::Image<float> sigma(kCamera, 1);
    for (int y = 0; y < kCamera.height; ++y) {
        float* row = sigma.row(y);
        for (int x = 0; x < kCamera.width; ++x)
            row[x] = 0.02f + 0.0001f * static_cast<float>((x + y) % 300);
    }
    return sigma;
}

struct Fixture {
    fpp::Image<float> phase = make_phase();
    fpp::Image<float> sigma = make_sigma();
    fpp::CoefficientTable polynomial = make_table(fpp::TableModel::polynomial);
    fpp::CoefficientTable ray = make_table(fpp::TableModel::ray);
    fpp::CoefficientTable rational = make_table(fpp::TableModel::rational);

    static const Fixture& get() {
        static const Fixture f;
        return f;
    }
    const fpp::CoefficientTable& table(fpp::TableModel model) const {
        return model == fpp::TableModel::polynomial ? polynomial
               : model == fpp::TableModel::ray      ? ray
                                                    : rational;
    }
    static std::size_t table_bytes(const fpp::CoefficientTable& t) {
        return static_cast<std::size_t>(t.info().tile_count()) *
               static_cast<std::size_t>(t.planes()) *
               static_cast<std::size_t>(t.info().tile_pixels()) * sizeof(float);
    }
    std::size_t input_bytes(fpp::TableModel model) const {
        return phase.pixel_count() * sizeof(float) + table_bytes(table(model));
    }
};

// The bandwidth baseline: copy the phase image and the table.
void copy_input(benchmark::State& state, fpp::TableModel model) {
    const Fixture& fx = Fixture::get();
    const fpp::CoefficientTable& table = fx.table(model);
    const std::size_t phase_bytes = fx.phase.pixel_count() * sizeof(float);
    const std::size_t table_bytes = Fixture::table_bytes(table);
    std::vector<unsigned char> dst(phase_bytes + table_bytes);
    for (auto _ : state) {
        std::memcpy(dst.data(), fx.phase.data(), phase_bytes);
        std::memcpy(dst.data() + phase_bytes, table.tile(0, 0), table_bytes);
        benchmark::DoNotOptimize(dst.data());
        benchmark::ClobberMemory();
    }
    state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) *
                            static_cast<std::int64_t>(phase_bytes + table_bytes));
}

// Into the same cloud every frame, as a scanner does; with `sigma`, also
// sigma_z from the coordinate sigma.
void apply(benchmark::State& state, fpp::TableModel model, int threads, bool sigma) {
    const Fixture& fx = Fixture::get();
    fpp::ThreadPool& pool = fpp::ThreadPool::shared(threads);
    fpp::PointCloud cloud;
    const fpp::Image<float>* coordinate_sigma = sigma ? &fx.sigma : nullptr;
    fpp::TableApplyStats stats =
        fpp::apply_table(fx.table(model), fx.phase, cloud, &pool, coordinate_sigma);
    for (auto _ : state) {
        stats = fpp::apply_table(fx.table(model), fx.phase, cloud, &pool, coordinate_sigma);
        benchmark::DoNotOptimize(cloud.xyz.data());
        benchmark::DoNotOptimize(cloud.sigma_z.data());
    }
    state.counters["threads"] = pool.size();
    state.counters["points"] = static_cast<double>(stats.points);
    state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) *
                            static_cast<std::int64_t>(fx.input_bytes(model)));
}

fs::path table_file_path(fpp::TableModel model) {
    return fs::temp_directory_path() /
           ("fpp-bench-" + std::to_string(::getpid()) + "-" + fpp::to_string(model) + ".fpt");
}

// The table file of a model, written on first use (removed at exit by main).
fs::path table_file(fpp::TableModel model) {
    const fs::path path = table_file_path(model);
    if (!fs::exists(path))
        fpp::write_table(path, Fixture::get().table(model));
    return path;
}

// Start-up cost: loading a table file (read or mapped), checking every CRC
// and coefficient.
void load(benchmark::State& state, fpp::TableModel model, bool map) {
    const fs::path path = table_file(model);
    for (auto _ : state) {
        const fpp::CoefficientTable table = fpp::load_table(path, &kCamera, map);
        benchmark::DoNotOptimize(table.tile(0, 0));
    }
    state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) *
                            static_cast<std::int64_t>(fs::file_size(path)));
}

} // namespace

int main(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv))
        return 1;
    const int all = fpp::ThreadPool::resolve_threads(0);
    for (const fpp::TableModel model :
         {fpp::TableModel::polynomial, fpp::TableModel::ray, fpp::TableModel::rational}) {
        const std::string m = fpp::to_string(model);
        benchmark::RegisterBenchmark(("copy_input/" + m).c_str(), copy_input, model)
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime();
        for (const bool sigma : {false, true}) {
            const std::string tail = sigma ? "/sigma" : "";
            benchmark::RegisterBenchmark(("apply_table/" + m + "/1_thread" + tail).c_str(), apply,
                                         model, 1, sigma)
                ->Unit(benchmark::kMillisecond)
                ->UseRealTime();
            benchmark::RegisterBenchmark(("apply_table/" + m + "/all_threads" + tail).c_str(),
                                         apply, model, all, sigma)
                ->Unit(benchmark::kMillisecond)
                ->UseRealTime();
        }
        benchmark::RegisterBenchmark(("load_table/" + m + "/mapped").c_str(), load, model, true)
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime();
        benchmark::RegisterBenchmark(("load_table/" + m + "/read").c_str(), load, model, false)
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime();
    }
    fpp::bench::BestTimeReporter reporter;
    benchmark::RunSpecifiedBenchmarks(&reporter);
    benchmark::Shutdown();

    std::printf("\nsummary (%dx%d frame, tiles 32x8, best of the repetitions; %d threads = all)\n",
                kCamera.width, kCamera.height, all);
    for (const fpp::TableModel model :
         {fpp::TableModel::polynomial, fpp::TableModel::ray, fpp::TableModel::rational}) {
        const std::string m = fpp::to_string(model);
        const double copy = 1e3 * reporter.seconds("copy_input/" + m);
        const double one = 1e3 * reporter.seconds("apply_table/" + m + "/1_thread");
        const double many = 1e3 * reporter.seconds("apply_table/" + m + "/all_threads");
        if (copy <= 0 || one <= 0)
            continue;
        const double mb = static_cast<double>(Fixture::get().input_bytes(model)) / 1e6;
        std::printf("  %-10s reads %5.1f MB: 1 thread %6.2f ms (target <= 10, %.2fx the copy),"
                    " all threads %6.2f ms (%.2fx); copy %6.2f ms\n",
                    m.c_str(), mb, one, one / copy, many, many > 0 ? many / copy : 0.0, copy);
        const double one_sigma = 1e3 * reporter.seconds("apply_table/" + m + "/1_thread/sigma");
        const double many_sigma = 1e3 * reporter.seconds("apply_table/" + m + "/all_threads/sigma");
        if (one_sigma > 0 && many_sigma > 0 && many > 0)
            std::printf("  %-10s with sigma_z: 1 thread %6.2f ms (%.2fx without), all threads "
                        "%6.2f ms (%.2fx without)\n",
                        "", one_sigma, one_sigma / one, many_sigma, many_sigma / many);
        const double mapped = 1e3 * reporter.seconds("load_table/" + m + "/mapped");
        const double read = 1e3 * reporter.seconds("load_table/" + m + "/read");
        if (mapped > 0 && read > 0)
            std::printf(
                "  %-10s load (all CRCs and values checked): mapped %.1f ms, read %.1f ms\n", "",
                mapped, read);
    }
    for (const fpp::TableModel model :
         {fpp::TableModel::polynomial, fpp::TableModel::ray, fpp::TableModel::rational}) {
        std::error_code ec;
        fs::remove(table_file_path(model), ec);
    }
    return 0;
}
