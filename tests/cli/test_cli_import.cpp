// fpp-calib import: frames of SLStudio, SLMaster and OpenCV's structured_light
// become capture sets. On the real captures in ../shared/datasets the import
// from the bare frames and the tool's parameters must give the hand-written
// manifests there; on frames rendered here from each tool's own pattern
// formula (imports.md), or by the tool itself where it is installed
// (OpenCV's), our rendering of the imported sequence must match the tool's
// frames and the decode must find every projector column.

#include "test_support.hpp"

#include "fpp/calib/capture_import.hpp"
#include "fpp/capture_set.hpp"
#include "fpp/decoder.hpp"
#include "fpp/error.hpp"
#include "fpp/patterns.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/structured_light.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <initializer_list>
#include <map>
#include <numbers>
#include <string>
#include <vector>

namespace {

using fpp::test::TempDir;
namespace fs = std::filesystem;
using Frames = std::vector<cv::Mat>;
constexpr double kPi = std::numbers::pi;

fpp::test::ToolRun run_calib(const std::string& args, const TempDir& scratch) {
    return fpp::test::run_tool(fpp::test::calib_exe(), args, scratch.path());
}

std::string quote(const fs::path& p) {
    return fpp::test::shell_quote(p.string());
}

// --- the real captures ---

struct RealCase {
    const char* folder;  // under ../shared/datasets
    const char* options; // fpp-calib import options
};

class ImportRealCapture : public ::testing::TestWithParam<RealCase> {};

TEST_P(ImportRealCapture, GivesTheHandWrittenManifest) {
    const fs::path source = fpp::test::dataset(GetParam().folder);
    FPP_REQUIRE_DATASET(source);
    TempDir dir;
    // The bare frames, as the tool left them (no capture.yaml).
    const fs::path frames = dir / "frames";
    fs::create_directory(frames);
    for (const auto& entry : fs::directory_iterator(source))
        if (entry.path().extension() == ".png")
            fs::copy_file(entry.path(), frames / entry.path().filename());
    const fs::path out = dir / "imported";
    const auto run = run_calib(std::string("import ") + GetParam().options + " " + quote(frames) +
                                   " --out " + quote(out),
                               dir);
    ASSERT_EQ(run.exit_code, 0) << run.output;
    const fpp::CaptureManifest imported = fpp::read_manifest(out / "capture.yaml");
    const fpp::CaptureManifest hand = fpp::read_manifest(source / "capture.yaml");
    EXPECT_EQ(imported.sequence, hand.sequence);
    EXPECT_EQ(imported.frames, hand.frames);
    EXPECT_EQ(imported.camera, hand.camera);
    EXPECT_EQ(imported.projector, hand.projector);
    // And it decodes exactly as the hand-written set.
    const fpp::DecodeResult a = fpp::decode(fpp::read_capture_set(out));
    const fpp::DecodeResult b = fpp::decode(fpp::read_capture_set(source));
    ASSERT_EQ(a.proj_x.size(), b.proj_x.size());
    std::size_t differing = 0;
    for (int y = 0; y < a.camera.height; ++y)
        for (int x = 0; x < a.camera.width; ++x) {
            const float u = a.proj_x.at(x, y), v = b.proj_x.at(x, y);
            differing += !(u == v || (std::isnan(u) && std::isnan(v)));
        }
    EXPECT_EQ(differing, 0u);
}

INSTANTIATE_TEST_SUITE_P(
    Datasets, ImportRealCapture,
    ::testing::Values(
        RealCase{"slstudio/skull_2x3", "slstudio --codec 2x3 --projector 1824x1140"},
        RealCase{"slstudio/skull_3ps", "slstudio --codec 3 --projector 1824x1140"},
        RealCase{"slstudio/calibration/calseq1",
                 "slstudio --codec 2x3 --direction both --projector 1824x1140"},
        RealCase{"slmaster/monocular",
                 "slmaster --codec complementary --steps 12 --fringes 32 --projector 1920x1080"}),
    [](const auto& case_info) { // the dataset's folder: slstudio_skull_2x3
        std::string name = case_info.param.folder;
        std::replace(name.begin(), name.end(), '/', '_');
        return name;
    });

// --- each tool's patterns, from its own formula ---

cv::Mat profile_image(int width, int height, bool along_x, const std::function<double(int)>& f) {
    cv::Mat m(height, width, CV_8U);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            m.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(f(along_x ? x : y));
    return m;
}

// SLStudio pstools::computePhaseVector: 255 * 1/2 (1 + cos(2 pi i / pitch - phase)), truncated.
cv::Mat slstudio_fringe(int w, int h, bool x, double pitch, double phase) {
    return profile_image(
        w, h, x, [=](int i) { return 255.0 * 0.5 * (1 + std::cos(2 * kPi * i / pitch - phase)); });
}

Frames slstudio_2x3(int w, int h) {
    Frames f;
    for (int k = 0; k < 3; ++k)
        f.push_back(slstudio_fringe(w, h, true, w / 16.0, 2 * kPi / 3 * k));
    for (int k = 0; k < 3; ++k)
        f.push_back(slstudio_fringe(w, h, true, w, 2 * kPi / 3 * k));
    return f;
}

Frames slstudio_2p1(int w, int h) {
    return {slstudio_fringe(w, h, true, w, 0), slstudio_fringe(w, h, true, w, kPi / 2),
            cv::Mat(h, w, CV_8U, cv::Scalar(127.5))};
}

Frames slstudio_graycode(int w, int h) { // white, black, 10 planes of the column's Gray code
    Frames f{cv::Mat(h, w, CV_8U, cv::Scalar(255)), cv::Mat(h, w, CV_8U, cv::Scalar(0))};
    const int bits = static_cast<int>(std::ceil(std::log2(double(w))));
    for (int p = 0; p < 10; ++p)
        f.push_back(profile_image(w, h, true, [=](int j) {
            const unsigned g = static_cast<unsigned>(j) ^ (static_cast<unsigned>(j) >> 1);
            return 255.0 * ((g >> (bits - 1 - p)) & 1u);
        }));
    return f;
}

// CodecPhaseShiftModulated.cpp: nPhaseX = 24 fringes across the width (the
// preset once assumed 8, which decoded to nonsense with exit 0), nPhaseY =
// 16 carrier periods across the height.
Frames slstudio_modulated(int w, int h, double fringes) { // 3 x 3 products, then the cue
    Frames f;
    for (int sx = 0; sx < 3; ++sx)
        for (int sy = 0; sy < 3; ++sy) {
            cv::Mat m(h, w, CV_8U);
            for (int r = 0; r < h; ++r)
                for (int c = 0; c < w; ++c) {
                    const double lx =
                        0.5 + 0.5 * std::cos(2 * kPi * c / (w / fringes) - 2 * kPi / 3 * sx);
                    const double my =
                        0.5 + 0.5 * std::cos(2 * kPi * r / (h / 16.0) - 2 * kPi / 3 * sy);
                    m.at<std::uint8_t>(r, c) = cv::saturate_cast<std::uint8_t>(255 * lx * my);
                }
            f.push_back(m);
        }
    for (int k = 0; k < 3; ++k)
        f.push_back(slstudio_fringe(w, h, true, w, 2 * kPi / 3 * k));
    return f;
}

// SLStudio CodecPhaseShiftMicro: 3 frames of pitch 75.02 at phase 2 pi k / 3,
// then pitches 70.00 .. 80.00 at phase pi for odd indices, 0 for even ones.
Frames slstudio_micro(int w, int h) {
    const double pitches[] = {75.02, 70.00, 71.32, 72.47, 73.72, 76.23, 77.35, 78.40, 79.22, 80.00};
    Frames f;
    for (int k = 0; k < 3; ++k)
        f.push_back(slstudio_fringe(w, h, true, pitches[0], -2 * kPi / 3 * k));
    for (int i = 1; i < 10; ++i)
        f.push_back(slstudio_fringe(w, h, true, pitches[i], i % 2 == 1 ? kPi : 0.0));
    return f;
}

// SLMaster's phase frames: 127.5 + 127.5 cos(2 pi (k mod P) / P - pi + 2 pi i / N).
Frames slmaster_phase(int w, int h, int steps, int fringes) {
    Frames f;
    const int P = w / fringes;
    for (int i = 0; i < steps; ++i)
        f.push_back(profile_image(w, h, true, [=](int k) {
            return 127.5 +
                   127.5 * std::cos((k % P) / double(P) * 2 * kPi - kPi + 2 * kPi / steps * i);
        }));
    return f;
}

// SLMaster: its phase frames, then the Gray planes of width / 2^(i+1) blocks,
// reflected; shift-gray moves them by P/2.
Frames slmaster(int w, int h, int steps, int fringes, bool shifted) {
    Frames f = slmaster_phase(w, h, steps, fringes);
    const int P = w / fringes;
    const int planes = static_cast<int>(std::log2(double(fringes))) + (shifted ? 0 : 1);
    std::vector<int> sequential{0, 255};
    for (int i = 0; i < planes; ++i) {
        const int block = w / static_cast<int>(sequential.size());
        const std::vector<int> seq = sequential;
        const int shift = shifted ? P / 2 : 0;
        f.push_back(profile_image(w, h, true, [=](int k) {
            return double(seq[std::size_t(((k + shift) % w) / block)]);
        }));
        for (int j = int(sequential.size()) - 1; j >= 0; --j)
            sequential.push_back(sequential[std::size_t(j)]);
    }
    return f;
}

// SLMaster's interzone code: SLMaster's phase frames, then log4(fringes)
// frames of blocks of width / 4^(i+1) coloured 0, 85, 170, 255, each frame's
// sequence the previous one, reversed, again and reversed again.
Frames slmaster_interzone(int w, int h, int steps, int fringes) {
    Frames f = slmaster_phase(w, h, steps, fringes);
    std::vector<int> sequential{0, 85, 170, 255};
    for (int blocks = 4; blocks <= fringes; blocks *= 4) {
        const std::vector<int> seq = sequential;
        const int block = w / blocks;
        f.push_back(
            profile_image(w, h, true, [=](int k) { return double(seq[std::size_t(k / block)]); }));
        const std::vector<int> reversed(seq.rbegin(), seq.rend());
        sequential.clear();
        for (const auto* part : {&seq, &reversed, &seq, &reversed})
            sequential.insert(sequential.end(), part->begin(), part->end());
    }
    return f;
}

// SLMaster's three-frequency code: F, F - 6 and F - 11 fringes of period
// width / count (not rounded), `steps` frames each, the levels truncated.
Frames slmaster_three_frequency(int w, int h, int steps, int highest) {
    Frames f;
    for (const int count : {highest, highest - 6, highest - 11})
        for (int i = 0; i < steps; ++i)
            f.push_back(profile_image(w, h, true, [=](int k) {
                const double P = double(w) / count;
                const double t = k / P - std::floor(k / P);
                return std::floor(127.5 +
                                  127.5 * std::cos((2 * t - 1) * kPi + 2 * kPi / steps * i));
            }));
    return f;
}

// OpenCV GrayCodePattern (checked against libopencv_structured_light 4.6):
// ceil(log2) planes, columns then rows, MSB first, Gray bit 1 = white, each
// followed by its inverse; then white and black (getImagesForShadowMasks).
Frames opencv_graycode(int w, int h) {
    Frames f;
    for (bool x : {true, false}) {
        const int n = x ? w : h;
        const int bits = static_cast<int>(std::ceil(std::log2(double(n))));
        for (int p = 0; p < bits; ++p)
            for (int inverse = 0; inverse < 2; ++inverse)
                f.push_back(profile_image(w, h, x, [=](int j) {
                    const unsigned g = static_cast<unsigned>(j) ^ (static_cast<unsigned>(j) >> 1);
                    const unsigned bit = (g >> (bits - 1 - p)) & 1u;
                    return 255.0 * (inverse ? 1 - bit : bit);
                }));
    }
    f.push_back(cv::Mat(h, w, CV_8U, cv::Scalar(255)));
    f.push_back(cv::Mat(h, w, CV_8U, cv::Scalar(0)));
    return f;
}

// OpenCV SinusoidalPattern, by libopencv_structured_light itself: the three
// PSP patterns (the same for FTP and FAPS) for each of `counts` periods
// across the width (horizontal = false) or the height.
Frames opencv_sinusoidal(int w, int h, bool horizontal, std::initializer_list<int> counts) {
    Frames f;
    for (int count : counts) {
        auto params = cv::makePtr<cv::structured_light::SinusoidalPattern::Params>();
        params->width = w;
        params->height = h;
        params->nbrOfPeriods = count;
        params->methodId = cv::structured_light::PSP;
        params->horizontal = horizontal;
        Frames set;
        cv::structured_light::SinusoidalPattern::create(params)->generate(set);
        f.insert(f.end(), set.begin(), set.end());
    }
    return f;
}

struct RenderedCase {
    const char* name;
    const char* options;    // fpp-calib import options (projector added)
    const char* frame_name; // printf pattern of the tool's frame files
    int width, height;
    std::function<Frames(int, int)> frames;
    double max_level_difference; // our render of the imported sequence vs the tool's frames
    double decode_tolerance;     // px, |decoded - column| for every decoded pixel
    bool decodes_y;
    bool decodes_x = true;
};

std::vector<RenderedCase> rendered_cases() {
    return {
        {"slstudio_2x3", "slstudio --codec 2x3", "frameSeq_%02d.bmp", 320, 96, slstudio_2x3, 1,
         0.05, false},
        // One period across 320 px: one 8-bit level (1/127.5 rad) is 0.4 px.
        {"slstudio_2p1", "slstudio --codec 2p1", "frameSeq_%02d.bmp", 320, 96, slstudio_2p1, 1, 1.0,
         false},
        // SLStudio shows 10 column planes: a projector of 513..1024 columns.
        {"slstudio_graycode", "slstudio --codec graycode", "frameSeq_%02d.bmp", 1024, 32,
         slstudio_graycode, 0, 0.5, false},
        {"slstudio_modulated", "slstudio --codec modulated", "frameSeq_%02d.bmp", 320, 96,
         [](int w, int h) { return slstudio_modulated(w, h, 24); }, 1, 0.5, false},
        // A build with other constants: its frames and the override agree.
        {"slstudio_modulated_8", "slstudio --codec modulated --modulated-phases 8",
         "frameSeq_%02d.bmp", 320, 96, [](int w, int h) { return slstudio_modulated(w, h, 8); }, 1,
         0.5, false},
        // 75 px fringes: one 8-bit level (1/127.5 rad) is 0.09 px.
        {"slstudio_micro", "slstudio --codec micro", "frameSeq_%02d.bmp", 320, 96, slstudio_micro,
         1, 0.2, false},
        {"slmaster_complementary", "slmaster --codec complementary --steps 4 --fringes 8",
         "%02d.bmp", 320, 96, [](int w, int h) { return slmaster(w, h, 4, 8, false); }, 1, 0.05,
         false},
        // The last half period repeats step 0's code: a wrapping gray block.
        {"slmaster_shift_gray", "slmaster --codec shift-gray --steps 4 --fringes 8", "%02d.bmp",
         320, 96, [](int w, int h) { return slmaster(w, h, 4, 8, true); }, 1, 0.05, false},
        // SLMaster's defaults: 3 steps, 16 fringes of 20 px, two four-level frames.
        {"slmaster_interzone", "slmaster --codec interzone", "%02d.bmp", 320, 96,
         [](int w, int h) { return slmaster_interzone(w, h, 3, 16); }, 1, 0.05, false},
        // SLMaster's defaults: 4 steps of 32, 26 and 21 fringes (10, 12.3, 15.2 px).
        {"slmaster_three_frequency", "slmaster --codec three-frequency", "%02d.bmp", 320, 96,
         [](int w, int h) { return slmaster_three_frequency(w, h, 4, 32); }, 1, 0.05, false},
        {"opencv_graycode", "opencv --codec graycode --direction both", "pattern_%02d.png", 320, 96,
         opencv_graycode, 0, 0.5, true},
        // 20 px fringes: one 8-bit level (1/127.5 rad) is 0.025 px.
        {"opencv_sinusoidal", "opencv --codec sinusoidal --fringe-counts 1,4,16",
         "pattern_%02d.png", 320, 96,
         [](int w, int h) {
             return opencv_sinusoidal(w, h, false, {1, 4, 16});
         },
         1, 0.05, false},
        {"opencv_sinusoidal_y", "opencv --codec sinusoidal --direction y --fringe-counts 1,4",
         "pattern_%02d.png", 320, 96,
         [](int w, int h) {
             return opencv_sinusoidal(w, h, true, {1, 4});
         },
         1, 0.05, true, false},
    };
}

class ImportRendered : public ::testing::TestWithParam<RenderedCase> {};

std::vector<RenderedCase> cases_storage = rendered_cases();

TEST_P(ImportRendered, MatchesTheToolAndDecodes) {
    const RenderedCase& c = GetParam();
    TempDir dir;
    const fs::path frames = dir / "frames";
    fs::create_directory(frames);
    const Frames tool = c.frames(c.width, c.height);
    std::map<std::string, std::size_t> tool_index; // file name -> tool frame
    for (std::size_t i = 0; i < tool.size(); ++i) {
        char name[64];
        std::snprintf(name, sizeof name, c.frame_name, int(i));
        tool_index[name] = i;
        // What a linear camera below saturation records of the pattern.
        cv::Mat camera;
        tool[i].convertTo(camera, CV_8U, 0.9, 12.0);
        ASSERT_TRUE(cv::imwrite((frames / name).string(), camera));
    }
    const fs::path out = dir / "imported";
    const std::string projector = std::to_string(c.width) + "x" + std::to_string(c.height);
    const auto run = run_calib(std::string("import ") + c.options + " --projector " + projector +
                                   " " + quote(frames) + " --out " + quote(out),
                               dir);
    ASSERT_EQ(run.exit_code, 0) << run.output;
    const fpp::CaptureSet set = fpp::read_capture_set(out);

    // Our rendering of the imported sequence is the tool's pattern, frame by
    // frame in the manifest's order.
    const auto ours = fpp::render_sequence(set.manifest.sequence, set.manifest.projector);
    ASSERT_EQ(ours.size(), tool.size());
    double worst = 0;
    for (std::size_t i = 0; i < ours.size(); ++i) {
        const cv::Mat& frame = tool[tool_index.at(set.manifest.frames[i])];
        for (int y = 0; y < c.height; ++y)
            for (int x = 0; x < c.width; ++x)
                worst = std::max(worst, std::fabs(double(ours[i].at(x, y)) -
                                                  double(frame.at<std::uint8_t>(y, x))));
    }
    EXPECT_LE(worst, c.max_level_difference) << "largest level difference over every frame";

    // Decoded as camera frames (camera = projector): every pixel finds its column.
    const fpp::DecodeResult r = fpp::decode(set);
    ASSERT_EQ(r.proj_x.empty(), !c.decodes_x);
    ASSERT_EQ(r.proj_y.empty(), !c.decodes_y);
    std::size_t valid = 0, wrong = 0;
    double sum2 = 0;
    for (int y = 0; y < c.height; ++y)
        for (int x = 0; x < c.width; ++x) {
            // The first coded axis decides validity and carries the RMS.
            const double u = c.decodes_x ? r.proj_x.at(x, y) : r.proj_y.at(x, y);
            const int truth = c.decodes_x ? x : y;
            if (std::isnan(u))
                continue;
            ++valid;
            sum2 += (u - truth) * (u - truth);
            wrong += std::fabs(u - truth) > c.decode_tolerance;
            if (c.decodes_x && c.decodes_y) {
                const double v = r.proj_y.at(x, y);
                wrong += std::isnan(v) || std::fabs(v - y) > c.decode_tolerance;
            }
        }
    const double pixels = double(c.width) * c.height;
    EXPECT_GE(double(valid) / pixels, 0.99) << valid << " of " << pixels << " decoded";
    EXPECT_EQ(wrong, 0u) << "RMS " << std::sqrt(sum2 / std::max<double>(1.0, double(valid)));
    std::printf("[ figures  ] %s: level difference %.0f, decoded %.2f %%, RMS %.3f px\n", c.name,
                worst, 100.0 * double(valid) / pixels,
                std::sqrt(sum2 / std::max<double>(1.0, double(valid))));
}

INSTANTIATE_TEST_SUITE_P(Tools, ImportRendered, ::testing::ValuesIn(cases_storage),
                         [](const auto& test_info) { return std::string(test_info.param.name); });

// --- refusals ---

TEST(CliImport, RefusesWithNamedErrors) {
    TempDir dir;
    const fs::path frames = dir / "frames";
    fs::create_directory(frames);
    const Frames tool = slstudio_2x3(320, 96);
    for (std::size_t i = 0; i + 1 < tool.size(); ++i) // one frame short
        cv::imwrite((frames / ("frameSeq_0" + std::to_string(i) + ".bmp")).string(), tool[i]);
    const std::string base = "import slstudio --projector 320x96 " + quote(frames);
    auto r = run_calib(base + " --codec 2x3 --out " + quote(dir / "a"), dir);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(frames.string() + ": frames: found 5 image files"), std::string::npos)
        << r.output;
    EXPECT_FALSE(fs::exists(dir / "a"));

