// fpp-calib reconstruct, run as a person would: a small simulated capture end
// to end (PLY and XYZ TIFF against the ground truth), and bad inputs that
// must exit with 2, name what is wrong and leave no output behind.

#include "calib_run.hpp"
#include "test_support.hpp"

#include "fpp/calib/simulated_rig.hpp"
#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/capture_set.hpp"
#include "fpp/image_io.hpp"
#include "fpp/point_cloud.hpp"
#include "fpp/simulator/rig.hpp"
#include "fpp/yaml_fields.hpp"

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
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

std::string q(const fs::path& p) {
    return quote(p.string());
}

using fpp::test::run_calib;

// The paper rig with the camera binned 4x (400 x 300, same field of view).
fpp::sim::Rig small_rig() {
    fpp::sim::Rig rig = fpp::sim::Rig::paper().binned_camera(4);
    rig.name = "paper-quarter";
    return rig;
}

// Captures and calibrations shared by the tests (simulated once).
class CliReconstruct : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        dir_ = new TempDir;
        const fs::path rig_file = *dir_ / "rig.yaml";
        std::ofstream(rig_file) << fpp::sim::rig_to_yaml(small_rig());
        for (const char* sequence : {"gray-xy", "gray-x", "plain-gray-x"}) {
            const auto sim =
                run_calib("simulate --rig " + q(rig_file) + " --scene plane --sequence " +
                              sequence + " --out " + q(*dir_ / sequence),
                          dir_->path());
            ASSERT_EQ(sim.exit_code, 0) << sim.output;
        }
        // Code-only: white, black and 10 Gray planes along x (step 1.25
        // projector columns), as SLStudio's Gray codec.
        std::ofstream(*dir_ / "gray-only.yaml")
            << "sequence:\n  - pattern: white\n  - pattern: black\n  - pattern: gray\n"
               "    axis: x\n    period: 1.25\n    bits: 10\n";
        // Micro phase shifting alone: 5 periods of 16 to 20.4 px (beats
        // 1400 / j px, j = 1, 11, 16, 19: tests/integration/core/test_decode_families.cpp).
        std::ofstream(*dir_ / "micro.yaml")
            << "sequence:\n  - pattern: micro_phase\n    axis: x\n"
               "    periods: [16.0, 16.184971, 18.300654, 19.58042, 20.437956]\n";
        // Phase alone in two periods (20 px, and one across the projector):
        // reversed, a field consistent with itself, mirrored.
        std::ofstream(*dir_ / "two-periods.yaml")
            << "sequence:\n  - {pattern: phase, axis: x, period: 20, steps: 4}\n"
               "  - {pattern: phase, axis: x, period: 1280, steps: 4}\n";
        for (const char* name : {"gray-only", "micro", "two-periods"}) {
            const auto sim = run_calib(
                "simulate --rig " + q(rig_file) + " --scene plane --sequence " +
                    q(*dir_ / (std::string(name) + ".yaml")) + " --out " + q(*dir_ / name),
                dir_->path());
            ASSERT_EQ(sim.exit_code, 0) << sim.output;
        }
        fpp::calib::save_calibration(*dir_ / "calib.yaml",
                                     fpp::calib::calibration_from_rig(small_rig()));
    }
    static void TearDownTestSuite() {
        delete dir_;
        dir_ = nullptr;
    }
    static fs::path path(const std::string& name) { return *dir_ / name; }

    static TempDir* dir_;
};

TempDir* CliReconstruct::dir_ = nullptr;

// A copy of a capture whose description has the projector's shift direction
// reversed in every phase block (the frames are as captured).
fs::path misdescribed_copy(const fs::path& from, const fs::path& to) {
    fs::copy(from, to, fs::copy_options::recursive);
    fpp::CaptureManifest manifest = fpp::read_manifest(to / "capture.yaml");
    for (auto& block : manifest.sequence)
        if (auto* phase = std::get_if<fpp::PhaseBlock>(&block))
            phase->shift_sign = -phase->shift_sign;
    std::ofstream(to / "capture.yaml") << fpp::manifest_to_yaml(manifest);
    return to;
}

bool folder_is_empty(const fs::path& folder) {
    return fs::is_empty(folder);
}

