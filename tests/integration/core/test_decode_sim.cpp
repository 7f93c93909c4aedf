// Decoding simulated captures of the paper's rig (effects off) against the
// renderer's projector-coordinate truth, for every standard sequence.
// Full 1600 x 1200 camera; 2 x 2 binned (same optics,
// 4 x fewer pixels) where the tests run slowly: under the sanitizers and
// as AArch64 programs under qemu-user (test_support.hpp). The streaming
// decoder on such a capture: test_decode_sim_streaming.cpp.

#include "fpp/capture_set.hpp"
#include "fpp/decode_accuracy.hpp"
#include "fpp/decoder.hpp"
#include "fpp/sequences.hpp"
#include "fpp/simulator/renderer.hpp"
#include "fpp/simulator/rig.hpp"
#include "fpp/simulator/scene.hpp"

#include "test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <ostream>
#include <string>
#include <vector>

namespace {

constexpr int kBinning = fpp::test::kSimulatedCaptureBinning;

fpp::sim::Rig paper_rig(double read_noise_dn) {
    fpp::sim::Rig rig = fpp::sim::Rig::paper().without_effects();
    if (kBinning > 1)
        rig = rig.binned_camera(kBinning);
    rig.sensor.read_noise_dn = read_noise_dn;
    return rig;
}

fpp::CaptureSet to_capture(const fpp::sim::SimulatedCapture& sim) {
    // Constructed, not assigned member by member: GCC 12 -O3 for AArch64
    // reports a false null dereference in the inlined vector assignment.
    return fpp::CaptureSet{{}, sim.manifest, sim.frames};
}

// Finest fringe period per axis (0 = axis not coded).
double finest_period(const fpp::Sequence& sequence, fpp::Axis axis) {
    double period = 0;
    for (const auto& block : sequence)
        if (const auto* p = std::get_if<fpp::PhaseBlock>(&block))
            if (p->axis == axis && (period == 0 || p->period < period))
                period = p->period;
    return period;
}

// Pixels within `radius` px of a depth discontinuity (|dZ| > 2 mm between
// 4-neighbours) or of a pixel without projector light.
fpp::Image<std::uint8_t> near_edges(const fpp::sim::SimulatedCapture& sim, int radius) {
    const auto& xyz = sim.truth_xyz;
    const auto& proj = sim.truth_projector;
    const int w = xyz.width(), h = xyz.height();
    fpp::Image<std::uint8_t> edge(w, h, 1, 0);
    auto lit = [&](int x, int y) { return std::isfinite(proj.at(x, y, 0)); };
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            if (!lit(x, y))
                continue;
            bool e = false;
            const int nx[4] = {x - 1, x + 1, x, x};
            const int ny[4] = {y, y, y - 1, y + 1};
            for (int k = 0; k < 4 && !e; ++k) {
                if (nx[k] < 0 || ny[k] < 0 || nx[k] >= w || ny[k] >= h)
                    continue;
                if (!lit(nx[k], ny[k]) ||
                    std::abs(double(xyz.at(x, y, 2)) - double(xyz.at(nx[k], ny[k], 2))) > 2.0)
                    e = true;
            }
            edge.at(x, y) = e ? 1 : 0;
        }
    fpp::Image<std::uint8_t> near(w, h, 1, 0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            if (!edge.at(x, y))
                continue;
            for (int v = std::max(0, y - radius); v <= std::min(h - 1, y + radius); ++v)
                for (int u = std::max(0, x - radius); u <= std::min(w - 1, x + radius); ++u)
                    near.at(u, v) = 1;
        }
    return near;
}

struct EdgeReport {
    std::size_t near_valid = 0; // decoded pixels near edges
    std::size_t near_gross = 0; // ... off by more than the gross limit
    std::size_t far_truth = 0;  // lit pixels away from edges
    std::size_t far_valid = 0;  // ... decoded
    double far_coverage() const { return far_truth ? double(far_valid) / double(far_truth) : 0; }
};

// `gross`: error (px) that counts as corruption rather than phase noise.
EdgeReport edge_report(const fpp::Image<float>& decoded, const fpp::sim::SimulatedCapture& sim,
                       int channel, const fpp::Image<std::uint8_t>& near, double gross) {
    EdgeReport r;
    for (int y = 0; y < decoded.height(); ++y)
        for (int x = 0; x < decoded.width(); ++x) {
            const float t = sim.truth_projector.at(x, y, channel);
            const float d = decoded.at(x, y);
            if (!std::isfinite(t))
                continue;
            if (near.at(x, y)) {
                if (!std::isfinite(d))
                    continue;
                ++r.near_valid;
                if (std::abs(double(d) - double(t)) > gross)
                    ++r.near_gross;
            } else {
                ++r.far_truth;
                if (std::isfinite(d))
                    ++r.far_valid;
            }
        }
    return r;
}

