// Decoding the real captures in ../shared/datasets (SLMaster, SLStudio).

#include "fpp/capture_set.hpp"
#include "fpp/decode_consistency.hpp"
#include "fpp/decode_diagnosis.hpp"
#include "fpp/decode_report.hpp"
#include "fpp/decoder.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

namespace {

fpp::DecodeResult decode_folder(const std::filesystem::path& folder) {
    return fpp::decode(fpp::read_capture_set(folder));
}

double valid_fraction(const fpp::DecodeResult& r) {
    std::size_t valid = 0;
    for (std::size_t i = 0; i < r.mask.pixel_count(); ++i)
        valid += (r.mask.data()[i] & fpp::kDecodeValid) != 0;
    return double(valid) / double(r.mask.pixel_count());
}

// Share of 4-neighbour pairs of decoded pixels whose coordinates differ by
// more than `step` px (a wrong fringe order shows as a step of about a period).
double jump_share(const fpp::Image<float>& p, double step) {
    std::size_t pairs = 0, jumps = 0;
    for (int y = 0; y < p.height(); ++y)
        for (int x = 0; x < p.width(); ++x) {
            const float a = p.at(x, y);
            if (!std::isfinite(a))
                continue;
            for (const auto& [u, v] : {std::pair{x + 1, y}, std::pair{x, y + 1}}) {
                if (u >= p.width() || v >= p.height())
                    continue;
                const float b = p.at(u, v);
                if (!std::isfinite(b))
                    continue;
                ++pairs;
                if (std::abs(double(a) - double(b)) > step)
                    ++jumps;
            }
        }
    return pairs ? double(jumps) / double(pairs) : 1.0;
}

TEST(DecodeDatasets, EveryCaptureDecodes) {
    const auto root = fpp::test::dataset("");
    FPP_REQUIRE_DATASET(fpp::test::dataset("slmaster/monocular"));
    int decoded = 0;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(root)) {
        if (entry.path().filename() != "capture.yaml")
            continue;
        SCOPED_TRACE(entry.path().string());
        const fpp::CaptureSet set = fpp::read_capture_set(entry.path().parent_path());
        fpp::DecodeResult r;
        ASSERT_NO_THROW(r = fpp::decode(set));
        EXPECT_FALSE(r.method_x.empty() && r.method_y.empty());
        EXPECT_GT(valid_fraction(r), 0.05);
        // Correctly described real captures raise no consistency alarm
        // (fpp/decode_consistency.hpp; its simulated wrong descriptions:
        // DecodeConsistencySim.*).
        const fpp::DecodeConsistency c = fpp::check_decode_consistency(r, set.manifest.sequence);
        for (int axis = 0; axis < 2; ++axis)
            if (c.axis[axis].checked)
                std::printf("[ figures  ] %s %s: smooth %zu, against %.3f %%, jumps %.3f per "
                            "period\n",
                            entry.path().parent_path().filename().c_str(), axis ? "y" : "x",
                            c.axis[axis].smooth, 100.0 * c.axis[axis].against_fraction(),
                            c.axis[axis].jumps_per_period());
        EXPECT_FALSE(c.inconsistent) << c.message;
        ++decoded;
    }
    EXPECT_GE(decoded, 9);
}