// fpp-calib reconstruct of one of the shared captures into `ply`, with the
// rig's calibration beside it (calib.yaml in the suite's folder).
ToolRun reconstruct_into(const fs::path& capture, const fs::path& ply, const fs::path& dir) {
    return run_calib("reconstruct " + q(capture) + " --calib " +
                         q(capture.parent_path() / "calib.yaml") + " --out " + q(ply),
                     dir);
}

// RMS distance (mm) of a cloud's points from the truth at their pixels.
double rms_against_truth(const fpp::PlyPoints& cloud, const fpp::Image<float>& truth) {
    double sum = 0;
    for (std::size_t k = 0; k < cloud.size(); ++k) {
        const std::size_t i = cloud.pixel[k];
        const double dx = double(cloud.x[k] - truth.data()[3 * i]);
        const double dy = double(cloud.y[k] - truth.data()[3 * i + 1]);
        const double dz = double(cloud.z[k] - truth.data()[3 * i + 2]);
        sum += dx * dx + dy * dy + dz * dz;
    }
    return std::sqrt(sum / double(std::max<std::size_t>(cloud.size(), 1)));
}

TEST_F(CliReconstruct, SimulatedPlaneEndToEnd) {
    TempDir out;
    const fs::path ply = out / "cloud.ply";
    const fs::path xyz = out / "xyz.tiff";
    const auto run = run_calib("reconstruct " + q(path("gray-xy")) + " --calib " +
                                   q(path("calib.yaml")) + " --out " + q(ply) + " --xyz " + q(xyz),
                               out.path());
    ASSERT_EQ(run.exit_code, 0) << run.output;
    EXPECT_NE(run.output.find("axes: xy"), std::string::npos) << run.output;
    EXPECT_NE(run.output.find("error against ground truth"), std::string::npos) << run.output;

    const fpp::PlyPoints cloud = fpp::read_ply(ply);
    const fpp::Image<float> truth = fpp::read_tiff_float(path("gray-xy") / "truth_xyz.tiff");
    const fpp::Image<float> map = fpp::read_tiff_float(xyz);
    ASSERT_EQ(cloud.organised, (fpp::Size{400, 300}));
    ASSERT_EQ(map.size(), (fpp::Size{400, 300}));
    ASSERT_EQ(map.channels(), 3);
    ASSERT_EQ(cloud.pixel.size(), cloud.size());
    EXPECT_GT(cloud.size(), 400u * 300u * 99 / 100); // the plane fills the field
    double sum = 0;
    for (std::size_t k = 0; k < cloud.size(); ++k) {
        const std::size_t i = cloud.pixel[k];
        ASSERT_LT(i, truth.pixel_count());
        // The TIFF holds the same point at that pixel.
        EXPECT_EQ(map.data()[3 * i], cloud.x[k]);
        EXPECT_EQ(map.data()[3 * i + 2], cloud.z[k]);
        const double dx = double(cloud.x[k] - truth.data()[3 * i]);
        const double dy = double(cloud.y[k] - truth.data()[3 * i + 1]);
        const double dz = double(cloud.z[k] - truth.data()[3 * i + 2]);
        sum += dx * dx + dy * dy + dz * dz;
        EXPECT_GT(cloud.quality[k], 20.0f); // modulation, DN
        EXPECT_GT(cloud.intensity[k], 20.0f);
    }
    EXPECT_LT(std::sqrt(sum / double(cloud.size())), 0.01); // mm
    // Pixels without a point are NaN in the TIFF.
    std::size_t nan_pixels = 0;
    for (std::size_t i = 0; i < map.pixel_count(); ++i)
        nan_pixels += std::isnan(map.data()[3 * i]);
    EXPECT_EQ(nan_pixels + cloud.size(), map.pixel_count());
}

TEST_F(CliReconstruct, XOnlyCaptureUsesTheIterativeSolve) {
    TempDir out;
    const fs::path ply = out / "cloud.ply";
    const auto run = reconstruct_into(path("gray-x"), ply, out.path());
    ASSERT_EQ(run.exit_code, 0) << run.output;
    EXPECT_NE(run.output.find("axes: x "), std::string::npos) << run.output;
    EXPECT_NE(run.output.find("x-only solve"), std::string::npos) << run.output;
    EXPECT_GT(fpp::read_ply(ply).size(), 400u * 300u * 99 / 100);
}

