// fpp-calib simulate and decode, run as a person would: exit codes, files
// written, and nothing written on bad input.

#include "test_support.hpp"

#include "fpp/capture_set.hpp"
#include "fpp/decode_accuracy.hpp"
#include "fpp/image_io.hpp"
#include "fpp/simulator/rig.hpp"

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

namespace {

using fpp::test::TempDir;
namespace fs = std::filesystem;

using fpp::test::ToolRun;

std::string quote(const std::string& s) {
    return fpp::test::shell_quote(s);
}

ToolRun run_calib(const std::string& args, const TempDir& scratch) {
    return fpp::test::run_tool(fpp::test::calib_exe(), args, scratch.path());
}

// The paper rig with the camera shrunk 4x (same field of view) so that a
// whole simulate-and-decode round trip takes a fraction of a second.
fs::path write_small_rig(const TempDir& dir) {
    fpp::sim::Rig rig = fpp::sim::Rig::paper();
    rig.name = "paper-quarter";
    rig.camera_size = {400, 300};
    rig.camera.fu /= 4;
    rig.camera.fv /= 4;
    rig.camera.skew /= 4;
    rig.camera.cu = (rig.camera.cu + 0.5) / 4 - 0.5;
    rig.camera.cv = (rig.camera.cv + 0.5) / 4 - 0.5;
    const fs::path path = dir / "rig.yaml";
    std::ofstream(path) << fpp::sim::rig_to_yaml(rig);
    return path;
}

// A gray-x capture of the plane scene on the small rig, written to `capture`.
ToolRun simulate_gray_x_plane(const TempDir& dir, const fs::path& capture) {
    return run_calib("simulate --rig " + quote(write_small_rig(dir).string()) +
                         " --scene plane --sequence gray-x --out " + quote(capture.string()),
                     dir);
}

TEST(CliDecode, SimulatedPlaneDecodesToGroundTruth) {
    TempDir dir;
    const fs::path rig = write_small_rig(dir);
    const fs::path capture = dir / "capture";
    const fs::path out = dir / "decoded";
    auto sim = run_calib("simulate --rig " + quote(rig.string()) +
                             " --scene plane --sequence gray-xy --out " + quote(capture.string()),
                         dir);
    ASSERT_EQ(sim.exit_code, 0) << sim.output;
    auto dec =
        run_calib("decode " + quote(capture.string()) + " --out " + quote(out.string()), dir);
    ASSERT_EQ(dec.exit_code, 0) << dec.output;

    for (const char* name :
         {"proj_x.tiff", "proj_y.tiff", "modulation.tiff", "mask.png", "flags.png", "proj_x.png",
          "proj_y.png", "modulation.png", "decode.md"})
        EXPECT_TRUE(fs::exists(out / name)) << name;

    const auto truth = fpp::read_tiff_float(capture / "truth_proj.tiff");
    const auto px = fpp::read_tiff_float(out / "proj_x.tiff");
    const auto py = fpp::read_tiff_float(out / "proj_y.tiff");
    ASSERT_EQ(px.size(), (fpp::Size{400, 300}));
    const auto ax = fpp::compare_to_truth(px, truth, 0, 20.0);
    const auto ay = fpp::compare_to_truth(py, truth, 1, 20.0);
    EXPECT_EQ(ax.unwrap_errors, 0u);
    EXPECT_EQ(ay.unwrap_errors, 0u);
    EXPECT_LT(ax.rms_px, 0.02);
    EXPECT_LT(ay.rms_px, 0.02);
    EXPECT_GT(ax.coverage(), 0.98);
    EXPECT_NE(dec.output.find("Error against ground truth"), std::string::npos) << dec.output;
    // The report counts the pixels (fpp/decode_report.hpp): the plane fills
    // the view, every lit pixel decodes and the counts add up to the image.
    std::ostringstream text;
    text << std::ifstream(out / "decode.md").rdbuf();
    const std::string report = text.str();
    EXPECT_NE(report.find("(coverage of lit 100.00 %)"), std::string::npos) << report;
    EXPECT_NE(report.find("lit floor"), std::string::npos) << report;
    for (const char* reason : {"| dark (not lit) |", "| saturated | 0 |", "| low modulation |",
                               "| code and phase disagree | 0 |", "| out of range",
                               "| no cue | 0 |", "| other (no flag) | 0 |"})
        EXPECT_NE(report.find(reason), std::string::npos) << reason << "\n" << report;
    EXPECT_EQ(report.find("## Diagnosis"), std::string::npos) << report;
}

// A capture whose description has the wrong shift direction in one phase
// block: decode names the fix, exits 3 and still writes its outputs.
TEST(CliDecode, ReversedShiftIsDiagnosedAndExitsNonZero) {
    TempDir dir;
    const fs::path rig = write_small_rig(dir);
    const fs::path capture = dir / "capture";
    auto sim =
        run_calib("simulate --rig " + quote(rig.string()) +
                      " --scene plane --sequence heterodyne-x --out " + quote(capture.string()),
                  dir);
    ASSERT_EQ(sim.exit_code, 0) << sim.output;
    fpp::CaptureManifest manifest = fpp::read_manifest(capture / "capture.yaml");
    std::get<fpp::PhaseBlock>(manifest.sequence[2]).shift_sign = -1;
    std::ofstream(capture / "capture.yaml") << fpp::manifest_to_yaml(manifest);

    const fs::path out = dir / "decoded";
    auto dec =
        run_calib("decode " + quote(capture.string()) + " --out " + quote(out.string()), dir);
    EXPECT_EQ(dec.exit_code, 3) << dec.output;
    EXPECT_NE(dec.output.find("With shift_sign 1 in sequence[2], 100 % of lit pixels decode"),
              std::string::npos)
        << dec.output;
    EXPECT_TRUE(fs::exists(out / "proj_x.tiff"));
    std::ostringstream text;
    text << std::ifstream(out / "decode.md").rdbuf();
    EXPECT_NE(text.str().find("## Diagnosis"), std::string::npos) << text.str();
}

TEST(CliDecode, BadOptionNamesTheOptionAndWritesNothing) {
    TempDir dir;
    const fs::path capture = dir / "capture";
    ASSERT_EQ(simulate_gray_x_plane(dir, capture).exit_code, 0);
    const fs::path out = dir / "out";
    auto run = run_calib("decode " + quote(capture.string()) + " --min-modulation 1.5 --out " +
                             quote(out.string()),
                         dir);
    EXPECT_EQ(run.exit_code, 2) << run.output;
    EXPECT_NE(run.output.find("command line: --min-modulation: "), std::string::npos) << run.output;
    EXPECT_NE(run.output.find("in [0, 1)"), std::string::npos) << run.output;
    EXPECT_FALSE(fs::exists(out));
}

TEST(CliDecode, MalformedManifestExitsNonZeroAndWritesNothing) {
    TempDir dir;
    const fs::path capture = dir / "bad";
    fs::create_directories(capture);
    std::ofstream(capture / "capture.yaml")
        << "format: fpp-capture/1\n"
           "camera: {width: 4, height: 4}\n"
           "projector: {width: 8, height: 8}\n"
           "frames: [a.png, b.png, c.png]\n"
           "sequence:\n"
           "  - {pattern: phase, axis: x, period: -2.0, steps: 3}\n";
    const fs::path out = dir / "out";
    auto run =
        run_calib("decode " + quote(capture.string()) + " --out " + quote(out.string()), dir);
    EXPECT_EQ(run.exit_code, 2) << run.output;
    EXPECT_NE(run.output.find("capture.yaml"), std::string::npos) << run.output;
    EXPECT_NE(run.output.find("period"), std::string::npos) << run.output;
    EXPECT_FALSE(fs::exists(out));
}

TEST(CliDecode, MissingFrameNamesTheFrame) {
    TempDir dir;
    const fs::path capture = dir / "capture";
    ASSERT_EQ(simulate_gray_x_plane(dir, capture).exit_code, 0);
    fs::remove(capture / "005.png");
    const fs::path out = dir / "out";
    auto run =
        run_calib("decode " + quote(capture.string()) + " --out " + quote(out.string()), dir);
    EXPECT_EQ(run.exit_code, 2) << run.output;
    EXPECT_NE(run.output.find("005.png"), std::string::npos) << run.output;
    EXPECT_FALSE(fs::exists(out));
}

TEST(CliSimulate, RefusesToOverwriteACaptureSet) {
    TempDir dir;
    const fs::path rig = write_small_rig(dir);
    const fs::path capture = dir / "capture";
    fs::create_directories(capture);
    auto run = run_calib(
        "simulate --rig " + quote(rig.string()) + " --out " + quote(capture.string()), dir);
    EXPECT_NE(run.exit_code, 0);
    EXPECT_NE(run.output.find("already exists"), std::string::npos) << run.output;
    EXPECT_TRUE(fs::is_empty(capture));
}

TEST(CliSimulate, UnknownSceneIsAnError) {
    TempDir dir;
    auto run =
        run_calib("simulate --scene no-such-scene --out " + quote((dir / "c").string()), dir);
    EXPECT_NE(run.exit_code, 0);
    EXPECT_NE(run.output.find("no-such-scene"), std::string::npos) << run.output;
    EXPECT_FALSE(fs::exists(dir / "c"));
}

} // namespace