    cv::imwrite((frames / "frameSeq_05.bmp").string(), cv::Mat(97, 320, CV_8U, cv::Scalar(0)));
    r = run_calib(base + " --codec 2x3 --out " + quote(dir / "b"), dir);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("frameSeq_05.bmp: frames[5]: frame is 320x97 8-bit"), std::string::npos)
        << r.output;
    EXPECT_FALSE(fs::exists(dir / "b"));

    r = run_calib(base + " --codec 4x4 --out " + quote(dir / "c"), dir);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("codec: unknown SLStudio codec '4x4'"), std::string::npos) << r.output;

    r = run_calib("import slmaster --projector 320x96 --codec complementary --fringes 6 " +
                      quote(frames) + " --out " + quote(dir / "d"),
                  dir);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("fringes: SLMaster needs a fringe count"), std::string::npos)
        << r.output;

    // SLMaster's other presets: parameters its generators cannot have used,
    // and six frames where its interzone code has five (three phase frames,
    // two four-level frames).
    const std::string slmaster = "import slmaster --projector 320x96 " + quote(frames) + " --out ";
    const std::vector<std::pair<std::string, std::string>> slmaster_cases = {
        {"--codec interzone --fringes 8",
         "fringes: SLMaster's interzone code needs a fringe count (nbrOfPeriods) that is a "
         "power of 4"},
        {"--codec interzone --fringes 256",
         "fringes: the projector's 320 pixels are not a multiple of 256"},
        {"--codec interzone --steps 4", "steps: SLMaster's interzone code needs an odd shiftTime"},
        {"--codec three-frequency --fringes 11",
         "fringes: SLMaster's three-frequency code shows nbrOfPeriods"},
        {"--codec interzone",
         "frames: found 6 image files (PNG, TIFF, BMP), but slmaster's interzone (direction x) "
         "has 5 frames: phase (3), gray (2)"},
    };
    for (const auto& [options, message] : slmaster_cases) {
        r = run_calib(slmaster + quote(dir / "s") + " " + options, dir);
        EXPECT_EQ(r.exit_code, 2) << options << ": " << r.output;
        EXPECT_NE(r.output.find(message), std::string::npos) << options << ": " << r.output;
        EXPECT_FALSE(fs::exists(dir / "s"));
    }

    const std::string sinusoidal =
        "import opencv --projector 320x96 --codec sinusoidal " + quote(frames) + " --out ";
    r = run_calib(sinusoidal + quote(dir / "e") + " --fringe-counts 16", dir);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("fringe-counts: one set of 16 fringes tells the position within a "
                            "fringe only"),
              std::string::npos)
        << r.output;
    r = run_calib(sinusoidal + quote(dir / "f") + " --fringe-counts 1,200", dir);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("fringe-counts: 200 fringes across 320 pixels: need 1 .. 106"),
              std::string::npos)
        << r.output;
    r = run_calib(sinusoidal + quote(dir / "g") + " --fringe-counts 1 --direction both", dir);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("direction: OpenCV's SinusoidalPattern codes one axis per set"),
              std::string::npos)
        << r.output;
    r = run_calib(sinusoidal + quote(dir / "h"), dir);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("fringe-counts: give nbrOfPeriods of each set"), std::string::npos)
        << r.output;
    for (const char* name : {"e", "f", "g", "h"})
        EXPECT_FALSE(fs::exists(dir / name));
}

} // namespace
