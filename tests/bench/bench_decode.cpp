// Decoding speed at the paper's camera resolution (1600x1200), against two
// baselines measured in the same run:
//   - a plain copy of the same input bytes (memory bandwidth), and
//   - OpenCV's structured_light PSP wrapped phase on the same 3-step frames.
// Prints the ratios at the end. Targets: fpp's 3-step wrapped phase at least
// 10x faster than OpenCV's PSP; full decode within 2x of the copy. Run with
// --benchmark_repetitions=N on a shared machine: the summary takes the best.

#include "fpp/decoder.hpp"
#include "fpp/patterns.hpp"
#include "fpp/simulator/renderer.hpp"
#include "fpp/simulator/rig.hpp"
#include "fpp/simulator/scene.hpp"

#include "best_time_reporter.hpp"

#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>
#include <opencv2/structured_light.hpp>

#include <cstdio>
#include <cstring>
#include <map>
#include <string>
#include <vector>

namespace {

// 8-step phase (period 20) + complementary Gray code (6 bits + 1), x axis.
fpp::Sequence full_sequence() {
    fpp::PhaseBlock phase;
    phase.axis = fpp::Axis::x;
    phase.period = 20.0;
    phase.steps = 8;
    fpp::GrayBlock gray;
    gray.axis = fpp::Axis::x;
    gray.period = 20.0;
    gray.bits = 6;
    gray.complementary = true;
    return {phase, gray};
}

// One period across the projector: decodes without unwrapping, so the work is
// the wrapped phase (plus its conversion to projector pixels), as OpenCV's PSP.
fpp::Sequence three_step_sequence() {
    fpp::PhaseBlock phase;
    phase.axis = fpp::Axis::x;
    phase.period = 1280.0;
    phase.steps = 3;
    return {phase};
}

// The fpp-capture/2 families, x axis, each with the code that unwraps it in
// practice (complementary Gray 6 + 1 bits at period 20 for the phase ones).
fpp::GrayBlock complementary_gray_20() {
    fpp::GrayBlock gray;
    gray.axis = fpp::Axis::x;
    gray.period = 20.0;
    gray.bits = 6;
    gray.complementary = true;
    return gray;
}

fpp::Sequence family_sequence(const std::string& name) {
    if (name == "gray_code_10bit_inverse") {
        fpp::GrayBlock gray;
        gray.axis = fpp::Axis::x;
        gray.period = 1.25;
        gray.bits = 10;
        gray.inverse = true;
        return {gray};
    }
    if (name == "natural_binary_10bit_wb") {
        fpp::GrayBlock binary;
        binary.axis = fpp::Axis::x;
        binary.period = 1.25;
        binary.bits = 10;
        binary.code = fpp::CodeKind::binary;
        return {fpp::WhiteBlock{}, fpp::BlackBlock{}, binary};
    }
    if (name == "micro_5_periods") {
        fpp::MicroPhaseBlock micro;
        micro.axis = fpp::Axis::x;
        for (int j : {0, 1, 11, 16, 19})
            micro.periods.push_back(1.0 / (1.0 / 16.0 - j / 1400.0));
        return {micro};
    }
    fpp::PhaseBlock phase;
    phase.axis = fpp::Axis::x;
    phase.period = 20.0;
    phase.steps = 3;
    if (name == "two_plus_one_gray") {
        phase.shifting = fpp::PhaseShifting::two_plus_one;
    } else { // modulated_3x3_gray
        phase.shifting = fpp::PhaseShifting::modulated;
        phase.carrier_steps = 3;
        phase.carrier_period = 8.0;
    }
    return {phase, complementary_gray_20()};
}

const std::vector<std::string>& family_names() {
    static const std::vector<std::string> names = {"gray_code_10bit_inverse",
                                                   "natural_binary_10bit_wb", "micro_5_periods",
                                                   "two_plus_one_gray", "modulated_3x3_gray"};
    return names;
}

struct Fixture {
    fpp::CaptureSet full;
    fpp::CaptureSet three;
    std::size_t full_bytes = 0;
    std::map<std::string, fpp::CaptureSet> families;
    std::map<std::string, std::size_t> family_bytes;

