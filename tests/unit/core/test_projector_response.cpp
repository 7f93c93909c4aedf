// The projector response (fpp/projector_response.hpp): its fit from a ramp
// of grey levels, its monotone interpolation, its inverse as a pattern LUT
// (GammaLut::from_response), its two files, and every bad input refused with
// the file and the field named.

#include "fpp/error.hpp"
#include "fpp/image_io.hpp"
#include "fpp/patterns.hpp"
#include "fpp/projector_response.hpp"

#include "test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace fpp;
using fpp::test::TempDir;

namespace {

double gamma22(double level) {
    return std::pow(level / 255.0, 2.2);
}

// A camera looking at a flat board lit by a projector with the normalised
// response `response` (0 at level 0, 1 at level 255), a black level and
// ambient light, the illumination falling off across the image; Gaussian
// noise, rounding and clipping as a sensor does. Columns below
// `dark_columns` see a black square (3 % albedo); columns from
// `bright_from` on a glossy patch twice as bright (they saturate).
struct SyntheticRamp {
    Size camera{80, 60};
    int bit_depth = 8;
    std::function<double(double)> response = gamma22;
    double white_dn = 170;      // level 255 at the image centre, above the black, 8-bit DN
    double black_level = 0.005; // fraction of full light at level 0
    double ambient_dn = 5;
    double noise_dn = 1.5;
    int dark_columns = 0;
    int bright_from = 1 << 30;
    std::vector<int> levels = standard_ramp_levels();

    ResponseRamp make(std::uint32_t seed) const {
        ResponseRamp ramp;
        ramp.levels = levels;
        const double scale = bit_depth == 8 ? 1.0 : 257.0; // 8-bit DN to the container's
        const double full = bit_depth == 8 ? 255.0 : 65535.0;
        std::mt19937 rng(seed);
        std::normal_distribution<double> noise(0.0, noise_dn * scale);
        for (const int level : levels) {
            Frame f;
            f.bit_depth = bit_depth;
            if (bit_depth == 8)
                f.u8 = Image<std::uint8_t>(camera);
            else
                f.u16 = Image<std::uint16_t>(camera);
            for (int y = 0; y < camera.height; ++y) {
                for (int x = 0; x < camera.width; ++x) {
                    double gain = white_dn * (0.75 + 0.25 * x / camera.width) *
                                  (0.85 + 0.15 * y / camera.height);
                    if (x < dark_columns)
                        gain *= 0.03;
                    if (x >= bright_from)
                        gain *= 2.0;
                    const double light = response(level) + black_level;
                    const double dn = std::clamp(
                        std::round(scale * (ambient_dn + gain * light) + noise(rng)), 0.0, full);
                    if (bit_depth == 8)
                        f.u8.at(x, y) = static_cast<std::uint8_t>(dn);
                    else
                        f.u16.at(x, y) = static_cast<std::uint16_t>(dn);
                }
            }
            ramp.frames.push_back(std::move(f));
        }
        return ramp;
    }
};

// Largest |fitted - truth| over the fitted levels.
double worst_level_error(const ProjectorResponse& r, const std::function<double(double)>& truth) {
    double worst = 0;
    for (std::size_t k = 0; k < r.levels.size(); ++k)
        worst = std::max(worst, std::abs(r.emitted[k] - truth(r.levels[k])));
    return worst;
}

// Runs f; expects an InputError naming `file` and exactly `field`, whose
// message contains `hint`.
template <class F>
void expect_input_error(F&& f, const fs::path& file, const std::string& field,
                        const std::string& hint) {
    try {
        f();
        ADD_FAILURE() << "accepted; expected a rejection of " << field;
    } catch (const InputError& e) {
        const std::string what = e.what();
        EXPECT_EQ(e.file(), file) << what;
        EXPECT_EQ(e.field(), field) << what;
        EXPECT_NE(what.find(hint), std::string::npos) << what;
        std::printf("refused as expected: %s\n", what.c_str());
    }
}

void write_text(const fs::path& path, const std::string& text) {
    std::ofstream(path) << text;
}

// A response sampled exactly from `f` at the standard ramp levels.
ProjectorResponse sampled(const std::function<double(double)>& f) {
    ProjectorResponse r;
    for (const int level : standard_ramp_levels()) {
        r.levels.push_back(level);
        r.emitted.push_back(f(level));
    }
    return r;
}

} // namespace