TEST(CliDecode, CorrectPhaseErrorRemovesAProjectorGammasErrorFromTheCaptureAlone) {
    // A 3-step sequence on a projector of gamma 2.2 that nobody measured:
    // decode as is, then with --correct-phase-error.
    TempDir dir;
    fpp::sim::Rig rig = fpp::sim::load_rig(write_small_rig(dir));
    rig.projector_optics.gamma = 2.2;
    const fs::path rig_file = dir / "gamma-rig.yaml";
    std::ofstream(rig_file) << fpp::sim::rig_to_yaml(rig);
    const fs::path sequence = dir / "three-step.yaml";
    std::ofstream(sequence) << "sequence:\n  - {pattern: white}\n  - {pattern: black}\n"
                               "  - {pattern: phase, axis: x, period: 20, steps: 3}\n"
                               "  - {pattern: gray, axis: x, period: 20, bits: 6, "
                               "complementary: true}\n";
    const fs::path capture = dir / "capture";
    auto sim = run_calib("simulate --rig " + quote(rig_file.string()) +
                             " --scene inclined-plane --sequence " + quote(sequence.string()) +
                             " --out " + quote(capture.string()),
                         dir);
    ASSERT_EQ(sim.exit_code, 0) << sim.output;
    const auto truth = fpp::read_tiff_float(capture / "truth_proj.tiff");
    double rms[2] = {0, 0};
    for (int corrected = 0; corrected < 2; ++corrected) {
        const fs::path out = dir / (corrected ? "corrected" : "as-is");
        auto dec = run_calib("decode " + quote(capture.string()) + " --out " + quote(out.string()) +
                                 (corrected ? " --correct-phase-error" : ""),
                             dir);
        ASSERT_EQ(dec.exit_code, 0) << dec.output;
        const auto a =
            fpp::compare_to_truth(fpp::read_tiff_float(out / "proj_x.tiff"), truth, 0, 20.0);
        EXPECT_GT(a.coverage(), 0.98);
        rms[corrected] = a.rms_px;
        std::ostringstream text;
        text << std::ifstream(out / "decode.md").rdbuf();
        const std::string report = text.str();
        EXPECT_EQ(report.find("phase-error correction (x): applied") != std::string::npos,
                  corrected == 1)
            << report;
    }
    std::printf("3 steps, gamma 2.2: projector x RMS %.4f px as is, %.4f px corrected\n", rms[0],
                rms[1]);
    EXPECT_GT(rms[0], 0.3);
    EXPECT_LT(rms[1], rms[0] / 5);
}
