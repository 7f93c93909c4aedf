// Speed and memory of a whole scan on the virtual scanner at full size: the
// paper rig with its effects (1600x1200 Mono8 camera, 1280x800 projector,
// sequence gray-x: 17 frames), a rational table made from the rig's true
// geometry, Scanner::scan(ScanMode::scan) on the virtual clock so that the
// 60 Hz flips cost no wall time. Each iteration is one scan; its wall time is
// dominated by the simulator rendering the frames, which is not part of the
// scanner's own timings reported as counters (ScanTimings, ms):
//   push_mean / push_max    streaming decoder work per frame (target < 4 ms:
//                           it must fit inside one 60 Hz pattern)
//   finish, apply, write    last decode step, table kernel, outputs fsynced
//   last_frame_to_disk      last frame received to PLY on disk (target < 50 ms)
// Baselines measured in the same run: a memcpy of one frame, and a memcpy
// plus an fsynced write of a new file of the scan's PLY size (the summary
// sets the spread of its runs beside that of the scans' last frame to disk:
// a slow disk write shows in both). Parts: the
// streaming decoder frame by frame on the scan's frames (which frame costs
// what), encode_ply alone (the PLY encoded into one buffer) and
// write_ply_synced alone (encoded piece by piece as it is written, fsynced:
// the scanner's write of the PLY).
// Memory: the peak RSS (getrusage ru_maxrss) growth across a scan, the peak
// being reset before each scan (/proc/self/clear_refs; the RSS is also
// sampled at each flip event, i.e. during the capture), against the table's
// bytes and what the streaming decoder holds (frames of one phase block,
// its state planes and its result images).
// Run with --benchmark_repetitions=N on a shared machine: the summary lists
// every scan, and takes the best of the repetitions for the baselines.

#include "fpp/coefficient_table.hpp"
#include "fpp/decoder.hpp"
#include "fpp/lens_model.hpp"
#include "fpp/parallel.hpp"
#include "fpp/patterns.hpp"
#include "fpp/point_cloud.hpp"
#include "fpp/scanner/board_config.hpp"
#include "fpp/scanner/scanner.hpp"
#include "fpp/scanner/sim_board.hpp"
#include "fpp/simulator/renderer.hpp"
#include "fpp/simulator/rig.hpp"
#include "fpp/table_kernel.hpp"

#include "best_time_reporter.hpp"

#include "rig_truth_table.hpp"
#include "sim_board_yaml.hpp"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include <fcntl.h>
#include <malloc.h>
#include <sys/resource.h>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;
using fpp::scanner::ScanOutcome;

constexpr double kMiB = 1024.0 * 1024.0;

// --- memory probes -----------------------------------------------------------

// Peak resident set of the process, bytes (ru_maxrss is in KiB on Linux).
double peak_rss_bytes() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return static_cast<double>(usage.ru_maxrss) * 1024.0;
}

// Current resident set, bytes.
double current_rss_bytes() {
    std::ifstream statm("/proc/self/statm");
    long pages_total = 0;
    long pages_resident = 0;
    statm >> pages_total >> pages_resident;
    return static_cast<double>(pages_resident) * static_cast<double>(::sysconf(_SC_PAGESIZE));
}

// Resets the peak RSS to the current RSS (Linux >= 4.0); false if refused.
bool reset_peak_rss() {
    std::ofstream clear("/proc/self/clear_refs");
    clear << "5";
    clear.flush();
    return clear.good();
}

// Heap bytes in use (glibc: arenas plus mmapped blocks).
double heap_in_use_bytes() {
    const struct mallinfo2 info = ::mallinfo2();
    return static_cast<double>(info.uordblks) + static_cast<double>(info.hblkhd);
}

// --- the rig's table ---------------------------------------------------------

std::size_t table_bytes(const fpp::TableInfo& info) {
    return static_cast<std::size_t>(info.tile_count()) *
           static_cast<std::size_t>(fpp::table_planes(info.model)) *
           static_cast<std::size_t>(info.tile_pixels()) * sizeof(float);
}

// --- the board -------------------------------------------------------------

// A sim board in a temporary folder under /tmp: the board file, the table
// and the scan store (pruned to 1 MiB: only the newest scan stays).
struct Board {
    fs::path dir;
    fs::path store;
    fs::path table_file;
    fpp::scanner::BoardConfig config;