// SLMaster relief tile: 12-step phase (period 60, offset -pi) plus
// complementary Gray code thresholded against the phase mean. Projector x
// increases smoothly along each row across the tile (README: about 544 to
// 1246 along row 600), no 2-pi jumps.
TEST(DecodeDatasets, SLMasterReliefIsSmoothAndComplete) {
    const auto folder = fpp::test::dataset("slmaster/monocular");
    FPP_REQUIRE_DATASET(folder);
    const fpp::DecodeResult r = decode_folder(folder);
    EXPECT_EQ(r.method_x, "complementary-gray");
    EXPECT_TRUE(r.proj_y.empty());

    // Inside the tile nearly every pixel decodes (its Gray frames clip in
    // places, which must not invalidate them).
    std::size_t inside = 0, valid = 0;
    for (int y = 380; y < 800; ++y)
        for (int x = 470; x < 900; ++x) {
            ++inside;
            valid += std::isfinite(r.proj_x.at(x, y));
        }
    EXPECT_GT(double(valid) / double(inside), 0.99);

    for (int row = 400; row <= 780; row += 20) {
        SCOPED_TRACE("row " + std::to_string(row));
        float previous = std::numeric_limits<float>::quiet_NaN();
        int count = 0;
        for (int x = 470; x < 900; ++x) {
            const float v = r.proj_x.at(x, row);
            if (!std::isfinite(v))
                continue;
            ++count;
            if (std::isfinite(previous)) {
                // About 1.6 projector px per camera px; a wrong fringe order
                // would step by 60.
                EXPECT_LT(v - previous, 10.0f) << "x " << x;
                EXPECT_GT(v - previous, -3.0f) << "x " << x;
            }
            previous = v;
        }
        EXPECT_GT(count, 400);
    }
    // Row 600 spans the projector columns the README states.
    float lo = 1e9f, hi = -1e9f;
    for (int x = 0; x < r.proj_x.width(); ++x) {
        const float v = r.proj_x.at(x, 600);
        if (x > 400 && x < 950 && std::isfinite(v)) {
            lo = std::min(lo, v);
            hi = std::max(hi, v);
        }
    }
    EXPECT_NEAR(lo, 544.0f, 30.0f);
    EXPECT_NEAR(hi, 1246.0f, 30.0f);
    EXPECT_LT(jump_share(r.proj_x, 15.0), 1e-4);
}

// SLStudio calibration poses: 3-step phase at 16 periods plus a one-period
// cue, along x and then y. The 3-step one-period cue is noisy (about 10-20 px
// RMS on the board), so a few per cent of the lit pixels fail the coarse/fine
// consistency check and are masked.
// The mistakes a user makes describing these captures, on the real frames:
// the shift direction reversed, SLMaster's phase offset left at 0 instead
// of -pi. Each is caught: by the decode's own diagnosis (coverage and its
// trials) or by the consistency check (fpp/decode_consistency.hpp). On
// SLStudio's two-period sets the shift of one block (the fine one) is
// reversed: both reversed at once decode to a consistent field, the one a
// mirrored projector gives, which no check of the capture alone can tell
// (95 % decode, no alarm: measured, not asserted).
TEST(DecodeDatasets, WrongDescriptionsOfRealCapturesAreCaught) {
    FPP_REQUIRE_DATASET(fpp::test::dataset("slmaster/monocular"));
    struct Case {
        const char* folder;
        const char* what;
        void (*change)(fpp::PhaseBlock&);
    };
    const Case cases[] = {
        {"slmaster/monocular", "shift_sign flipped",
         [](fpp::PhaseBlock& p) { p.shift_sign *= -1; }},
        {"slmaster/monocular", "phase_offset 0", [](fpp::PhaseBlock& p) { p.phase_offset = 0; }},
        {"slstudio/skull_2x3", "fine shift_sign flipped",
         [](fpp::PhaseBlock& p) { p.shift_sign *= p.period < 1000 ? -1 : 1; }},
        {"slstudio/calibration/calseq1", "fine shift_sign flipped",
         [](fpp::PhaseBlock& p) { p.shift_sign *= p.period < 1000 ? -1 : 1; }},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(std::string(c.folder) + ", " + c.what);
        fpp::CaptureSet set = fpp::read_capture_set(fpp::test::dataset(c.folder));
        for (auto& block : set.manifest.sequence)
            if (auto* p = std::get_if<fpp::PhaseBlock>(&block))
                c.change(*p);
        const fpp::DecodeResult r = fpp::decode(set);
        const fpp::DecodeStatistics stats = fpp::decode_statistics(r, fpp::frames_full_scale(set));
        const bool diagnosed = fpp::diagnose_decode(set, r, stats, {}).failed;
        const fpp::DecodeConsistency consistency =
            fpp::check_decode_consistency(r, set.manifest.sequence);
        std::printf("[ figures  ] %s, %s: coverage %.2f %%, diagnosis %s, against %.2f %%, jumps "
                    "%.2f per period%s\n",
                    c.folder, c.what, 100.0 * stats.coverage_of_lit(),
                    diagnosed ? "failed" : "passed", 100.0 * consistency.axis[0].against_fraction(),
                    consistency.axis[0].jumps_per_period(),
                    consistency.inconsistent ? ": INCONSISTENT" : "");
        EXPECT_TRUE(diagnosed || consistency.inconsistent);
    }
}

