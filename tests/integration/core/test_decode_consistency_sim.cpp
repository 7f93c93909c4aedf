// The decode's consistency check (fpp/decode_consistency.hpp) on the
// virtual scanner (effects rig: noise, defocus, gamma 2.2 through its
// precompensation; camera binned 2 x 2): every
// standard family and the shifted-Gray family decode consistent on the
// plane and on the composite scene (relief, sphere, their depth edges), and
// the descriptions a user gets wrong are caught on each family they apply
// to: the shift direction reversed, the phase offset off by half a turn
// (0 instead of -pi), a shifted code's offset left out.

#include "fpp/capture_set.hpp"
#include "fpp/decode_consistency.hpp"
#include "fpp/decode_diagnosis.hpp"
#include "fpp/decode_report.hpp"
#include "fpp/decoder.hpp"
#include "fpp/patterns.hpp"
#include "fpp/sequences.hpp"
#include "fpp/simulator/renderer.hpp"
#include "fpp/simulator/rig.hpp"
#include "fpp/simulator/scene.hpp"

#include "pattern_blocks.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

namespace {

constexpr double kPi = 3.14159265358979323846;

// Binned 2 x 2 (800 x 600; the fine period about 18 camera pixels): a
// quarter of the full camera's time, the same verdicts.
fpp::sim::Rig rig() {
    return fpp::sim::load_rig(fpp::sim::effects_rig_path()).binned_camera(2);
}

const fpp::sim::Renderer& renderer(const std::string& scene) {
    static const fpp::sim::Renderer plane(rig(), fpp::sim::named_scene("plane"));
    static const fpp::sim::Renderer composite(rig(), fpp::sim::named_scene("composite"));
    return scene == "plane" ? plane : composite;
}

std::vector<fpp::Frame> render(const fpp::Sequence& sequence, const fpp::sim::Renderer& r) {
    const fpp::GammaLut lut = fpp::GammaLut::precompensate(r.rig().projector_optics.gamma);
    std::vector<fpp::Frame> frames;
    int frame = 0;
    for (const auto& block : sequence)
        for (int k = 0; k < fpp::frame_count(block); ++k, ++frame)
            frames.push_back(r.render(fpp::render_pattern(block, k, r.rig().projector_size, &lut),
                                      fpp::sim::Renderer::frame_seed(3, frame)));
    return frames;
}

struct Checked {
    fpp::DecodeConsistency consistency;
    bool diagnosis_failed = false; // the decode's own diagnosis (coverage, trials)
    bool caught() const { return consistency.inconsistent || diagnosis_failed; }
};

// Frames of `shown` decoded as `described`: what the checks found.
Checked check(const fpp::Sequence& shown, fpp::Sequence described, const std::string& scene,
              const std::string& what) {
    const fpp::sim::Renderer& r = renderer(scene);
    fpp::CaptureSet set;
    set.manifest.camera = r.rig().camera_size;
    set.manifest.projector = r.rig().projector_size;
    set.frames = render(shown, r);
    set.manifest.sequence = std::move(described);
    const fpp::DecodeResult decoded = fpp::decode(set);
    Checked c;
    c.consistency = fpp::check_decode_consistency(decoded, set.manifest.sequence);
    const fpp::DecodeStatistics stats =
        fpp::decode_statistics(decoded, fpp::frames_full_scale(set));
    c.diagnosis_failed = fpp::diagnose_decode(set, decoded, stats, {}).failed;
    const fpp::AxisConsistency& x = c.consistency.axis[0];
    std::printf("[ figures  ] %-44s %-9s coverage %6.2f %%, smooth %7zu, against %6.3f %%, "
                "jumps %6.3f per period (period %.1f camera px)%s%s\n",
                what.c_str(), scene.c_str(), 100.0 * stats.coverage_of_lit(), x.smooth,
                100.0 * x.against_fraction(), x.jumps_per_period(), x.camera_period,
                c.consistency.inconsistent ? ": INCONSISTENT" : "",
                c.diagnosis_failed ? ": DIAGNOSIS FAILED" : "");
    return c;
}

bool has_code(const fpp::Sequence& s) {
    for (const auto& block : s)
        if (std::holds_alternative<fpp::GrayBlock>(block))
            return true;
    return false;
}

// The finest phase block only, its shift reversed (one block described
// wrong among several).
fpp::Sequence finest_reversed(fpp::Sequence s) {
    fpp::PhaseBlock* finest = nullptr;
    for (auto& block : s)
        if (auto* p = std::get_if<fpp::PhaseBlock>(&block);
            p && (!finest || p->period < finest->period))
            finest = p;
    if (finest)
        finest->shift_sign = -finest->shift_sign;
    return s;
}

fpp::Sequence with_phase(fpp::Sequence s, int sign, double offset) {
    for (auto& block : s)
        if (auto* p = std::get_if<fpp::PhaseBlock>(&block)) {
            p->shift_sign *= sign;
            p->phase_offset += offset;
        }
    return s;
}

// The shifted-Gray family: 4 steps of period 20 and a Gray code whose edges
// sit half a period from the phase's wraps (offset 10), inverse frames.
fpp::Sequence shifted_gray() {
    fpp::GrayBlock g = fpp::test::gray(fpp::Axis::x, 20, 7, false, true);
    g.offset = 10;
    return {fpp::test::phase(fpp::Axis::x, 20, 4), g};
}

std::vector<std::pair<std::string, fpp::Sequence>> families() {
    std::vector<std::pair<std::string, fpp::Sequence>> f;
    const fpp::Size projector = rig().projector_size;
    for (const std::string& name : fpp::standard_sequence_names())
        f.emplace_back(name, fpp::standard_sequence(name, projector));
    f.emplace_back("shifted-gray", shifted_gray());
    return f;
}

TEST(DecodeConsistencySim, CorrectDescriptionsOfEveryFamilyAreConsistent) {
    for (const std::string scene : {"plane", "composite"})
        for (const auto& [name, sequence] : families()) {
            SCOPED_TRACE(name + " on " + scene);
            const Checked c = check(sequence, sequence, scene, name);
            EXPECT_FALSE(c.consistency.inconsistent) << c.consistency.message;
            EXPECT_FALSE(c.diagnosis_failed);
        }
}

// The shift direction reversed and the phase offset half a turn off, on
// every family that joins a phase to a code: caught, by the coverage the
// decode keeps (complementary and inverse codes refuse most pixels; the
// diagnosis names the trial) or, where nearly every pixel still "decodes"
// (a plain or shifted code), by the consistency check naming the field.
TEST(DecodeConsistencySim, WrongPhaseOfPhaseAndCodeFamiliesIsCaught) {
    for (const std::string scene : {"plane", "composite"})
        for (const auto& [name, sequence] : families()) {
            if (!has_code(sequence) || !fpp::check_decode_consistency({}, sequence).axis[0].checked)
                continue;
            SCOPED_TRACE(name + " on " + scene);
            const Checked reversed = check(sequence, with_phase(sequence, -1, 0.0), scene,
                                           name + ", shift_sign flipped");
            EXPECT_TRUE(reversed.caught());
            if (!reversed.diagnosis_failed) {
                EXPECT_NE(reversed.consistency.message.find("shift_sign"), std::string::npos)
                    << reversed.consistency.message;
            }
            const Checked offset =
                check(sequence, with_phase(sequence, 1, kPi), scene, name + ", phase_offset + pi");
            EXPECT_TRUE(offset.caught());
            if (!offset.diagnosis_failed) {
                EXPECT_NE(offset.consistency.message.find("phase_offset"), std::string::npos)
                    << offset.consistency.message;
            }
        }
}

// Several phase periods: one block's shift reversed, or every block's
// offset half a turn off, is caught. (Every block's shift reversed at once
// is not, and cannot be from the capture: it decodes to a consistent field,
// the one a mirrored projector gives. Nor is a phase unwrapped spatially
// from a centerline with its shift reversed: its one line is no second cue
// to disagree with, and the field is as consistent, mirrored about it.)
TEST(DecodeConsistencySim, WrongPhaseOfMultiPeriodFamiliesIsCaught) {
    for (const std::string scene : {"plane", "composite"})
        for (const auto& [name, sequence] : families()) {
            if (has_code(sequence) || name == "centerline-xy" ||
                !fpp::check_decode_consistency({}, sequence).axis[0].checked)
                continue;
            SCOPED_TRACE(name + " on " + scene);
            EXPECT_TRUE(check(sequence, finest_reversed(sequence), scene,
                              name + ", finest shift_sign flipped")
                            .caught());
            EXPECT_TRUE(
                check(sequence, with_phase(sequence, 1, kPi), scene, name + ", phase_offset + pi")
                    .caught());
        }
}

TEST(DecodeConsistencySim, ShiftedCodeDescribedWithoutItsOffsetIsCaught) {
    fpp::Sequence described = shifted_gray();
    std::get<fpp::GrayBlock>(described[1]).offset = 0;
    for (const std::string scene : {"plane", "composite"}) {
        SCOPED_TRACE(scene);
        const Checked c =
            check(shifted_gray(), described, scene, "shifted-gray, code offset left out");
        EXPECT_TRUE(c.consistency.inconsistent);
        EXPECT_FALSE(c.diagnosis_failed); // nearly every pixel still "decodes"
        EXPECT_NE(c.consistency.message.find("offset of the code block"), std::string::npos)
            << c.consistency.message;
    }
}

} // namespace