    // `extra`: more board file lines (the HDR board's `hdr:`).
    explicit Board(const std::string& extra = "") {
        std::string name = (fs::temp_directory_path() / "fpp-bench-scanner-XXXXXX").string();
        if (::mkdtemp(name.data()) == nullptr)
            throw std::runtime_error("cannot create a temporary folder " + name);
        dir = name;
        store = dir / "scans";
        table_file = dir / "table.fpt";
        const fs::path board_file = dir / "board.yaml";
        fpp::test::SimBoardYaml yaml;
        yaml.name = "bench-sim";
        yaml.store = store;
        yaml.table = "table.fpt";
        yaml.max_mb = 1;
        yaml.binning = 1;
        yaml.seed = 1;
        yaml.frame_timeout_ms = 500;
        yaml.extra = extra;
        std::ofstream(board_file) << yaml.text();
        config = fpp::scanner::read_board_config(board_file);
    }
    ~Board() {
        std::error_code ec;
        fs::remove_all(dir, ec);
    }
    Board(const Board&) = delete;
    Board& operator=(const Board&) = delete;
};

// What one scan gave.
struct ScanRecord {
    fpp::scanner::ScanTimings timings;
    std::size_t points = 0;
    double ply_bytes = 0;
    double rss_before = 0;         // bytes, just before the scan
    double rss_peak_growth = 0;    // bytes, peak during the scan above rss_before
    double rss_capture_growth = 0; // bytes, largest RSS at a flip event above rss_before
};

struct Context {
    explicit Context(const std::string& extra = "") : board(extra) {}
    Board board;
    fpp::scanner::Logger log{[](fpp::scanner::LogLevel level, const std::string& message) {
        if (level <= fpp::scanner::LogLevel::warning)
            std::fprintf(stderr, "scanner: %s\n", message.c_str());
    }};
    std::unique_ptr<fpp::scanner::SimBoard> sim;
    std::unique_ptr<fpp::scanner::Scanner> scanner;
    fpp::TableInfo table_info;
    bool peak_reset = false;
    std::vector<ScanRecord> scans; // every benchmark iteration, in order

    double rss_at_flips = 0; // largest current RSS seen at a flip event of this scan

    // Samples the RSS at each flip event, during the capture (outside the
    // decoder's timed work).
    void watch_capture() {
        sim->display().on_flip([this](const fpp::drivers::FlipEvent&) {
            rss_at_flips = std::max(rss_at_flips, current_rss_bytes());
        });
    }

    ScanRecord scan() {
        ScanRecord r;
        peak_reset = reset_peak_rss();
        r.rss_before = peak_reset ? peak_rss_bytes() : current_rss_bytes();
        rss_at_flips = r.rss_before;
        const ScanOutcome out = scanner->scan(fpp::scanner::ScanMode::scan);
        r.rss_peak_growth = peak_rss_bytes() - r.rss_before;
        r.rss_capture_growth = rss_at_flips - r.rss_before;
        r.timings = out.timings;
        r.points = out.points;
        r.ply_bytes = static_cast<double>(fs::file_size(out.folder / "cloud.ply"));
        return r;
    }
};

Context* g_context = nullptr;
double g_ply_bytes = 0; // PLY size of the warm-up scan, for the file baseline

void scan(benchmark::State& state) {
    Context& cx = *g_context;
    ScanRecord last;
    double push_mean = 0, push_max = 0, finish = 0, apply = 0, write = 0, to_disk = 0;
    double growth = 0;
    for (auto _ : state) {
        last = cx.scan();
        if (last.points == 0) {
            state.SkipWithError("the scan gave no points");
            return;
        }
        cx.scans.push_back(last);
        push_mean += last.timings.push_mean_ms;
        push_max = std::max(push_max, last.timings.push_max_ms);
        finish += last.timings.finish_ms;
        apply += last.timings.apply_ms;
        write += last.timings.write_ms;
        to_disk += last.timings.last_frame_to_written_ms;
        growth = std::max(growth, last.rss_peak_growth);
    }
    // Means over the iterations (push_max and the RSS growth: their maximum).
    const double n = static_cast<double>(state.iterations());
    state.counters["push_mean_ms"] = push_mean / n;
    state.counters["push_max_ms"] = push_max;
    state.counters["finish_ms"] = finish / n;
    state.counters["apply_ms"] = apply / n;
    state.counters["write_ms"] = write / n;
    state.counters["last_frame_to_written_ms"] = to_disk / n;
    state.counters["points"] = static_cast<double>(last.points);
    state.counters["rss_growth_MiB"] = growth / kMiB;
}