// ---------------------------------------------------------------------------
// The fit
// ---------------------------------------------------------------------------

TEST(ProjectorResponseFit, GammaWithBlackLevelAndNoiseIsRecoveredAtEveryLevel) {
    // 8-bit and 16-bit frames (a 12-bit sensor MSB-aligned is 16-bit).
    for (const int depth : {8, 16}) {
        SyntheticRamp s;
        s.bit_depth = depth;
        const ResponseRamp ramp = s.make(7);
        const ProjectorResponse r = fit_projector_response(ramp);
        ASSERT_EQ(r.levels.size(), 17u);
        EXPECT_EQ(r.emitted.front(), 0.0);
        EXPECT_EQ(r.emitted.back(), 1.0);
        EXPECT_EQ(r.pixels_used, s.camera.area());
        const double worst = worst_level_error(r, gamma22);
        std::printf("%d-bit frames, gamma 2.2, black level 0.5 %%, noise 1.5 DN (8-bit): "
                    "worst fitted level off the truth by %.5f (relative light)\n",
                    depth, worst);
        // The standard error of each level's mean is about 0.0003 here.
        EXPECT_LT(worst, 0.0015) << depth;
    }
}

TEST(ProjectorResponseFit, DarkAndSaturatedPixelsAreLeftOut) {
    SyntheticRamp s;
    s.dark_columns = 10; // a black square: I(255) - I(0) about 5 DN
    s.bright_from = 60;  // 340 DN wanted at level 255: clipped from about level 200 on
    const ResponseRamp ramp = s.make(11);
    const ProjectorResponse r = fit_projector_response(ramp);
    EXPECT_EQ(r.pixels_used, std::size_t(50 * 60));
    const double worst = worst_level_error(r, gamma22);
    std::printf("with a black square and a saturated patch: %zu of %zu pixels used, worst level "
                "error %.5f\n",
                r.pixels_used, s.camera.area(), worst);
    EXPECT_LT(worst, 0.0015);
}

TEST(ProjectorResponseFit, ADeadZoneAtTheBottomStaysFlatAndMonotonic) {
    // No light below level 40, then a straight line: the dark levels' means
    // scatter around 0 by the noise and are pooled, not refused.
    SyntheticRamp s;
    s.response = [](double l) { return std::max(0.0, (l - 40.0) / 215.0); };
    const ProjectorResponse r = fit_projector_response(s.make(3));
    for (std::size_t k = 1; k < r.emitted.size(); ++k)
        EXPECT_GE(r.emitted[k], r.emitted[k - 1]) << k;
    for (std::size_t k = 0; k < 3; ++k)
        EXPECT_LT(r.emitted[k], 0.001) << r.levels[k];
    EXPECT_LT(worst_level_error(r, s.response), 0.0015);
}

TEST(ProjectorResponseFit, ANonMonotonicRampIsRefusedNamingTheLevel) {
    SyntheticRamp s;
    ResponseRamp ramp = s.make(5);
    ramp.folder = "/sessions/s1/response";
    // The frames of levels 128 and 144 swapped: the light falls at 144.
    std::swap(ramp.frames[8], ramp.frames[9]);
    expect_input_error([&] { fit_projector_response(ramp); }, ramp.folder / "ramp.yaml",
                       "levels[9]", "not monotonic");
}

TEST(ProjectorResponseFit, ASaturatedRampIsRefusedNamingTheFrameWhereItGoesWrong) {
    SyntheticRamp s;
    s.white_dn = 800; // full scale reached between levels 150 and 185
    ResponseRamp ramp = s.make(5);
    ramp.folder = "ramp-folder";
    // The first frame after which fewer than 1 % of the pixels (48) are
    // still below full scale, counted on the frames themselves.
    std::size_t expected = 0;
    for (std::size_t k = 0; k < ramp.frames.size(); ++k) {
        std::size_t below = 0;
        for (std::size_t i = 0; i < s.camera.area(); ++i) {
            bool ok = true;
            for (std::size_t j = 0; j <= k; ++j)
                ok = ok && ramp.frames[j].u8.data()[i] < 255;
            below += ok ? 1 : 0;
        }
        if (below < 48) {
            expected = k;
            break;
        }
    }
    ASSERT_GT(expected, 8u);
    ASSERT_LT(expected, 16u);
    expect_input_error([&] { fit_projector_response(ramp); }, "ramp-folder/ramp.yaml",
                       "frames[" + std::to_string(expected) + "]",
                       "saturates: from level " + std::to_string(ramp.levels[expected]) + " on");
    try {
        fit_projector_response(ramp);
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("lower the exposure"), std::string::npos);
    }
}