// A capture with no phase block reconstructs from its code alone, each pixel
// at its code step's centre: the error is that step's quantisation (about
// 0.43 projector px RMS here, 0.4 mm), not a refusal.
// (tests/integration/core/test_code_only_reconstruct_sim.cpp holds it to the
// quantisation floor at full resolution.)
TEST_F(CliReconstruct, CodeOnlyCaptureReconstructsAtItsCodeStep) {
    TempDir out;
    const fs::path ply = out / "cloud.ply";
    const auto run = reconstruct_into(path("gray-only"), ply, out.path());
    ASSERT_EQ(run.exit_code, 0) << run.output;
    EXPECT_NE(run.output.find("axes: x "), std::string::npos) << run.output;
    const fpp::PlyPoints cloud = fpp::read_ply(ply);
    EXPECT_GT(cloud.size(), 400u * 300u * 99 / 100);
    const double rms =
        rms_against_truth(cloud, fpp::read_tiff_float(path("gray-only") / "truth_xyz.tiff"));
    std::printf("[ figures  ] code-only reconstruction: %zu points, %.4f mm RMS against the "
                "truth\n",
                cloud.size(), rms);
    EXPECT_LT(rms, 0.6);
    EXPECT_GT(rms, 0.1); // a step's quantisation, not a phase's precision
}

// Micro phase shifting (no code, no other phase block) reconstructs to its
// phase's precision.
TEST_F(CliReconstruct, MicroPhaseCaptureReconstructs) {
    TempDir out;
    const fs::path ply = out / "cloud.ply";
    const auto run = reconstruct_into(path("micro"), ply, out.path());
    ASSERT_EQ(run.exit_code, 0) << run.output;
    const fpp::PlyPoints cloud = fpp::read_ply(ply);
    EXPECT_GT(cloud.size(), 400u * 300u * 97 / 100);
    const double rms =
        rms_against_truth(cloud, fpp::read_tiff_float(path("micro") / "truth_xyz.tiff"));
    std::printf("[ figures  ] micro phase reconstruction: %zu points, %.4f mm RMS against the "
                "truth\n",
                cloud.size(), rms);
    EXPECT_LT(rms, 0.05);
}

// Runs a reconstruction expected to fail with exit code 2 and a message
// holding every `needles`, and checks that nothing was written.
void expect_input_error(const std::string& args, const std::vector<std::string>& needles) {
    TempDir out;
    const auto run = run_calib(
        args + " --out " + q(out / "cloud.ply") + " --xyz " + q(out / "xyz.tiff"), out.path());
    EXPECT_EQ(run.exit_code, 2) << run.output;
    for (const auto& n : needles)
        EXPECT_NE(run.output.find(n), std::string::npos) << run.output;
    EXPECT_TRUE(folder_is_empty(out.path())) << "output left behind for: " << args;
}

TEST_F(CliReconstruct, AxisTheCaptureDoesNotCodeIsAnInputError) {
    expect_input_error("reconstruct " + q(path("gray-x")) + " --calib " + q(path("calib.yaml")) +
                           " --axes xy",
                       {"capture.yaml", "sequence", "along y"});
}

TEST_F(CliReconstruct, CalibrationWithAMissingKeyIsAnInputError) {
    TempDir dir;
    std::ifstream in(path("calib.yaml"));
    std::stringstream buffer;
    buffer << in.rdbuf();
    std::string text = buffer.str();
    // Drop the T block (key line and its indented lines).
    const std::size_t start = text.find("\nT: ");
    ASSERT_NE(start, std::string::npos);
    std::size_t end = text.find('\n', start + 1);
    while (end != std::string::npos && end + 1 < text.size() && text[end + 1] == ' ')
        end = text.find('\n', end + 1);
    text.erase(start, end - start);
    std::ofstream(dir / "broken.yaml") << text;
    expect_input_error("reconstruct " + q(path("gray-xy")) + " --calib " + q(dir / "broken.yaml"),
                       {"broken.yaml", "T: missing"});
}

TEST_F(CliReconstruct, CameraSizeMismatchIsAnInputError) {
    TempDir dir;
    // The full-resolution rig's calibration against the binned capture.
    fpp::calib::save_calibration(dir / "full.yaml",
                                 fpp::calib::calibration_from_rig(fpp::sim::Rig::paper()));
    expect_input_error("reconstruct " + q(path("gray-xy")) + " --calib " + q(dir / "full.yaml"),
                       {"full.yaml", "camera_size", "1600x1200", "400x300"});
}