// The HDR board: the same scene, table and sequence, four passes.
constexpr const char* kHdrExposures = "256000, 32000, 8000, 1000";
std::unique_ptr<Context> g_hdr_context;
std::vector<ScanRecord> g_hdr_scans;

// The HDR board: the same scene, table and sequence with four exposures,
// built when its benchmark first runs (after the single scan's, so that the
// memory figures stay the single scan's); its first scan allocates the
// passes' images.
Context& hdr_context() {
    if (!g_hdr_context) {
        g_hdr_context = std::make_unique<Context>(std::string("hdr: {exposures_us: [") +
                                                  kHdrExposures + "]}\n");
        Context& cx = *g_hdr_context;
        fs::copy_file(g_context->board.table_file, cx.board.table_file);
        cx.sim = std::make_unique<fpp::scanner::SimBoard>(cx.board.config);
        cx.scanner =
            std::make_unique<fpp::scanner::Scanner>(cx.board.config, cx.sim->devices(), cx.log);
        (void)cx.scan();
    }
    return *g_hdr_context;
}

// What the scanner itself spends on a scan, ms: the capture on the scan
// clock (flips, settle, exposures: virtual here, as long as on hardware)
// and its own work after the last frame.
double scanner_ms(const ScanRecord& r) {
    return r.timings.capture_ms + r.timings.last_frame_to_written_ms;
}

void scan_hdr(benchmark::State& state) {
    Context& cx = hdr_context();
    double push_mean = 0, push_max = 0, fuse = 0, total = 0;
    for (auto _ : state) {
        const ScanRecord r = cx.scan();
        g_hdr_scans.push_back(r);
        push_mean += r.timings.push_mean_ms;
        push_max = std::max(push_max, r.timings.push_max_ms);
        fuse += r.timings.fuse_ms;
        total += scanner_ms(r);
    }
    const double n = static_cast<double>(state.iterations());
    state.counters["push_mean_ms"] = push_mean / n;
    state.counters["push_max_ms"] = push_max;
    state.counters["fuse_ms"] = fuse / n;
    state.counters["scanner_ms"] = total / n;
}

// One camera frame copied.
void memcpy_frame(benchmark::State& state) {
    const fpp::Size size = g_context->sim->camera().size();
    const std::size_t bytes = size.area();
    std::vector<unsigned char> src(bytes, 1), dst(bytes, 0);
    for (auto _ : state) {
        std::memcpy(dst.data(), src.data(), bytes);
        benchmark::DoNotOptimize(dst.data());
        benchmark::ClobberMemory();
    }
    state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) *
                            static_cast<std::int64_t>(bytes));
}

// Every iteration of write_fsync_ply_size, over all its runs (ms): the spread
// of the file baseline, to set beside the spread of the scans' last frame to
// disk measured in the same run.
std::vector<double> g_file_baseline_ms;

// The PLY's bytes copied into a buffer, then written to a new file in the
// store's folder and fsynced (the file is removed outside the timing).
void write_fsync_ply_size(benchmark::State& state) {
    const auto bytes = static_cast<std::size_t>(g_ply_bytes);
    std::vector<char> src(bytes, 'x'), dst(bytes, 0);
    const fs::path path = g_context->board.dir / "baseline.bin";
    for (auto _ : state) {
        const auto t0 = std::chrono::steady_clock::now();
        std::memcpy(dst.data(), src.data(), bytes);
        const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
        if (fd < 0) {
            state.SkipWithError("cannot create the baseline file");
            return;
        }
        std::size_t done = 0;
        while (done < bytes) {
            const ssize_t n = ::write(fd, dst.data() + done, bytes - done);
            if (n <= 0)
                break;
            done += static_cast<std::size_t>(n);
        }
        const bool ok = done == bytes && ::fsync(fd) == 0;
        ::close(fd);
        g_file_baseline_ms.push_back(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                .count());
        state.PauseTiming();
        ::unlink(path.c_str());
        state.ResumeTiming();
        if (!ok) {
            state.SkipWithError("baseline write failed");
            return;
        }
    }
    state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) *
                            static_cast<std::int64_t>(bytes));
}

