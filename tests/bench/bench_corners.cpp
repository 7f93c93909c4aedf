// Checkerboard corner finding (fpp::calib::find_checkerboard: detector,
// cornerSubPix, corner model) per pose on 1600 x 1200 white frames of the
// paper rig with effects, 15 x 11 board of 12 mm (tests/support/
// corner_poses.hpp):
//   - a frontal board at 600 mm, the baseline;
//   - boards tilted 35-45 degrees pushed into the image's corners, lit
//     whole (the poses a careful session needs);
//   - the same pushed where the projector lights only part of the pattern
//     (the finders fail; the time spent failing, on each texture a session
//     tries).
// Prints each against the frontal pose. Target: tilted corner poses within
// 2x of the frontal one.

#include "corner_poses.hpp"

#include "fpp/calib/corners.hpp"
#include "fpp/simulator/rig.hpp"

#include "best_time_reporter.hpp"

#include <benchmark/benchmark.h>

#include <cstdio>
#include <vector>

namespace {

using fpp::calib::CornerTexture;

struct Fixture {
    std::vector<CornerTexture> frontal;
    std::vector<std::vector<CornerTexture>> tilted, part_lit;

    static const Fixture& get() {
        static const Fixture f;
        return f;
    }

private:
    Fixture() {
        const fpp::sim::Rig rig = fpp::sim::load_rig(fpp::sim::effects_rig_path());
        const fpp::sim::CheckerboardSpec spec = fpp::test::careful_session_board();
        auto texture = [&](const fpp::sim::Pose& pose, std::uint64_t seed) {
            return std::vector<CornerTexture>{
                {fpp::test::white_frame(rig, fpp::sim::checkerboard_scene(pose, spec), seed),
                 "white frame"}};
        };
        frontal = texture(fpp::sim::Pose::from_euler_deg({0, 0, 600}, 0, 0, 0), 1);
        // Every third pose: both upper corners, each tilt, three depths.
        const auto lit = fpp::test::tilted_corner_poses(rig, spec, {35, 40, 45}, 600);
        for (std::size_t k = 0; k < lit.size(); k += 3)
            tilted.push_back(texture(lit[k].pose, 10 + k));
        const auto dark = fpp::test::tilted_corner_poses(rig, spec, {35, 45}, 700, false);
        for (std::size_t k = 0; k < dark.size(); k += 4)
            part_lit.push_back(texture(dark[k].pose, 100 + k));
    }
};

// Time per pose: each iteration finds the board on every pose of the set.
void run(benchmark::State& state, const std::vector<std::vector<CornerTexture>>& poses) {
    int found = 0;
    for (auto _ : state) {
        found = 0;
        for (const auto& textures : poses)
            found += fpp::calib::find_checkerboard(textures, 15, 11).found ? 1 : 0;
    }
    state.counters["poses"] = static_cast<double>(poses.size());
    state.counters["found"] = found;
}

void BM_CornersFrontal(benchmark::State& state) {
    run(state, {Fixture::get().frontal});
}
void BM_CornersTiltedIntoImageCorners(benchmark::State& state) {
    run(state, Fixture::get().tilted);
}
void BM_CornersPartlyLitNotFound(benchmark::State& state) {
    run(state, Fixture::get().part_lit);
}

BENCHMARK(BM_CornersFrontal)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_CornersTiltedIntoImageCorners)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_CornersPartlyLitNotFound)->Unit(benchmark::kMillisecond)->UseRealTime();

} // namespace

int main(int argc, char** argv) {
    fpp::bench::BestTimeReporter reporter;
    if (!fpp::bench::run_benchmarks(argc, argv, reporter))
        return 1;

    const Fixture& fx = Fixture::get();
    const double frontal = reporter.seconds("BM_CornersFrontal/real_time");
    std::printf("\nCorner finding per pose, 1600x1200 white frame, 15 x 11 board:\n");
    const struct {
        const char* name;
        const char* label;
        std::size_t poses;
    } rows[] = {
        {"BM_CornersFrontal/real_time", "frontal, 600 mm", 1},
        {"BM_CornersTiltedIntoImageCorners/real_time", "tilted 35-45 deg into image corners",
         fx.tilted.size()},
        {"BM_CornersPartlyLitNotFound/real_time", "partly lit, not found (1 texture)",
         fx.part_lit.size()},
    };
    for (const auto& r : rows) {
        const double s = reporter.seconds(r.name);
        if (s <= 0 || r.poses == 0)
            continue;
        const double per_pose = s / static_cast<double>(r.poses);
        std::printf("  %-38s %2zu poses %8.1f ms a pose  %5.2fx the frontal pose\n", r.label,
                    r.poses, per_pose * 1e3, frontal > 0 ? per_pose / frontal : 0.0);
    }
    return 0;
}