TEST_F(CliReconstruct, ProjectorSizeMismatchIsAnInputError) {
    TempDir dir;
    fpp::calib::StereoCalibration c = fpp::calib::calibration_from_rig(small_rig());
    c.projector_size = {1920, 1080};
    fpp::calib::save_calibration(dir / "proj.yaml", c);
    expect_input_error("reconstruct " + q(path("gray-xy")) + " --calib " + q(dir / "proj.yaml"),
                       {"proj.yaml", "projector_size", "1920x1080", "1280x800"});
}

TEST_F(CliReconstruct, SizeOptionsFillOrContradictTheCalibration) {
    TempDir dir;
    // An SLMaster-style file: no sizes recorded.
    const fpp::calib::StereoCalibration c = fpp::calib::calibration_from_rig(small_rig());
    {
        std::ofstream out(dir / "caliInfo.yml");
        out << "%YAML:1.0\n---\n";
        auto matrix = [&](const char* key, int rows, int cols, const std::vector<double>& v) {
            out << key << ": !!opencv-matrix\n   rows: " << rows << "\n   cols: " << cols
                << "\n   dt: d\n   data: [";
            for (std::size_t i = 0; i < v.size(); ++i)
                out << (i ? ", " : " ") << v[i];
            out << " ]\n";
        };
        out.precision(17);
        const auto& k = c.camera;
        const auto& p = c.projector;
        matrix("M1", 3, 3, {k.fu, k.skew, k.cu, 0, k.fv, k.cv, 0, 0, 1});
        matrix("D1", 1, 5, {k.k1, k.k2, k.p1, k.p2, k.k3});
        matrix("M4", 3, 3, {p.fu, p.skew, p.cu, 0, p.fv, p.cv, 0, 0, 1});
        matrix("D4", 1, 5, {p.k1, p.k2, p.p1, p.p2, p.k3});
        matrix("Rlp", 3, 3, std::vector<double>(c.R.begin(), c.R.end()));
        matrix("Tlp", 3, 1, std::vector<double>(c.T.begin(), c.T.end()));
    }
    TempDir out;
    auto run =
        run_calib("reconstruct " + q(path("gray-xy")) + " --calib " + q(dir / "caliInfo.yml") +
                      " --calib-format slmaster --out " + q(out / "cloud.ply"),
                  out.path());
    ASSERT_EQ(run.exit_code, 0) << run.output;
    EXPECT_NE(run.output.find("records no camera size"), std::string::npos) << run.output;
    EXPECT_GT(fpp::read_ply(out / "cloud.ply").size(), 400u * 300u * 99 / 100);
    // A size given on the command line that the capture contradicts.
    expect_input_error("reconstruct " + q(path("gray-xy")) + " --calib " + q(dir / "caliInfo.yml") +
                           " --camera-size 1280x1024",
                       {"caliInfo.yml", "camera_size", "1280x1024", "400x300"});
    expect_input_error("reconstruct " + q(path("gray-xy")) + " --calib " + q(dir / "caliInfo.yml") +
                           " --projector-size 1280by800",
                       {"--projector-size", "WIDTHxHEIGHT"});
}

TEST_F(CliReconstruct, MissingFilesAreInputErrors) {
    TempDir dir;
    expect_input_error("reconstruct " + q(path("gray-xy")) + " --calib " + q(dir / "none.yaml"),
                       {"none.yaml"});
    expect_input_error("reconstruct " + q(dir / "no-capture") + " --calib " + q(path("calib.yaml")),
                       {"no-capture"});
    // Output into a folder that does not exist.
    TempDir out;
    const auto run =
        run_calib("reconstruct " + q(path("gray-xy")) + " --calib " + q(path("calib.yaml")) +
                      " --out " + q(out / "missing" / "cloud.ply"),
                  out.path());
    EXPECT_EQ(run.exit_code, 2) << run.output;
    EXPECT_NE(run.output.find("does not exist"), std::string::npos) << run.output;
    EXPECT_TRUE(folder_is_empty(out.path()));
}