// The frames of one scan, rendered once (pattern i on screen for frame i),
// and what decoding them gives: for the per-frame decoder profile and the
// PLY encoding below.
struct Frames {
    std::vector<fpp::Frame> frames;
    fpp::DecodeResult decoded;

    static Frames& get() {
        static Frames f = [] {
            Frames made;
            auto& sim = *g_context->sim;
            // The sequence's patterns only: the display also holds the
            // preview's white pattern after them.
            const auto count = static_cast<std::size_t>(g_context->scanner->frames_per_scan());
            for (std::size_t i = 0; i < count; ++i)
                made.frames.push_back(
                    sim.renderer().render(sim.display().pattern(i),
                                          fpp::sim::Renderer::frame_seed(1, static_cast<int>(i))));
            fpp::StreamingDecoder decoder(g_context->scanner->sequence(), sim.camera().size(),
                                          sim.display().size());
            for (const fpp::Frame& frame : made.frames)
                decoder.push(frame);
            made.decoded = decoder.finish();
            return made;
        }();
        return f;
    }
};

// Streaming decoder work frame by frame on real frames, as in the scanner
// (all threads, one decoder restarted scan after scan, result images
// recycled). Every sample is kept, per frame
// index, over all runs of this benchmark (repetitions included); counters:
// the frame with the slowest median, its best and median time (ms).
std::vector<std::vector<double>> g_push_samples_ms;

double median(std::vector<double> v) {
    if (v.empty())
        return 0.0;
    const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return *mid;
}

void push_per_frame(benchmark::State& state) {
    Frames& fx = Frames::get();
    const fpp::Size camera = g_context->sim->camera().size();
    const fpp::Size projector = g_context->sim->display().size();
    const fpp::Sequence& sequence = g_context->scanner->sequence();
    g_push_samples_ms.resize(fx.frames.size());
    fpp::StreamingDecoder decoder(sequence, camera, projector);
    for (auto _ : state) {
        decoder.restart(std::move(fx.decoded));
        for (std::size_t i = 0; i < fx.frames.size(); ++i) {
            const auto t0 = std::chrono::steady_clock::now();
            decoder.push(fx.frames[i]);
            g_push_samples_ms[i].push_back(
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                    .count());
        }
        fx.decoded = decoder.finish();
    }
    std::size_t slowest = 0;
    double slowest_median = 0;
    for (std::size_t i = 0; i < g_push_samples_ms.size(); ++i) {
        const double m = median(g_push_samples_ms[i]);
        if (m > slowest_median) {
            slowest_median = m;
            slowest = i;
        }
    }
    state.counters["slowest_frame"] = static_cast<double>(slowest);
    state.counters["slowest_median_ms"] = slowest_median;
    state.counters["slowest_best_ms"] =
        *std::min_element(g_push_samples_ms[slowest].begin(), g_push_samples_ms[slowest].end());
}

// The cloud of the decoded scan, with its B and A, as the scanner writes it.
fpp::PointCloud scan_cloud() {
    Frames& fx = Frames::get();
    const fpp::Size camera = g_context->sim->camera().size();
    const fpp::CoefficientTable table = fpp::load_table(g_context->board.table_file, &camera);
    fpp::PointCloud cloud;
    fpp::apply_table(table, fx.decoded.proj_x, cloud);
    cloud.quality = fx.decoded.modulation;
    cloud.intensity = fx.decoded.mean;
    return cloud;
}

// The CPU part of writing the PLY: the decoded scan's cloud encoded to bytes.
void encode_ply_bytes(benchmark::State& state) {
    const fpp::PointCloud cloud = scan_cloud();
    std::size_t bytes = 0;
    for (auto _ : state) {
        const std::string ply = fpp::encode_ply(cloud, {"bench"});
        bytes = ply.size();
        benchmark::DoNotOptimize(ply.data());
    }
    state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) *
                            static_cast<std::int64_t>(bytes));
}