TEST(ProjectorResponseFit, ATooDarkRampIsRefused) {
    SyntheticRamp s;
    s.white_dn = 12; // below the 20 DN a lit pixel needs
    ResponseRamp ramp = s.make(5);
    ramp.folder = "dark";
    expect_input_error([&] { fit_projector_response(ramp); }, "dark/ramp.yaml", "frames[16]",
                       "too dark");
}

TEST(ProjectorResponseFit, OptionsAreChecked) {
    const std::vector<std::function<void(ResponseFitOptions&)>> bad = {
        [](ResponseFitOptions& o) { o.min_lit_fraction = 0; },
        [](ResponseFitOptions& o) { o.saturation_fraction = 1.5; },
        [](ResponseFitOptions& o) { o.min_usable_fraction = NAN; },
        [](ResponseFitOptions& o) { o.trim_fraction = 0.5; },
        [](ResponseFitOptions& o) { o.monotonic_sigmas = -1; },
        [](ResponseFitOptions& o) { o.min_monotonic_drop = -0.1; },
    };
    for (const auto& change : bad) {
        ResponseFitOptions o;
        change(o);
        EXPECT_THROW(o.validate(), std::invalid_argument);
    }
    EXPECT_NO_THROW(ResponseFitOptions{}.validate());
}

// ---------------------------------------------------------------------------
// Interpolation and inverse
// ---------------------------------------------------------------------------

TEST(ProjectorResponseInterpolation, MonotoneThroughTheSamplesAndCloseToASmoothTruth) {
    const ProjectorResponse r = sampled(gamma22);
    for (std::size_t k = 0; k < r.levels.size(); ++k)
        EXPECT_DOUBLE_EQ(r.at(r.levels[k]), r.emitted[k]) << r.levels[k];
    double worst = 0, previous = -1;
    for (double l = 0; l <= 255.0; l += 0.25) {
        const double v = r.at(l);
        EXPECT_GE(v, previous) << l;
        previous = v;
        worst = std::max(worst, std::abs(v - gamma22(l)));
    }
    std::printf("gamma 2.2 sampled every 16 levels: interpolation off by at most %.6f\n", worst);
    EXPECT_LT(worst, 0.0005);
    EXPECT_EQ(r.at(-3), 0.0);
    EXPECT_EQ(r.at(300), 1.0);
}

TEST(ProjectorResponseInterpolation, AKinkDoesNotOvershoot) {
    // Flat, then a steep rise, then flat: a plain cubic spline overshoots
    // both corners; the monotone one stays inside every interval's values.
    ProjectorResponse r;
    r.levels = {0, 64, 96, 128, 255};
    r.emitted = {0, 0, 0.9, 1, 1};
    double previous = 0;
    for (double l = 0; l <= 255.0; l += 0.5) {
        const double v = r.at(l);
        EXPECT_GE(v, previous) << l;
        EXPECT_LE(v, 1.0) << l;
        if (l <= 64) {
            EXPECT_EQ(v, 0.0) << l;
        }
        if (l >= 128) {
            EXPECT_EQ(v, 1.0) << l;
        }
        previous = v;
    }
}

TEST(ProjectorResponseInverse, RoundTripThroughTheResponseIsWithinItsStep) {
    // The LUT of a response with gamma 2.2, sampled every 16 levels: the
    // light each wanted value gets, against the value wanted, under the true
    // response. The best any 8-bit LUT can do is half the response's local
    // step (up to 2.2/255/2 = 0.0043 near full light); the LUT of the exact
    // curve (GammaLut::precompensate) is that bound.
    const GammaLut lut = GammaLut::from_response(sampled(gamma22));
    const GammaLut exact = GammaLut::precompensate(2.2);
    double worst = 0, worst_exact = 0;
    int differ = 0;
    for (int i = 0; i < 256; ++i) {
        worst = std::max(worst, std::abs(gamma22(lut.level[std::size_t(i)]) - i / 255.0));
        worst_exact =
            std::max(worst_exact, std::abs(gamma22(exact.level[std::size_t(i)]) - i / 255.0));
        differ += lut.level[std::size_t(i)] != exact.level[std::size_t(i)];
    }
    std::printf("inverse of the sampled gamma 2.2: round trip off by at most %.5f (exact curve's "
                "LUT %.5f), %d of 256 entries differ from it\n",
                worst, worst_exact, differ);
    EXPECT_LE(worst, worst_exact + 0.0005);
    EXPECT_LT(worst_exact, 0.0044);
    EXPECT_LE(differ, 16);
    for (std::size_t i = 1; i < 256; ++i)
        EXPECT_GE(lut.level[i], lut.level[i - 1]) << i;
    EXPECT_EQ(lut.level[0], 0);
    EXPECT_EQ(lut.level[255], 255);
}