    static const Fixture& get() {
        static const Fixture f;
        return f;
    }

private:
    static fpp::CaptureSet make(const fpp::Sequence& sequence) {
        const fpp::sim::Rig rig = fpp::sim::Rig::paper();
        const fpp::sim::SimulatedCapture sim =
            fpp::sim::simulate(rig, fpp::sim::named_scene("plane"), sequence, 1);
        fpp::CaptureSet set;
        set.manifest = sim.manifest;
        set.frames = sim.frames;
        return set;
    }
    Fixture() : full(make(full_sequence())), three(make(three_step_sequence())) {
        for (const auto& f : full.frames)
            full_bytes += f.u8.pixel_count();
        for (const auto& name : family_names()) {
            families[name] = make(family_sequence(name));
            for (const auto& f : families[name].frames)
                family_bytes[name] += f.u8.pixel_count();
        }
    }
};

void BM_CopyInput(benchmark::State& state) {
    const auto& fx = Fixture::get();
    std::vector<std::uint8_t> dst(fx.full_bytes);
    for (auto _ : state) {
        std::size_t offset = 0;
        for (const auto& f : fx.full.frames) {
            std::memcpy(dst.data() + offset, f.u8.data(), f.u8.pixel_count());
            offset += f.u8.pixel_count();
        }
        benchmark::DoNotOptimize(dst.data());
        benchmark::ClobberMemory();
    }
    state.SetBytesProcessed(std::int64_t(state.iterations()) * std::int64_t(fx.full_bytes));
}

void BM_DecodeBatch(benchmark::State& state) {
    const auto& fx = Fixture::get();
    for (auto _ : state) {
        auto result = fpp::decode(fx.full);
        benchmark::DoNotOptimize(result.proj_x.data());
    }
    state.SetBytesProcessed(std::int64_t(state.iterations()) * std::int64_t(fx.full_bytes));
}

// The same on one thread, for boards with fewer free cores than this machine.
void BM_DecodeBatchOneThread(benchmark::State& state) {
    const auto& fx = Fixture::get();
    fpp::DecodeOptions options;
    options.threads = 1;
    for (auto _ : state) {
        auto result = fpp::decode(fx.full, options);
        benchmark::DoNotOptimize(result.proj_x.data());
    }
    state.SetBytesProcessed(std::int64_t(state.iterations()) * std::int64_t(fx.full_bytes));
}

// Scan after scan into the same result: no page faults or zero-filling of
// fresh output images (about 25 MB at this size).
void BM_DecodeBatchReuse(benchmark::State& state) {
    const auto& fx = Fixture::get();
    fpp::DecodeResult result = fpp::decode(fx.full);
    for (auto _ : state) {
        fpp::decode(fx.full, result);
        benchmark::DoNotOptimize(result.proj_x.data());
    }
    state.SetBytesProcessed(std::int64_t(state.iterations()) * std::int64_t(fx.full_bytes));
}

void BM_StreamingPushPerFrame(benchmark::State& state) {
    const auto& fx = Fixture::get();
    const auto& m = fx.full.manifest;
    const int frames = int(fx.full.frames.size());
    for (auto _ : state) {
        state.PauseTiming();
        fpp::StreamingDecoder decoder(m.sequence, m.camera, m.projector);
        state.ResumeTiming();
        for (const auto& f : fx.full.frames)
            decoder.push(f);
        state.PauseTiming();
        auto result = decoder.finish();
        benchmark::DoNotOptimize(result.proj_x.data());
        state.ResumeTiming();
    }
    // Report the time of one push.
    state.counters["frames"] = frames;
    state.SetItemsProcessed(std::int64_t(state.iterations()) * frames);
}

void BM_StreamingFinish(benchmark::State& state) {
    const auto& fx = Fixture::get();
    const auto& m = fx.full.manifest;
    for (auto _ : state) {
        state.PauseTiming();
        fpp::StreamingDecoder decoder(m.sequence, m.camera, m.projector);
        for (const auto& f : fx.full.frames)
            decoder.push(f);
        state.ResumeTiming();
        auto result = decoder.finish();
        benchmark::DoNotOptimize(result.proj_x.data());
    }
}

void BM_Fpp3StepWrappedPhase(benchmark::State& state) {
    const auto& fx = Fixture::get();
    for (auto _ : state) {
        auto result = fpp::decode(fx.three);
        benchmark::DoNotOptimize(result.proj_x.data());
    }
}

void BM_OpenCV3StepPSP(benchmark::State& state) {
    const auto& fx = Fixture::get();
    const auto& m = fx.three.manifest;
    auto params = cv::makePtr<cv::structured_light::SinusoidalPattern::Params>();
    params->width = m.projector.width;
    params->height = m.projector.height;
    params->nbrOfPeriods = 1;
    params->shiftValue = static_cast<float>(2 * CV_PI / 3);
    params->methodId = cv::structured_light::PSP;
    params->horizontal = false;
    params->setMarkers = false;
    auto psp = cv::structured_light::SinusoidalPattern::create(params);
    std::vector<cv::Mat> frames;
    for (const auto& f : fx.three.frames)
        frames.emplace_back(f.u8.height(), f.u8.width(), CV_8UC1,
                            const_cast<std::uint8_t*>(f.u8.data()));
    cv::Mat wrapped, shadow;
    for (auto _ : state) {
        psp->computePhaseMap(frames, wrapped, shadow);
        benchmark::DoNotOptimize(wrapped.data);
    }
}

// Batch decode of one family's capture (the name after the slash).
void BM_DecodeFamily(benchmark::State& state, const std::string& name) {
    const auto& fx = Fixture::get();
    const fpp::CaptureSet& set = fx.families.at(name);
    fpp::DecodeResult result = fpp::decode(set);
    for (auto _ : state) {
        fpp::decode(set, result);
        benchmark::DoNotOptimize(result.proj_x.data());
    }
    state.SetBytesProcessed(std::int64_t(state.iterations()) *
                            std::int64_t(fx.family_bytes.at(name)));
}

// The micro phase capture with every fringe order scored at every pixel: the
// baseline the default (windowed) search is measured against.
void BM_DecodeMicroEveryOrder(benchmark::State& state) {
    const fpp::CaptureSet& set = Fixture::get().families.at("micro_5_periods");
    fpp::DecodeOptions options;
    options.micro_every_order = true;
    fpp::DecodeResult result = fpp::decode(set, options);
    for (auto _ : state) {
        fpp::decode(set, result, options);
        benchmark::DoNotOptimize(result.proj_x.data());
    }
}

BENCHMARK_CAPTURE(BM_DecodeFamily, gray_code_10bit_inverse, std::string("gray_code_10bit_inverse"))
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_DecodeFamily, natural_binary_10bit_wb, std::string("natural_binary_10bit_wb"))
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_DecodeFamily, micro_5_periods, std::string("micro_5_periods"))
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_DecodeFamily, two_plus_one_gray, std::string("two_plus_one_gray"))
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_DecodeFamily, modulated_3x3_gray, std::string("modulated_3x3_gray"))
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_DecodeMicroEveryOrder)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_CopyInput)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_DecodeBatch)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_DecodeBatchOneThread)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_DecodeBatchReuse)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_StreamingPushPerFrame)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_StreamingFinish)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Fpp3StepWrappedPhase)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_OpenCV3StepPSP)->Unit(benchmark::kMillisecond)->UseRealTime();

} // namespace