// The scanner's write of the PLY alone: the decoded scan's cloud encoded and
// written piece by piece to a new file in the store's folder, fsynced (the
// file is removed outside the timing).
void write_ply_file(benchmark::State& state) {
    const fpp::PointCloud cloud = scan_cloud();
    const fs::path path = g_context->board.dir / "part.ply";
    for (auto _ : state) {
        fpp::write_ply_synced(path, cloud, {"bench"});
        state.PauseTiming();
        fs::remove(path);
        state.ResumeTiming();
    }
}

// The table kernel on the scan's phase: into a fresh cloud as the scanner
// does, its 3-channel image either handed back by the allocator warm (a
// tight loop) or fresh from the OS (free memory returned first with
// malloc_trim, outside the timing: page faults and zero-fill, as after the
// scan's other large buffers), or into a reused cloud.
enum class CloudKind { fresh_warm, fresh_from_os, reused };

void apply_table_cloud(benchmark::State& state, CloudKind kind) {
    Frames& fx = Frames::get();
    const fpp::Size camera = g_context->sim->camera().size();
    const fpp::CoefficientTable table = fpp::load_table(g_context->board.table_file, &camera);
    fpp::PointCloud reused;
    std::size_t points = fpp::apply_table(table, fx.decoded.proj_x, reused).points;
    for (auto _ : state) {
        if (kind == CloudKind::fresh_from_os) {
            state.PauseTiming();
            ::malloc_trim(0);
            state.ResumeTiming();
        }
        if (kind != CloudKind::reused) {
            fpp::PointCloud cloud;
            points = fpp::apply_table(table, fx.decoded.proj_x, cloud).points;
            benchmark::DoNotOptimize(cloud.xyz.data());
        } else {
            points = fpp::apply_table(table, fx.decoded.proj_x, reused).points;
            benchmark::DoNotOptimize(reused.xyz.data());
        }
    }
    state.counters["points"] = static_cast<double>(points);
}

// Heap held by a streaming decoder of this board's sequence, frame by frame,
// with recycled result images as in the scanner (bytes).
struct DecoderHeap {
    double at_construction = 0; // state planes (result images recycled)
    double peak = 0;            // at most: planes + the frames of one phase block
    double result_images = 0;   // proj_x, modulation, mean, mask (kept scan to scan)
};

DecoderHeap measure_decoder_heap(const fpp::Sequence& sequence, fpp::Size camera,
                                 fpp::Size projector) {
    fpp::Frame frame;
    frame.bit_depth = 8;
    frame.u8 = fpp::Image<std::uint8_t>(camera);
    auto run = [&](fpp::DecodeResult&& recycled, DecoderHeap* heap) {
        const double before = heap_in_use_bytes();
        fpp::StreamingDecoder decoder(sequence, camera, projector, fpp::DecodeOptions{},
                                      std::move(recycled));
        if (heap != nullptr)
            heap->at_construction = heap_in_use_bytes() - before;
        for (int i = 0; i < decoder.frames_expected(); ++i) {
            decoder.push(frame);
            if (heap != nullptr)
                heap->peak = std::max(heap->peak, heap_in_use_bytes() - before);
        }
        return decoder.finish();
    };
    const double before_first = heap_in_use_bytes();
    fpp::DecodeResult first = run(fpp::DecodeResult{}, nullptr);
    DecoderHeap heap;
    heap.result_images = heap_in_use_bytes() - before_first;
    fpp::DecodeResult second = run(std::move(first), &heap);
    benchmark::DoNotOptimize(second.proj_x.data());
    return heap;
}

// Frames the streaming decoder keeps: those of its longest phase block (a
// block is decoded in slices from its last frame on, so all its frames wait
// in slots until the last slice).
int frames_held(const fpp::Sequence& sequence) {
    int steps = 0;
    for (const auto& block : sequence)
        if (const auto* phase = std::get_if<fpp::PhaseBlock>(&block))
            steps = std::max(steps, phase->steps);
    return steps;
}

