// Virtual-scanner speed at the paper's camera resolution (1600x1200): the
// per-pose geometry (ray casting) and the per-frame render, effects off and on,
// one thread. A plain copy of one output frame is the baseline.

#include "fpp/patterns.hpp"
#include "fpp/simulator/renderer.hpp"
#include "fpp/simulator/rig.hpp"
#include "fpp/simulator/scene.hpp"

#include <benchmark/benchmark.h>

#include <cstring>
#include <filesystem>
#include <vector>

namespace {

fpp::sim::Rig effects_rig() {
    return fpp::sim::load_rig(fpp::sim::effects_rig_path());
}

fpp::Image<std::uint8_t> fringe(const fpp::sim::Rig& rig) {
    return fpp::render_pattern(fpp::PhaseBlock{fpp::Axis::x, 20.0, 8, 1, 0.0}, 1,
                               rig.projector_size);
}

void BM_CopyFrame(benchmark::State& state) {
    std::vector<std::uint8_t> src(1600 * 1200, 7), dst(src.size());
    for (auto _ : state) {
        std::memcpy(dst.data(), src.data(), src.size());
        benchmark::DoNotOptimize(dst.data());
        benchmark::ClobberMemory();
    }
}

void BM_GeometryPerPose(benchmark::State& state, const char* scene) {
    const auto rig = fpp::sim::Rig::paper();
    const auto s = fpp::sim::named_scene(scene);
    for (auto _ : state) {
        fpp::sim::Renderer r(rig, s, 1);
        benchmark::DoNotOptimize(r.truth_xyz().data());
    }
}

void BM_RenderFrame(benchmark::State& state, bool effects) {
    const auto rig = effects ? effects_rig() : fpp::sim::Rig::paper();
    fpp::sim::Renderer r(rig, fpp::sim::named_scene("plane"), 1);
    const auto pattern = fringe(rig);
    std::uint64_t seed = 0;
    for (auto _ : state) {
        auto frame = r.render(pattern, ++seed);
        benchmark::DoNotOptimize(frame.u8.data());
    }
}

BENCHMARK(BM_CopyFrame)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_GeometryPerPose, plane, "plane")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_GeometryPerPose, composite, "composite")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RenderFrame, effects_off, false)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RenderFrame, effects_on, true)->Unit(benchmark::kMillisecond);

} // namespace

BENCHMARK_MAIN();