TEST(ProjectorResponseInverse, ALinearResponseGivesTheIdentity) {
    ProjectorResponse r;
    r.levels = {0, 255};
    r.emitted = {0, 1};
    EXPECT_EQ(GammaLut::from_response(r).level, GammaLut::identity().level);
}

TEST(ProjectorResponseInverse, SquaredFringesForFourStepsOrMore) {
    // emitted_gamma 2: the light of wanted value v is v^2.
    const GammaLut lut = GammaLut::from_response(sampled(gamma22), 2.0);
    double worst = 0;
    for (int i = 0; i < 256; ++i) {
        const double v = i / 255.0;
        worst = std::max(worst, std::abs(gamma22(lut.level[std::size_t(i)]) - v * v));
    }
    std::printf("squared target through the sampled gamma 2.2: off by at most %.5f\n", worst);
    EXPECT_LT(worst, 0.0044); // half the response's largest step, as above
    EXPECT_THROW(GammaLut::from_response(sampled(gamma22), 0.5), std::invalid_argument);
    EXPECT_THROW(GammaLut::from_response(sampled(gamma22), NAN), std::invalid_argument);

    PhaseBlock phase;
    phase.axis = Axis::x;
    phase.period = 20;
    for (const int steps : {3, 4, 8}) {
        phase.steps = steps;
        EXPECT_EQ(compensation_emitted_gamma({WhiteBlock{}, phase}), steps == 3 ? 1.0 : 2.0);
    }
    // One 3-step block among others decides.
    PhaseBlock three = phase;
    three.steps = 3;
    EXPECT_EQ(compensation_emitted_gamma({phase, three}), 1.0);
}

TEST(ProjectorResponseInverse, AnInvalidResponseIsRefused) {
    ProjectorResponse r;
    r.levels = {0, 128, 255};
    r.emitted = {0, 0.7, 0.5};
    EXPECT_THROW(GammaLut::from_response(r), InputError);
}

// ---------------------------------------------------------------------------
// Files
// ---------------------------------------------------------------------------

TEST(ResponseRampFile, RoundTripKeepsLevelsFramesAndMetadata) {
    TempDir dir;
    for (const int depth : {8, 16}) {
        SyntheticRamp s;
        s.bit_depth = depth;
        s.camera = {24, 16};
        ResponseRamp ramp = s.make(1);
        ramp.metadata_yaml = "exposure_us: 8000\nrig: paper-rig-effects";
        const fs::path folder = dir / ("ramp-" + std::to_string(depth));
        write_response_ramp(folder, ramp);
        EXPECT_TRUE(fs::exists(folder / "ramp.yaml"));
        EXPECT_TRUE(fs::exists(folder / "level-000.png"));
        EXPECT_TRUE(fs::exists(folder / "level-255.png"));
        const ResponseRamp back = read_response_ramp(folder);
        EXPECT_EQ(back.levels, ramp.levels);
        EXPECT_EQ(back.folder, folder);
        ASSERT_EQ(back.frames.size(), ramp.frames.size());
        for (std::size_t i = 0; i < ramp.frames.size(); ++i) {
            EXPECT_EQ(back.frames[i].bit_depth, depth);
            EXPECT_EQ(back.frames[i].u8.storage(), ramp.frames[i].u8.storage()) << i;
            EXPECT_EQ(back.frames[i].u16.storage(), ramp.frames[i].u16.storage()) << i;
        }
        EXPECT_NE(back.metadata_yaml.find("exposure_us: 8000"), std::string::npos)
            << back.metadata_yaml;
        // Written once: a folder is never overwritten.
        EXPECT_THROW(write_response_ramp(folder, ramp), IoError);
    }
}