// Best, median and worst of a series of times (ms), and how many are over
// the 50 ms target.
void print_spread(const char* label, const std::vector<double>& ms) {
    if (ms.empty())
        return;
    const auto over = std::count_if(ms.begin(), ms.end(), [](double t) { return t >= 50.0; });
    std::printf("  %s over %zu runs: best %.1f, median %.1f, worst %.1f ms; %td of %zu at "
                "50 ms or more\n",
                label, ms.size(), *std::min_element(ms.begin(), ms.end()), median(ms),
                *std::max_element(ms.begin(), ms.end()), over, ms.size());
}

void print_row(const char* label, const ScanRecord& r) {
    std::printf("  %-8s push mean %5.2f max %5.2f | finish %6.2f apply %6.2f write %6.2f | "
                "last frame to disk %6.1f ms | %zu points, PLY %.1f MB | RSS %.0f MiB, peak +%.1f "
                "(capture +%.1f) MiB\n",
                label, r.timings.push_mean_ms, r.timings.push_max_ms, r.timings.finish_ms,
                r.timings.apply_ms, r.timings.write_ms, r.timings.last_frame_to_written_ms,
                r.points, r.ply_bytes / 1e6, r.rss_before / kMiB, r.rss_peak_growth / kMiB,
                r.rss_capture_growth / kMiB);
}

// Resident memory (bytes) at the steps of setting up, before any scan.
struct SetupMemory {
    double start = 0, with_sim = 0, with_scanner = 0, peak = 0;
};

void register_benchmarks() {
    const auto in_ms = [](benchmark::internal::Benchmark* b) {
        return b->Unit(benchmark::kMillisecond)->UseRealTime();
    };
    in_ms(benchmark::RegisterBenchmark("scan/1600x1200_gray-x", scan))->Iterations(3);
    in_ms(benchmark::RegisterBenchmark("baseline/memcpy_frame", memcpy_frame));
    in_ms(
        benchmark::RegisterBenchmark("baseline/memcpy_write_fsync_ply_size", write_fsync_ply_size));
    in_ms(benchmark::RegisterBenchmark("parts/push_per_frame", push_per_frame))->Iterations(20);
    in_ms(benchmark::RegisterBenchmark("parts/encode_ply", encode_ply_bytes));
    in_ms(benchmark::RegisterBenchmark("parts/write_ply_synced", write_ply_file));
    for (const auto& [name, kind] :
         {std::pair{"parts/apply_table/fresh_cloud_warm", CloudKind::fresh_warm},
          std::pair{"parts/apply_table/fresh_cloud_from_os", CloudKind::fresh_from_os},
          std::pair{"parts/apply_table/reused_cloud", CloudKind::reused}})
        in_ms(benchmark::RegisterBenchmark(name, apply_table_cloud, kind));
    in_ms(benchmark::RegisterBenchmark("scan_hdr/1600x1200_gray-x_4_exposures", scan_hdr))
        ->Iterations(2);
}