TEST_F(CliReconstruct, UnknownFormatNameIsRejected) {
    TempDir out;
    const auto run =
        run_calib("reconstruct " + q(path("gray-xy")) + " --calib " + q(path("calib.yaml")) +
                      " --calib-format matlab --out " + q(out / "c.ply"),
                  out.path());
    EXPECT_NE(run.exit_code, 0);
    EXPECT_NE(run.output.find("matlab"), std::string::npos) << run.output;
    EXPECT_TRUE(folder_is_empty(out.path()));
}

// A failed decode gives the likely cause, exit 3 and no cloud, never an empty PLY.
TEST_F(CliReconstruct, MisdescribedCaptureWritesNoCloud) {
    TempDir out;
    const fs::path capture = misdescribed_copy(path("gray-x"), out / "capture");
    const fs::path ply = out / "cloud.ply";
    const auto run = run_calib("reconstruct " + q(capture) + " --calib " + q(path("calib.yaml")) +
                                   " --out " + q(ply),
                               out.path());
    EXPECT_EQ(run.exit_code, 3) << run.output;
    EXPECT_NE(run.output.find("shift_sign 1 in sequence[2]"), std::string::npos) << run.output;
    EXPECT_NE(run.output.find("no point cloud written"), std::string::npos) << run.output;
    EXPECT_FALSE(fs::exists(ply));
}

// A plain (not complementary) Gray code with the phase's shift reversed:
// 95 % of the lit pixels still "decode", so the diagnosis is silent, but the
// field steps against its own trend: decode and reconstruct exit 5 naming
// shift_sign (decode writes its outputs for inspection, reconstruct no
// cloud); --accept-inconsistent takes the field as it is.
TEST_F(CliReconstruct, InconsistentDecodeExitsFiveNamingTheField) {
    TempDir out;
    const fs::path capture = misdescribed_copy(path("plain-gray-x"), out / "capture");
    const fs::path ply = out / "cloud.ply";
    const std::string reconstruct =
        "reconstruct " + q(capture) + " --calib " + q(path("calib.yaml")) + " --out " + q(ply);
    const auto run = run_calib(reconstruct, out.path());
    EXPECT_EQ(run.exit_code, 5) << run.output;
    EXPECT_NE(run.output.find("check shift_sign of sequence[2]"), std::string::npos) << run.output;
    EXPECT_NE(run.output.find("no point cloud written"), std::string::npos) << run.output;
    EXPECT_FALSE(fs::exists(ply));

    const auto decoded =
        run_calib("decode " + q(capture) + " --out " + q(out / "decoded"), out.path());
    EXPECT_EQ(decoded.exit_code, 5) << decoded.output;
    EXPECT_TRUE(fs::exists(out / "decoded" / "proj_x.tiff"));
    const std::string md = fpp::yaml_fields::read_text_file(out / "decoded" / "decode.md");
    EXPECT_NE(md.find("## Consistency"), std::string::npos);
    EXPECT_NE(md.find("Inconsistent: along x"), std::string::npos) << md;

    const auto accepted = run_calib(reconstruct + " --accept-inconsistent", out.path());
    EXPECT_EQ(accepted.exit_code, 0) << accepted.output;
    EXPECT_NE(accepted.output.find("warning: "), std::string::npos) << accepted.output;
    EXPECT_TRUE(fs::exists(ply));
    // The same capture described right is consistent.
    const auto right =
        run_calib("decode " + q(path("plain-gray-x")) + " --out " + q(out / "right"), out.path());
    EXPECT_EQ(right.exit_code, 0) << right.output;
    EXPECT_NE(fpp::yaml_fields::read_text_file(out / "right" / "decode.md").find("Consistent."),
              std::string::npos);
}

