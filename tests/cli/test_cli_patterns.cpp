// fpp-calib patterns: the projector images of a sequence plus a capture.yaml
// template. Decoding the written projector images as if they were the camera
// frames (camera = projector size) must give every pixel its own column (and
// row) within the family's resolution.

#include "test_support.hpp"

#include "fpp/capture_set.hpp"
#include "fpp/decoder.hpp"
#include "fpp/image_io.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

namespace {

using fpp::test::TempDir;
namespace fs = std::filesystem;

fpp::test::ToolRun run_calib(const std::string& args, const TempDir& scratch) {
    return fpp::test::run_tool(fpp::test::calib_exe(), args, scratch.path());
}

std::string quote(const fs::path& p) {
    return fpp::test::shell_quote(p.string());
}

struct Accuracy {
    double coverage = 0; // decoded fraction of the pixels
    double worst = 0;    // px, |decoded - own coordinate|, both axes
};

// Copies the projector images to the frame names capture.yaml lists (as a
// user saves camera frames, through a linear camera) and decodes.
Accuracy decode_own_patterns(const fs::path& out, const std::string& extension) {
    const fpp::CaptureManifest m = fpp::read_manifest(out / "capture.yaml");
    for (std::size_t i = 0; i < m.frames.size(); ++i) {
        char name[64];
        std::snprintf(name, sizeof name, "pattern_%02d.%s", int(i), extension.c_str());
        const cv::Mat image = cv::imread((out / "projector" / name).string(), cv::IMREAD_UNCHANGED);
        EXPECT_FALSE(image.empty()) << name;
        // What a linear camera below saturation records of the pattern.
        cv::Mat camera;
        image.convertTo(camera, CV_8U, 0.9, 12.0);
        EXPECT_TRUE(cv::imwrite((out / m.frames[i]).string(), camera));
    }
    const fpp::CaptureSet set = fpp::read_capture_set(out);
    const fpp::DecodeResult r = fpp::decode(set);
    Accuracy a;
    std::size_t valid = 0;
    for (int y = 0; y < r.camera.height; ++y)
        for (int x = 0; x < r.camera.width; ++x) {
            const float u = r.proj_x.empty() ? float(x) : r.proj_x.at(x, y);
            const float v = r.proj_y.empty() ? float(y) : r.proj_y.at(x, y);
            if (std::isnan(u) || std::isnan(v))
                continue;
            ++valid;
            a.worst = std::max({a.worst, std::fabs(double(u) - x), std::fabs(double(v) - y)});
        }
    a.coverage = double(valid) / (double(r.camera.width) * r.camera.height);
    return a;
}

TEST(CliPatterns, StandardSequenceDecodesToItsOwnPixels) {
    TempDir dir;
    const fs::path out = dir / "set";
    const auto run = run_calib("patterns --sequence gray-xy --projector 400x240 --camera 400x240 "
                               "--out " +
                                   quote(out),
                               dir);
    ASSERT_EQ(run.exit_code, 0) << run.output;
    EXPECT_TRUE(fs::exists(out / "README.txt"));
    const fpp::CaptureManifest m = fpp::read_manifest(out / "capture.yaml");
    EXPECT_EQ(m.frames.front(), "frame_00.png");
    EXPECT_EQ(m.camera, (fpp::Size{400, 240}));
    const Accuracy a = decode_own_patterns(out, "png");
    EXPECT_GE(a.coverage, 0.999);
    EXPECT_LT(a.worst, 0.05); // 8-step phase, period 20: quantisation only
    std::printf("[ figures  ] gray-xy: decoded %.3f %%, worst %.4f px\n", 100 * a.coverage,
                a.worst);
}

TEST(CliPatterns, CodeOnlySequenceAsBmp) {
    TempDir dir;
    std::ofstream(dir / "seq.yaml")
        << "sequence:\n"
           "  - {pattern: white}\n"
           "  - {pattern: black}\n"
           "  - {pattern: gray, axis: x, period: 1, bits: 9, inverse: true}\n"
           "  - {pattern: gray, axis: y, period: 1, bits: 8, inverse: true}\n";
    const fs::path out = dir / "set";
    const auto run = run_calib("patterns --sequence " + quote(dir / "seq.yaml") +
                                   " --projector 400x240 --camera 400x240 --image-format bmp "
                                   "--out " +
                                   quote(out),
                               dir);
    ASSERT_EQ(run.exit_code, 0) << run.output;
    EXPECT_TRUE(fs::exists(out / "projector" / "pattern_35.bmp"));
    const Accuracy a = decode_own_patterns(out, "bmp");
    EXPECT_GE(a.coverage, 0.999);
    EXPECT_LE(a.worst, 0.5); // a code step of 1 px
    std::printf("[ figures  ] gray code, period 1: decoded %.3f %%, worst %.4f px\n",
                100 * a.coverage, a.worst);
}

TEST(CliPatterns, GammaChangesTheLevelsAndBadInputIsNamed) {
    TempDir dir;
    auto run = run_calib("patterns --sequence gray-x --projector 64x8 --camera 64x8 --gamma 2.2 "
                         "--out " +
                             quote(dir / "g"),
                         dir);
    ASSERT_EQ(run.exit_code, 0) << run.output;
    run = run_calib(
        "patterns --sequence gray-x --projector 64x8 --camera 64x8 --out " + quote(dir / "l"), dir);
    ASSERT_EQ(run.exit_code, 0) << run.output;
    // A mid-grey fringe level is brighter once pre-compensated for gamma 2.2.
    const cv::Mat g =
        cv::imread((dir / "g" / "projector" / "pattern_02.png").string(), cv::IMREAD_UNCHANGED);
    const cv::Mat l =
        cv::imread((dir / "l" / "projector" / "pattern_02.png").string(), cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(g.empty());
    EXPECT_GT(cv::mean(g)[0], cv::mean(l)[0] + 20);

    run = run_calib("patterns --sequence gray-x --projector 64by8 --camera 64x8 --out " +
                        quote(dir / "bad"),
                    dir);
    EXPECT_EQ(run.exit_code, 2) << run.output;
    EXPECT_NE(run.output.find("--projector: expected WIDTHxHEIGHT"), std::string::npos)
        << run.output;
    EXPECT_FALSE(fs::exists(dir / "bad"));
}

} // namespace