// The timing targets over the warm scans (at least one), against the
// baselines measured in the same run.
void print_targets(Context& context, const fpp::bench::BestTimeReporter& reporter) {
    double push_mean = 0, push_max = 0, to_disk_worst = 0, write = 0, to_disk = 0;
    for (const ScanRecord& r : context.scans) {
        push_mean += r.timings.push_mean_ms;
        push_max = std::max(push_max, r.timings.push_max_ms);
        write += r.timings.write_ms;
        to_disk += r.timings.last_frame_to_written_ms;
        to_disk_worst = std::max(to_disk_worst, r.timings.last_frame_to_written_ms);
    }
    const double n = static_cast<double>(context.scans.size());
    push_mean /= n;
    write /= n;
    to_disk /= n;
    const double copy = 1e3 * reporter.seconds("baseline/memcpy_frame");
    const double file = 1e3 * reporter.seconds("baseline/memcpy_write_fsync_ply_size");
    const double encode = 1e3 * reporter.seconds("parts/encode_ply");
    const double write_ply = 1e3 * reporter.seconds("parts/write_ply_synced");
    const double apply_warm = 1e3 * reporter.seconds("parts/apply_table/fresh_cloud_warm");
    const double apply_os = 1e3 * reporter.seconds("parts/apply_table/fresh_cloud_from_os");
    const double apply_reused = 1e3 * reporter.seconds("parts/apply_table/reused_cloud");
    std::printf("targets over %zu warm scans:\n", context.scans.size());
    std::printf("  push per frame: mean %.2f ms, max %.2f ms (target < 4: %s); "
                "memcpy of a frame %.3f ms -> mean %.1fx, max %.1fx the copy\n",
                push_mean, push_max, push_max < 4.0 ? "met" : "NOT met", copy,
                copy > 0 ? push_mean / copy : 0.0, copy > 0 ? push_max / copy : 0.0);
    if (!g_push_samples_ms.empty()) {
        std::printf("  push by frame over %zu decodes, best/median/worst ms:",
                    g_push_samples_ms[0].size());
        for (std::size_t i = 0; i < g_push_samples_ms.size(); ++i) {
            const auto& v = g_push_samples_ms[i];
            std::printf(" %zu:%.2f/%.2f/%.2f", i, *std::min_element(v.begin(), v.end()), median(v),
                        *std::max_element(v.begin(), v.end()));
        }
        std::printf("\n");
    }
    std::printf("  last frame to PLY on disk: mean %.1f ms, worst %.1f ms (target < 50: %s); "
                "write %.1f ms; memcpy + fsynced write of %.1f MB %.1f ms -> write %.2fx, "
                "last frame to disk %.2fx the baseline; encode_ply into one buffer alone "
                "%.1f ms; write_ply_synced alone %.1f ms (%.2fx the baseline)\n",
                to_disk, to_disk_worst, to_disk_worst < 50.0 ? "met" : "NOT met", write,
                g_ply_bytes / 1e6, file, file > 0 ? write / file : 0.0,
                file > 0 ? to_disk / file : 0.0, encode, write_ply,
                file > 0 ? write_ply / file : 0.0);
    std::vector<double> to_disk_ms;
    for (const ScanRecord& r : context.scans)
        to_disk_ms.push_back(r.timings.last_frame_to_written_ms);
    print_spread("last frame to disk", to_disk_ms);
    if (!g_hdr_scans.empty()) {
        double single = 0, hdr = 0, hdr_push_mean = 0, hdr_push_max = 0, fuse = 0, after = 0;
        for (const ScanRecord& r : context.scans)
            single += scanner_ms(r) / n;
        const double m = static_cast<double>(g_hdr_scans.size());
        for (const ScanRecord& r : g_hdr_scans) {
            hdr += scanner_ms(r) / m;
            hdr_push_mean += r.timings.push_mean_ms / m;
            hdr_push_max = std::max(hdr_push_max, r.timings.push_max_ms);
            fuse += r.timings.fuse_ms / m;
            after += r.timings.last_frame_to_written_ms / m;
        }
        std::printf("  HDR scan (%s us, %d frames): push per frame mean %.2f ms, max %.2f ms "
                    "(target < 4: %s); fusion %.1f ms; last frame to disk %.1f ms; the whole "
                    "scan on the scan clock %.0f ms against the single scan's %.0f ms (%.1fx: "
                    "the exposures and four times the frames)\n",
                    kHdrExposures, 4 * context.scanner->frames_per_scan(), hdr_push_mean,
                    hdr_push_max, hdr_push_max < 4.0 ? "met" : "NOT met", fuse, after, hdr, single,
                    single > 0 ? hdr / single : 0.0);
    }
    print_spread("baseline write", g_file_baseline_ms);
    std::printf("  apply_table alone: into a fresh cloud (as the scanner) %.1f ms when the "
                "allocator hands back warm memory, %.1f ms from the OS; into a reused one "
                "%.1f ms\n",
                apply_warm, apply_os, apply_reused);
}