TEST(DecodeDatasets, SLStudioCalibrationPosesDecodeInXAndY) {
    const auto calibration = fpp::test::dataset("slstudio/calibration");
    FPP_REQUIRE_DATASET(calibration);
    for (int pose = 1; pose <= 6; ++pose) {
        const auto folder = calibration / ("calseq" + std::to_string(pose));
        SCOPED_TRACE(folder.string());
        const fpp::DecodeResult r = decode_folder(folder);
        EXPECT_EQ(r.method_x, "multi-period");
        EXPECT_EQ(r.method_y, "multi-period");
        // Well-lit pixels (modulation >= 15 DN: board, table, wall) decode.
        std::size_t lit = 0, valid = 0;
        for (std::size_t i = 0; i < r.mask.pixel_count(); ++i) {
            if (r.modulation.data()[i] < 15.0f)
                continue;
            ++lit;
            valid += (r.mask.data()[i] & fpp::kDecodeValid) != 0;
        }
        EXPECT_GT(lit, 900000u);
        EXPECT_GT(double(valid) / double(lit), 0.92);
        // Coordinates lie on the projector (1824 x 1140, with the decoder's
        // one-pixel margin).
        for (int axis = 0; axis < 2; ++axis) {
            const fpp::Image<float>& p = axis == 0 ? r.proj_x : r.proj_y;
            const float extent = axis == 0 ? 1824.0f : 1140.0f;
            float lo = 1e9f, hi = -1e9f;
            for (std::size_t i = 0; i < p.pixel_count(); ++i)
                if (std::isfinite(p.data()[i])) {
                    lo = std::min(lo, p.data()[i]);
                    hi = std::max(hi, p.data()[i]);
                }
            EXPECT_GE(lo, -1.5f);
            EXPECT_LE(hi, extent + 0.5f);
            EXPECT_GT(hi - lo, 0.5f * extent);
            // Smooth: steps of a quarter period between neighbours are rare
            // (object edges and the odd wrong fringe order).
            const double period = axis == 0 ? 114.0 : 71.25;
            EXPECT_LT(jump_share(p, period / 4), 2e-3);
        }
    }
}

TEST(DecodeDatasets, SLStudioSkulls) {
    const auto two = fpp::test::dataset("slstudio/skull_2x3");
    const auto one = fpp::test::dataset("slstudio/skull_3ps");
    FPP_REQUIRE_DATASET(two);
    FPP_REQUIRE_DATASET(one);
    const fpp::DecodeResult r2 = decode_folder(two);
    const fpp::DecodeResult r1 = decode_folder(one);
    EXPECT_EQ(r2.method_x, "multi-period");
    EXPECT_EQ(r1.method_x, "direct");
    // The same skull: where both decode, the two agree to within the noise of
    // the one-period phase (a wrong fringe order in the first would be 114 px off).
    std::size_t both = 0, far = 0;
    for (std::size_t i = 0; i < r1.proj_x.pixel_count(); ++i) {
        const float a = r1.proj_x.data()[i], b = r2.proj_x.data()[i];
        if (!std::isfinite(a) || !std::isfinite(b))
            continue;
        ++both;
        if (std::abs(a - b) > 57.0f)
            ++far;
    }
    EXPECT_GT(both, 300000u);
    EXPECT_LT(double(far) / double(both), 5e-3);
}

} // namespace