int main(int argc, char** argv) {
    fpp::bench::BestTimeReporter reporter;
    if (!fpp::bench::run_benchmarks(argc, argv, reporter))
        return 1;

    const double copy = reporter.seconds("BM_CopyInput");
    const double batch = reporter.seconds("BM_DecodeBatch");
    const double one = reporter.seconds("BM_DecodeBatchOneThread");
    const double reuse = reporter.seconds("BM_DecodeBatchReuse");
    const double pushes = reporter.seconds("BM_StreamingPushPerFrame");
    const double finish = reporter.seconds("BM_StreamingFinish");
    const double fpp3 = reporter.seconds("BM_Fpp3StepWrappedPhase");
    const double cv3 = reporter.seconds("BM_OpenCV3StepPSP");
    const int frames = int(Fixture::get().full.frames.size());
    std::printf("\nsummary (1600x1200, 8-step phase + complementary Gray, %d frames, 8-bit;"
                " best of the repetitions)\n",
                frames);
    if (copy > 0 && batch > 0)
        std::printf("  full decode / copy of input : %.2f (target <= 2)  [%.2f ms vs %.2f ms]\n",
                    batch / copy, batch * 1e3, copy * 1e3);
    if (copy > 0 && one > 0)
        std::printf("  same, on one thread         : %.2f              [%.2f ms]\n", one / copy,
                    one * 1e3);
    if (copy > 0 && reuse > 0)
        std::printf("  same, reusing the result    : %.2f              [%.2f ms]\n", reuse / copy,
                    reuse * 1e3);
    if (pushes > 0)
        std::printf("  streaming push per frame    : %.2f ms; finish %.2f ms\n",
                    pushes * 1e3 / frames, finish * 1e3);
    if (fpp3 > 0 && cv3 > 0)
        std::printf("  OpenCV PSP / fpp, 3-step    : %.1fx (target >= 10)  [%.2f ms vs %.2f ms]\n",
                    cv3 / fpp3, cv3 * 1e3, fpp3 * 1e3);
    // Each family against a copy of its own input bytes, scaled from the
    // copy measured above (same run, same memory system).
    const Fixture& fx = Fixture::get();
    for (const auto& name : family_names()) {
        const double t = reporter.seconds("BM_DecodeFamily/" + name + "/real_time");
        const double bytes = double(fx.family_bytes.at(name));
        const double family_copy = copy * bytes / double(fx.full_bytes);
        if (t > 0 && family_copy > 0)
            std::printf("  %-27s : %.2f x copy of its %zu frames  [%.2f ms vs %.2f ms]\n",
                        name.c_str(), t / family_copy, fx.families.at(name).frames.size(), t * 1e3,
                        family_copy * 1e3);
    }
    const double micro = reporter.seconds("BM_DecodeFamily/micro_5_periods/real_time");
    const double micro_every = reporter.seconds("BM_DecodeMicroEveryOrder/real_time");
    if (micro > 0 && micro_every > 0)
        std::printf("  micro, every order / default: %.2fx  [%.2f ms vs %.2f ms]\n",
                    micro_every / micro, micro_every * 1e3, micro * 1e3);
    return 0;
}