struct MethodCase {
    std::string sequence;
    std::vector<std::string> scenes; // scenes it is expected to decode without error
    double rms_noise_free;
    bool noisy; // also checked with 1.5 DN read noise
};

// The centerline method needs the centerline on every surface: in the
// composite scene the background and the sphere carry none (and the relief's
// edge against the background happens to jump by whole periods on both axes,
// which spatial unwrapping cannot see), so it is checked on plane and relief.
std::vector<MethodCase> method_cases() {
    return {
        {"gray-xy", {"plane", "composite"}, 0.02, true},
        {"plain-gray-x", {"plane", "composite"}, 0.02, true},
        {"inverse-gray-x", {"plane", "composite"}, 0.02, true},
        {"multi-period-x", {"plane", "composite"}, 0.02, true},
        {"heterodyne-x", {"plane", "composite"}, 0.02, true},
        {"centerline-xy", {"plane", "relief"}, 0.02, true},
        // 3 steps at period 80: about 0.04 px from 8-bit quantisation alone.
        {"slstudio-like-x", {"plane", "composite"}, 0.06, false},
    };
}

void PrintTo(const MethodCase& c, std::ostream* os) {
    *os << c.sequence;
}

class DecodeSim : public ::testing::TestWithParam<MethodCase> {};

TEST_P(DecodeSim, MatchesTruth) {
    const MethodCase& mc = GetParam();
    for (const std::string& scene_name : mc.scenes) {
        const fpp::sim::Scene scene = fpp::sim::named_scene(scene_name);
        for (const double noise : {0.0, 1.5}) {
            if (noise > 0 && !mc.noisy)
                continue;
            SCOPED_TRACE(mc.sequence + " on " + scene_name + ", read noise " +
                         std::to_string(noise));
            const fpp::sim::Rig rig = paper_rig(noise);
            const fpp::sim::Renderer renderer(rig, scene);
            const fpp::Sequence sequence = fpp::standard_sequence(mc.sequence, rig.projector_size);
            const fpp::sim::SimulatedCapture sim = fpp::sim::simulate(renderer, sequence, 17);
            const fpp::DecodeResult r = fpp::decode(to_capture(sim));
            const fpp::Image<std::uint8_t> near = near_edges(sim, 2);
            int axes = 0;
            for (int channel = 0; channel < 2; ++channel) {
                const fpp::Axis axis = channel == 0 ? fpp::Axis::x : fpp::Axis::y;
                const double period = finest_period(sequence, axis);
                const fpp::Image<float>& decoded = channel == 0 ? r.proj_x : r.proj_y;
                if (period == 0) {
                    EXPECT_TRUE(decoded.empty());
                    continue;
                }
                ++axes;
                const fpp::AxisAccuracy acc =
                    fpp::compare_to_truth(decoded, sim.truth_projector, channel, period);
                // Gross: 1 px at period 20 (50x the noise-free RMS), period/20 above.
                const EdgeReport edges =
                    edge_report(decoded, sim, channel, near, std::max(1.0, period / 20.0));
                std::printf("[ figures  ] %-16s %-9s noise %.1f axis %c: rms %.4f px, p99 %.3f, "
                            "unwrap errors %zu / %zu, coverage %.4f (away from edges %.4f), "
                            "near-edge gross %zu / %zu\n",
                            mc.sequence.c_str(), scene_name.c_str(), noise, "xy"[channel],
                            acc.rms_px, acc.p99_abs_px, acc.unwrap_errors, acc.compared,
                            acc.coverage(), edges.far_coverage(), edges.near_gross,
                            edges.near_valid);
                EXPECT_EQ(acc.false_valid, 0u);
                EXPECT_GT(edges.far_coverage(), 0.98);
                if (noise == 0) {
                    EXPECT_EQ(acc.unwrap_errors, 0u);
                    EXPECT_LE(acc.rms_px, mc.rms_noise_free);
                    // Occlusion edges do not corrupt their neighbours.
                    EXPECT_EQ(edges.near_gross, 0u);
                } else {
                    EXPECT_LE(acc.unwrap_error_rate(), 1e-4);
                    EXPECT_LE(acc.rms_px, 0.1);
                    EXPECT_LE(double(edges.near_gross), 1e-3 * double(edges.near_valid));
                }
            }
            EXPECT_GT(axes, 0);
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Paper, DecodeSim, ::testing::ValuesIn(method_cases()),
                         [](const auto& param_info) {
                             std::string n = param_info.param.sequence;
                             std::replace(n.begin(), n.end(), '-', '_');
                             return n;
                         });

} // namespace