// Every shift reversed (or a projector showing its image mirrored) gives a
// field consistent with itself, the true one mirrored along x: decode sees
// nothing wrong; reconstruct sees that it fits the calibration only
// mirrored (as described 37 % of the pixels give no point, depth 168 ..
// 14247 mm; mirrored none, 479 mm) and exits 5 saying so, with no file.
TEST_F(CliReconstruct, MirroredFieldExitsFiveSayingSo) {
    TempDir out;
    const fs::path capture = misdescribed_copy(path("two-periods"), out / "capture");
    const fs::path ply = out / "cloud.ply";
    const std::string reconstruct =
        "reconstruct " + q(capture) + " --calib " + q(path("calib.yaml")) + " --out " + q(ply);
    const auto run = run_calib(reconstruct, out.path());
    EXPECT_EQ(run.exit_code, 5) << run.output;
    EXPECT_NE(run.output.find("the decoded field fits the calibration mirrored along x"),
              std::string::npos)
        << run.output;
    EXPECT_NE(run.output.find("mirrored ((W - 1) - x), 0.00 % of the decoded pixels give no point"),
              std::string::npos)
        << run.output;
    EXPECT_FALSE(fs::exists(ply));
    const auto decoded =
        run_calib("decode " + q(capture) + " --out " + q(out / "decoded"), out.path());
    EXPECT_EQ(decoded.exit_code, 0) << decoded.output;

    const auto accepted = run_calib(reconstruct + " --accept-inconsistent", out.path());
    EXPECT_EQ(accepted.exit_code, 0) << accepted.output;
    EXPECT_NE(accepted.output.find("warning: "), std::string::npos) << accepted.output;
    EXPECT_TRUE(fs::exists(ply));
    const auto right = reconstruct_into(path("two-periods"), out / "right.ply", out.path());
    EXPECT_EQ(right.exit_code, 0) << right.output;
    EXPECT_EQ(right.output.find("mirrored"), std::string::npos) << right.output;
}

// The same on real frames: SLStudio's 2x3 skull with both blocks' shifts
// reversed decodes 95 % of its lit pixels, consistently; with SLStudio's
// calibration 3.58 % of them give no point and the depth spans 238 .. 1224
// mm, mirrored 0.00 % and 368 .. 460 mm: exit 5. Described right: no alarm.
TEST(CliReconstructRealData, ReversedSkullExitsFiveSayingItFitsMirrored) {
    const fs::path skull = fpp::test::dataset("slstudio/skull_2x3");
    FPP_REQUIRE_DATASET(skull);
    const fs::path calibration = fpp::test::dataset("slstudio/calibration/calibration.xml");
    TempDir out;
    const fs::path capture = misdescribed_copy(skull, out / "capture");
    for (const auto& [set, code] : {std::pair{capture, 5}, std::pair{skull, 0}}) {
        const auto run = run_calib("reconstruct " + q(set) + " --calib " + q(calibration) +
                                       " --out " + q(out / "cloud.ply"),
                                   out.path());
        EXPECT_EQ(run.exit_code, code) << run.output;
        EXPECT_EQ(run.output.find("fits the calibration mirrored along x") != std::string::npos,
                  code == 5)
            << run.output;
    }
}

// Decoded pixels but no point (a calibration that puts every ray pair
// behind the camera): a clear error naming the calibration, no file.
TEST_F(CliReconstruct, NoPointIsAnErrorNotAnEmptyCloud) {
    TempDir out;
    fpp::calib::StereoCalibration wrong = fpp::calib::calibration_from_rig(small_rig());
    for (double& t : wrong.T)
        t = -t;
    const fs::path calib = out / "wrong.yaml";
    fpp::calib::save_calibration(calib, wrong);
    const fs::path ply = out / "cloud.ply";
    const auto run = run_calib("reconstruct " + q(path("gray-x")) + " --calib " + q(calib) +
                                   " --axes x --out " + q(ply),
                               out.path());
    std::printf("%s\n", run.output.c_str());
    EXPECT_EQ(run.exit_code, 3) << run.output;
    EXPECT_NE(run.output.find("none gave a point"), std::string::npos) << run.output;
    EXPECT_NE(run.output.find("wrong.yaml"), std::string::npos) << run.output;
    EXPECT_FALSE(fs::exists(ply));
}

TEST_F(CliReconstruct, BadDecodeOptionNamesTheOption) {
    TempDir out;
    const fs::path ply = out / "cloud.ply";
    const auto run = run_calib("reconstruct " + q(path("gray-x")) + " --calib " +
                                   q(path("calib.yaml")) + " --threads 5000 --out " + q(ply),
                               out.path());
    EXPECT_EQ(run.exit_code, 2) << run.output;
    EXPECT_NE(run.output.find("command line: --threads: "), std::string::npos) << run.output;
    EXPECT_FALSE(fs::exists(ply));
}

} // namespace