TEST(ResponseRampFile, AnInconsistentRampIsRefusedBeforeWriting) {
    TempDir dir;
    SyntheticRamp s;
    s.camera = {8, 6};
    ResponseRamp ramp = s.make(1);
    ramp.frames.pop_back();
    expect_input_error([&] { write_response_ramp(dir / "r", ramp); }, dir / "r" / "ramp.yaml",
                       "frames", "16 frames for 17 levels");
    EXPECT_FALSE(fs::exists(dir / "r"));
    ramp = s.make(1);
    ramp.levels[3] = 16;
    expect_input_error([&] { write_response_ramp(dir / "r", ramp); }, dir / "r" / "ramp.yaml",
                       "levels[3]", "strictly increasing");
    EXPECT_FALSE(fs::exists(dir / "r"));
}

TEST(ResponseRampFile, MalformedRampsAreRefusedNamingFileAndField) {
    TempDir dir;
    SyntheticRamp s;
    s.camera = {8, 6};
    s.levels = {0, 128, 255};
    const fs::path good = dir / "good";
    write_response_ramp(good, s.make(1));
    const std::string frames = "frames: [level-000.png, level-128.png, level-255.png]\n";

    // A copy of the good ramp with another ramp.yaml.
    int copies = 0;
    auto ramp_with = [&](const std::string& yaml) {
        const fs::path folder = dir / ("bad-" + std::to_string(++copies));
        fs::copy(good, folder);
        write_text(folder / "ramp.yaml", yaml);
        return folder;
    };
    struct Case {
        std::string yaml, field, hint;
    };
    const std::string head = "format: fpp-response-ramp/1\n";
    const std::vector<Case> cases = {
        {"format: fpp-capture/1\nlevels: [0, 128, 255]\n" + frames, "format", "unknown format"},
        {head + "levels: [0, 128, 100]\n" + frames, "levels[2]", "strictly increasing"},
        {head + "levels: [0, 128, 300]\n" + frames, "levels[2]", "outside 0..255"},
        {head + "levels: [16, 128, 255]\n" + frames, "levels[0]", "first level must be 0"},
        {head + "levels: [0, 128, 254]\n" + frames, "levels[2]", "last level must be 255"},
        {head + "levels: [0, 255]\nframes: [level-000.png, level-255.png]\n", "levels",
         "at least 3"},
        {head + "levels: [0, 128.5, 255]\n" + frames, "levels[1]", "integer"},
        {head + "levels: [0, \"128\", 255]\n" + frames, "levels[1]", "quoted"},
        {head + "levels: [0, 64, 128, 255]\n" + frames, "frames", "3 frames listed for 4 levels"},
        {head + "levels: [0, 128, 255]\nframes: [level-000.png, level-000.png, level-255.png]\n",
         "frames[1]", "listed twice"},
        {head + "levels: [0, 128, 255]\nframes: [level-000.png, /tmp/x.png, level-255.png]\n",
         "frames[1]", "relative"},
        {head + "levels: [0, 128, 255]\nframes: [level-000.png, ../x.png, level-255.png]\n",
         "frames[1]", "inside the ramp folder"},
        {head + "levels: [0, 128, 255]\n" + frames + "exposure: 3\n", "exposure", "unknown key"},
        {head + frames, "levels", "missing field"},
        {head + "levels: [0, 128, 255\n" + frames, "", "not valid YAML"},
    };
    for (const Case& c : cases) {
        const fs::path folder = ramp_with(c.yaml);
        SCOPED_TRACE(c.yaml);
        expect_input_error([&] { read_response_ramp(folder); }, folder / "ramp.yaml", c.field,
                           c.hint);
    }

    // Frame files: missing, another size, another depth, not an image.
    auto broken_frame = [&](const std::function<void(const fs::path&)>& damage) {
        const fs::path folder = dir / ("frame-" + std::to_string(++copies));
        fs::copy(good, folder);
        damage(folder / "level-128.png");
        return folder;
    };
    fs::path f = broken_frame([](const fs::path& p) { fs::remove(p); });
    expect_input_error([&] { read_response_ramp(f); }, f / "level-128.png", "frames[1]",
                       "not found");
    f = broken_frame([](const fs::path& p) {
        fs::remove(p);
        write_png(p, Image<std::uint8_t>(9, 6));
    });
    expect_input_error([&] { read_response_ramp(f); }, f / "level-128.png", "frames[1]",
                       "9x6 pixels but frames[0] is 8x6");
    f = broken_frame([](const fs::path& p) {
        fs::remove(p);
        write_png(p, Image<std::uint16_t>(8, 6));
    });
    expect_input_error([&] { read_response_ramp(f); }, f / "level-128.png", "frames[1]",
                       "16-bit but frames[0] is 8-bit");
    f = broken_frame([](const fs::path& p) { write_text(p, "not a png"); });
    expect_input_error([&] { read_response_ramp(f); }, f / "level-128.png", "frames[1]", "");
    expect_input_error([&] { read_response_ramp(dir / "none"); }, dir / "none", "", "not a folder");
}