// Where the memory goes: setting up, the table and the frames held, the
// decoder, the growth across a scan.
void print_memory(Context& context, const SetupMemory& setup, const ScanRecord& first) {
    const fpp::Size camera = context.sim->camera().size();
    const fpp::Size projector = context.sim->display().size();
    const fpp::Sequence& sequence = context.scanner->sequence();
    const double frame_bytes = static_cast<double>(camera.area()); // Mono8
    const int held = frames_held(sequence);
    const double table = static_cast<double>(table_bytes(context.table_info));
    const DecoderHeap decoder = measure_decoder_heap(sequence, camera, projector);

    double growth = 0;
    for (const ScanRecord& r : context.scans)
        growth = std::max(growth, r.rss_peak_growth);
    std::printf("memory (MiB; peak RSS from getrusage%s):\n",
                context.peak_reset ? ", reset before each scan" : ", NOT resettable here");
    std::printf("  RSS at start %.1f, with the sim board %.1f (+%.1f), with the scanner %.1f "
                "(+%.1f: table mapped and checked, patterns), peak so far %.1f\n",
                setup.start / kMiB, setup.with_sim / kMiB, (setup.with_sim - setup.start) / kMiB,
                setup.with_scanner / kMiB, (setup.with_scanner - setup.with_sim) / kMiB,
                setup.peak / kMiB);
    std::printf("  table %.1f; frames held by the streaming decoder: %d x %.2f = %.1f "
                "(one phase block); table + frames = %.1f\n",
                table / kMiB, held, frame_bytes / kMiB, held * frame_bytes / kMiB,
                (table + held * frame_bytes) / kMiB);
    std::printf("  decoder heap (measured): state planes %.1f, peak %.1f (planes + frames), "
                "result images kept scan to scan %.1f\n",
                decoder.at_construction / kMiB, decoder.peak / kMiB, decoder.result_images / kMiB);
    const double warm_peak = context.scans.back().rss_before + growth;
    std::printf("  peak RSS growth across a scan: first %.1f, warm scans up to %.1f; "
                "RSS before a warm scan %.1f, its peak %.1f\n",
                first.rss_peak_growth / kMiB, growth / kMiB, context.scans.back().rss_before / kMiB,
                warm_peak / kMiB);
    std::printf("  scanner's share of the peak (peak minus RSS with the sim board alone): "
                "%.1f = %.2fx table + frames\n",
                (warm_peak - setup.with_sim) / kMiB,
                (warm_peak - setup.with_sim) / (table + held * frame_bytes));
}

int run(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv))
        return 1;

    // The table is built and written before any measurement; its memory is
    // freed and the peak reset below.
    Context context;
    g_context = &context;
    {
        const fpp::sim::Rig rig = fpp::sim::load_rig(context.board.config.sim->rig);
        const fpp::CoefficientTable table = fpp::test::rig_truth_table(rig);
        context.table_info = table.info();
        fpp::write_table(context.board.table_file, table);
    }
    reset_peak_rss();
    SetupMemory setup;
    setup.start = current_rss_bytes();
    context.sim = std::make_unique<fpp::scanner::SimBoard>(context.board.config);
    setup.with_sim = current_rss_bytes();
    context.scanner = std::make_unique<fpp::scanner::Scanner>(context.board.config,
                                                              context.sim->devices(), context.log);
    context.watch_capture();
    setup.with_scanner = current_rss_bytes();
    setup.peak = peak_rss_bytes();

    // The first scan allocates the result images that later scans reuse.
    const ScanRecord first = context.scan();
    g_ply_bytes = first.ply_bytes;

    register_benchmarks();
    fpp::bench::BestTimeReporter reporter;
    benchmark::RunSpecifiedBenchmarks(&reporter);
    benchmark::Shutdown();

    const fpp::Size camera = context.sim->camera().size();
    const fpp::Size projector = context.sim->display().size();
    std::printf("\nsummary (%dx%d Mono8 camera, %dx%d projector, %d frames, %d threads; "
                "virtual clock)\n",
                camera.width, camera.height, projector.width, projector.height,
                context.scanner->frames_per_scan(), fpp::ThreadPool::resolve_threads(0));
    std::printf("scans (ms; RSS before the scan, its peak growth, and its largest growth "
                "sampled at the flips, i.e. during the capture):\n");
    print_row("first", first);
    for (std::size_t i = 0; i < context.scans.size(); ++i) {
        char label[24];
        std::snprintf(label, sizeof label, "#%zu", i + 1);
        print_row(label, context.scans[i]);
    }
    if (context.scans.empty())
        return 0;
    print_targets(context, reporter);
    g_hdr_context.reset();
    print_memory(context, setup, first);
    return 0;
}

} // namespace

// Exceptions are caught so that the temporary board folder is removed.
int main(int argc, char** argv) {
    try {
        return run(argc, argv);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_scanner: %s\n", e.what());
        return 1;
    }
}