TEST(ProjectorResponseFile, RoundTripIsExact) {
    TempDir dir;
    SyntheticRamp s;
    ResponseRamp ramp = s.make(2);
    ramp.folder = "/sessions/s1/response";
    const ProjectorResponse r = fit_projector_response(ramp);
    const fs::path file = dir / "projector-response.yaml";
    save_projector_response(file, r);
    const ProjectorResponse back = load_projector_response(file);
    EXPECT_EQ(back.levels, r.levels);
    EXPECT_EQ(back.emitted, r.emitted); // bit-exact: shortest round-trip text
    EXPECT_EQ(back.pixels_used, r.pixels_used);
    EXPECT_EQ(back.ramp, "/sessions/s1/response");
    // A hand-written response without the fit's record reads too.
    write_text(file, "format: fpp-projector-response/1\nlevels: [0, 128, 255]\n"
                     "emitted: [0, 0.2, 1]\n");
    EXPECT_DOUBLE_EQ(load_projector_response(file).at(128), 0.2);
}

TEST(ProjectorResponseFile, MalformedResponsesAreRefusedNamingFileAndField) {
    TempDir dir;
    const fs::path file = dir / "response.yaml";
    const std::string head = "format: fpp-projector-response/1\n";
    struct Case {
        std::string yaml, field, hint;
    };
    const std::vector<Case> cases = {
        {head + "levels: [0, 128, 255]\nemitted: [0, 0.7, 0.5]\n", "emitted[2]", "not monotonic"},
        {head + "levels: [0, 128, 255]\nemitted: [0.01, 0.2, 1]\n", "emitted[0]", "start at 0"},
        {head + "levels: [0, 128, 255]\nemitted: [0, 0.2, 0.98]\n", "emitted[2]", "end at 1"},
        {head + "levels: [0, 128, 255]\nemitted: [0, 1]\n", "emitted", "2 values for 3 levels"},
        {head + "levels: [0, 128, 250]\nemitted: [0, 0.2, 1]\n", "levels[2]",
         "end at drive level 255"},
        {head + "levels: [0, 128, 128, 255]\nemitted: [0, 0.2, 0.3, 1]\n", "levels[2]",
         "strictly increasing"},
        {head + "levels: [0]\nemitted: [0]\n", "levels", "at least 2"},
        {head + "levels: [0, 255]\nemitted: [0, .nan]\n", "emitted[1]", "non-finite"},
        {head + "levels: [0, 255]\nemitted: [0, 1]\npixels_used: -4\n", "pixels_used",
         "whole number"},
        {head + "levels: [0, 255]\nemitted: [0, 1]\ngamma: 2.2\n", "gamma", "unknown key"},
        {"format: fpp-response-ramp/1\nlevels: [0, 255]\nemitted: [0, 1]\n", "format",
         "unknown format"},
        {head + "levels: [0, 255]\n", "emitted", "missing field"},
    };
    for (const Case& c : cases) {
        write_text(file, c.yaml);
        SCOPED_TRACE(c.yaml);
        expect_input_error([&] { load_projector_response(file); }, file, c.field, c.hint);
    }
    // Nothing invalid is written.
    ProjectorResponse r;
    r.levels = {0, 255};
    r.emitted = {0, 0.9};
    const fs::path out = dir / "out.yaml";
    expect_input_error([&] { save_projector_response(out, r); }, out, "emitted[1]", "end at 1");
    EXPECT_FALSE(fs::exists(out));
}
