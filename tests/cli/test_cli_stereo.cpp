// fpp-calib simulate-session and stereo, run as a person would: exit codes,
// files written, and on bad input a clear error naming the file, exit code 2
// and nothing written. Sessions use the camera binned 4x (400 x 300) so that
// each takes a second or two.

#include "test_support.hpp"

#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/image_io.hpp"

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

bool contains(const std::string& text, const std::string& what) {
    return text.find(what) != std::string::npos;
}

// A session of `poses` poses, camera binned 4x.
fs::path simulate_session(const TempDir& dir, const std::string& name, int poses,
                          const std::string& extra = "") {
    const fs::path session = dir / name;
    const ToolRun run = run_calib("simulate-session --poses " + std::to_string(poses) +
                                      " --binning 4 --out " + quote(session.string()) + " " + extra,
                                  dir);
    EXPECT_EQ(run.exit_code, 0) << run.output;
    return session;
}

// The stereo command on `session`; the outputs must not exist afterwards
// when it fails.
ToolRun stereo(const TempDir& dir, const fs::path& session, const std::string& extra = "") {
    return run_calib("stereo " + quote(session.string()) + " --out " +
                         quote((dir / "calib.yaml").string()) + " --report " +
                         quote((dir / "report").string()) + " " + extra,
                     dir);
}

void expect_refused(const TempDir& dir, const ToolRun& run) {
    EXPECT_EQ(run.exit_code, 2) << run.output;
    EXPECT_FALSE(fs::exists(dir / "calib.yaml"));
    EXPECT_FALSE(fs::exists(dir / "report"));
}

TEST(CliStereo, SimulatedSessionCalibratesAndWritesTheReport) {
    TempDir dir;
    const fs::path session = simulate_session(dir, "session", 6, "--seed 3");
    EXPECT_TRUE(fs::exists(session / "board.yaml"));
    EXPECT_TRUE(fs::exists(session / "pose-06" / "capture.yaml"));
    const ToolRun run = stereo(dir, session);
    ASSERT_EQ(run.exit_code, 0) << run.output;
    EXPECT_TRUE(contains(run.output, "calibrated from 6 of 6 poses")) << run.output;
    EXPECT_TRUE(contains(run.output, "the camera alone from its corners"))
        << run.output; // progress on stderr
    EXPECT_TRUE(contains(run.output, "dense samples of the boards' bright parts")) << run.output;

    const fpp::calib::StereoCalibration c = fpp::calib::load_calibration(dir / "calib.yaml");
    EXPECT_EQ(c.camera_size, (fpp::Size{400, 300}));
    EXPECT_EQ(c.projector_size, (fpp::Size{1280, 800}));
    EXPECT_GT(c.camera_rms, 0);
    EXPECT_LT(c.camera_rms, 0.1);
    EXPECT_LT(c.projector_rms, 0.1);
    EXPECT_NEAR(c.projector.fu, 1949.18, 5); // the paper's projector
    ASSERT_EQ(c.poses.size(), 6u);
    EXPECT_EQ(c.poses[0].name, "pose-01");
    EXPECT_EQ(c.poses[0].corners, 88);

    const fs::path report = dir / "report";
    std::ifstream in(report / "summary.md");
    std::stringstream summary;
    summary << in.rdbuf();
    EXPECT_TRUE(contains(summary.str(), "## Reprojection error")) << summary.str();
    EXPECT_TRUE(contains(summary.str(), "Procedure: camera-first")) << summary.str();
    EXPECT_TRUE(contains(summary.str(), "Correction grids: camera 12 x 9")) << summary.str();
    EXPECT_EQ(fpp::calib::load_calibration(dir / "calib.yaml").board_square_size, 15.0);
    EXPECT_TRUE(contains(summary.str(), "Projector corner methods against ground truth"))
        << summary.str();
    // The other skew setting's calibration only on request (--compare-skew).
    EXPECT_FALSE(contains(summary.str(), "(comparison)")) << summary.str();
    for (const char* png : {"corners-pose-01.png", "corners-pose-06.png", "residuals-camera.png",
                            "residuals-projector.png", "pose-rms.png"}) {
        ASSERT_TRUE(fs::exists(report / png)) << png;
        const fpp::PngInfo info = fpp::read_png_info(report / png);
        EXPECT_EQ(info.bit_depth, 8) << png;
        EXPECT_EQ(info.channels, 3) << png;
        EXPECT_GT(info.size.width, 100) << png;
    }

    // Run again into the same report folder: the earlier report is replaced.
    fs::remove(dir / "calib.yaml");
    const ToolRun again =
        stereo(dir, session, "--corner-method homography --no-skew --compare-skew");
    ASSERT_EQ(again.exit_code, 0) << again.output;
    EXPECT_TRUE(contains(again.output, "corners by homography")) << again.output;
    EXPECT_EQ(fpp::calib::load_calibration(dir / "calib.yaml").camera.skew, 0.0);
    std::ifstream in_again(report / "summary.md");
    std::stringstream summary_again;
    summary_again << in_again.rdbuf();
    EXPECT_TRUE(contains(summary_again.str(), "skew estimated (comparison)"))
        << summary_again.str();
}

// The paper's procedure on request, and the held-out check of absolute
// accuracy in the output and the report.
// The trueness the calibration predicts: in the file, on the terminal and
// in the report with its map; session-check's verdicts and exit statuses.
TEST(CliStereo, TruenessIsStatedAndTheSessionChecked) {
    TempDir dir;
    const fs::path session = simulate_session(dir, "session", 6, "--seed 3");
    const ToolRun run = stereo(dir, session);
    ASSERT_EQ(run.exit_code, 0) << run.output;
    EXPECT_TRUE(contains(run.output, "Predicted trueness (1 sigma")) << run.output;
    const fpp::calib::StereoCalibration c = fpp::calib::load_calibration(dir / "calib.yaml");
    ASSERT_TRUE(c.trueness.known());
    EXPECT_EQ(c.trueness.length_mm, 150);
    EXPECT_GT(c.trueness.middle().along_depth_mm, 0);
    EXPECT_TRUE(fs::exists(dir / "report" / "trueness.png"));
    std::stringstream summary;
    summary << std::ifstream(dir / "report" / "summary.md").rdbuf();
    EXPECT_TRUE(contains(summary.str(), "## Trueness")) << summary.str();

    const auto check = [&](const std::string& extra) {
        return run_calib("session-check " + quote(session.string()) + " " + extra, dir);
    };
    const ToolRun loose = check("--target-um 100000");
    EXPECT_EQ(loose.exit_code, 0) << loose.output;
    EXPECT_TRUE(contains(loose.output, "Session: enough")) << loose.output;
    EXPECT_TRUE(contains(loose.output, "Poses: 6 used of 6 found")) << loose.output;
    const ToolRun strict = check("--target-um 1");
    EXPECT_TRUE(strict.exit_code == 3 || strict.exit_code == 4) << strict.output;
    EXPECT_TRUE(contains(strict.output, "Next pose: ")) << strict.output;
    const ToolRun bad = check("--target-um -3");
    EXPECT_EQ(bad.exit_code, 1) << bad.output;
    EXPECT_TRUE(contains(bad.output, "target_mm")) << bad.output;

    // Two poses: too weak, said so, not an error.
    const fs::path two = simulate_session(dir, "two", 2, "--seed 4");
    const ToolRun weak = run_calib("session-check " + quote(two.string()), dir);
    EXPECT_EQ(weak.exit_code, 4) << weak.output;
    EXPECT_TRUE(contains(weak.output, "Session: too weak")) << weak.output;
    EXPECT_TRUE(contains(weak.output, "only 2 of 2 poses are usable")) << weak.output;
}

TEST(CliStereo, JointProcedureAndTheHeldOutCheck) {
    TempDir dir;
    const fs::path session = simulate_session(dir, "session", 6, "--seed 4");
    const ToolRun run = stereo(
        dir, session, "--procedure joint --camera-grid none --projector-grid none --held-out");
    ASSERT_EQ(run.exit_code, 0) << run.output;
    EXPECT_TRUE(contains(run.output, "joint bundle adjustment")) << run.output;
    EXPECT_TRUE(contains(run.output, "held-out poses")) << run.output;
    EXPECT_TRUE(contains(run.output, "pose-06: 88 corners")) << run.output;
    const fpp::calib::StereoCalibration c = fpp::calib::load_calibration(dir / "calib.yaml");
    EXPECT_TRUE(c.camera_correction.empty());
    EXPECT_TRUE(c.projector_correction.empty());
    std::ifstream in(dir / "report" / "summary.md");
    std::stringstream summary;
    summary << in.rdbuf();
    EXPECT_TRUE(contains(summary.str(), "## Held-out poses")) << summary.str();
    EXPECT_TRUE(contains(summary.str(), "Procedure: joint")) << summary.str();
    // A grid size that is no grid size.
    TempDir other;
    const ToolRun bad = stereo(other, session, "--camera-grid 12by9");
    EXPECT_NE(bad.exit_code, 0);
    EXPECT_TRUE(contains(bad.output, "--camera-grid")) << bad.output;
    EXPECT_FALSE(fs::exists(other / "calib.yaml"));
}

TEST(CliStereo, FewerThanThreeUsablePosesIsAnError) {
    TempDir dir;
    const fs::path session = simulate_session(dir, "session", 2);
    const ToolRun run = stereo(dir, session);
    expect_refused(dir, run);
    EXPECT_TRUE(contains(run.output, session.string())) << run.output;
    EXPECT_TRUE(contains(run.output, "only 2 of 2 poses are usable")) << run.output;
    EXPECT_TRUE(contains(run.output, "at least 3")) << run.output;
}

TEST(CliStereo, PosesOfDifferentSizesAreAnError) {
    TempDir dir;
    const fs::path session = simulate_session(dir, "session", 3);
    // One pose from a camera binned 2x (800 x 600) slipped into the session.
    const fs::path other = dir / "other";
    ASSERT_EQ(
        run_calib("simulate-session --poses 1 --binning 2 --out " + quote(other.string()), dir)
            .exit_code,
        0);
    fs::rename(other / "pose-01", session / "pose-04");
    const ToolRun run = stereo(dir, session);
    expect_refused(dir, run);
    EXPECT_TRUE(contains(run.output, (session / "pose-04" / "capture.yaml").string()))
        << run.output;
    EXPECT_TRUE(contains(run.output, "camera size 800 x 600 differs from pose-01's 400 x 300"))
        << run.output;
}

TEST(CliStereo, BoardNeverFoundIsAnErrorWithEveryPosesReason) {
    TempDir dir;
    // White planes, described as a checkerboard.
    const fs::path session = simulate_session(dir, "session", 3, "--kind plane");
    std::ofstream(session / "board.yaml", std::ios::trunc)
        << "format: fpp-board/1\nkind: checkerboard\ninner_corners: [11, 8]\nsquare_size: 15.0\n";
    const ToolRun run = stereo(dir, session);
    expect_refused(dir, run);
    EXPECT_TRUE(contains(run.output, "only 0 of 3 poses are usable")) << run.output;
    for (const char* pose : {"pose-01", "pose-02", "pose-03"})
        EXPECT_TRUE(contains(run.output, std::string(pose) + ": no 11 x 8 checkerboard found"))
            << run.output;
    EXPECT_TRUE(contains(run.output, "skipped pose-01")) << run.output; // said while it happens
}

TEST(CliStereo, PhaseMissingOnAnAxisIsAnError) {
    TempDir dir;
    const fs::path session = simulate_session(dir, "session", 3, "--sequence gray-x");
    const ToolRun run = stereo(dir, session);
    expect_refused(dir, run);
    EXPECT_TRUE(contains(run.output, (session / "pose-01" / "capture.yaml").string()))
        << run.output;
    EXPECT_TRUE(contains(run.output, "sequence")) << run.output;
    EXPECT_TRUE(contains(run.output, "no phase block along y")) << run.output;
}

TEST(CliStereo, BoardFileMissingOrNotACheckerboardIsAnError) {
    TempDir dir;
    const fs::path session = simulate_session(dir, "session", 3);
    fs::remove(session / "board.yaml");
    ToolRun run = stereo(dir, session);
    expect_refused(dir, run);
    EXPECT_TRUE(contains(run.output, (session / "board.yaml").string())) << run.output;
    EXPECT_TRUE(contains(run.output, "missing")) << run.output;

    std::ofstream(session / "board.yaml") << "format: fpp-board/1\nkind: plane\n";
    run = stereo(dir, session);
    expect_refused(dir, run);
    EXPECT_TRUE(contains(run.output, "kind")) << run.output;
    EXPECT_TRUE(contains(run.output, "needs a checkerboard")) << run.output;

    const fs::path empty = dir / "empty";
    fs::create_directories(empty);
    std::ofstream(empty / "board.yaml")
        << "format: fpp-board/1\nkind: checkerboard\ninner_corners: [11, 8]\n"
           "square_size: 15.0\n";
    run = stereo(dir, empty);
    expect_refused(dir, run);
    EXPECT_TRUE(contains(run.output, "no capture sets")) << run.output;
}

TEST(CliStereo, ReportFolderThatIsNotAReportIsRefusedBeforeAnyWork) {
    TempDir dir;
    fs::create_directories(dir / "report");
    std::ofstream(dir / "report" / "notes.txt") << "mine\n";
    const ToolRun run = stereo(dir, dir / "no-such-session");
    EXPECT_EQ(run.exit_code, 2) << run.output;
    EXPECT_TRUE(contains(run.output, "not a calibration report")) << run.output;
    EXPECT_TRUE(fs::exists(dir / "report" / "notes.txt"));
    EXPECT_FALSE(fs::exists(dir / "calib.yaml"));
}

TEST(CliSimulateSession, RefusesToOverwriteAndChecksItsArguments) {
    TempDir dir;
    fs::create_directories(dir / "session");
    ToolRun run =
        run_calib("simulate-session --poses 2 --out " + quote((dir / "session").string()), dir);
    EXPECT_NE(run.exit_code, 0);
    EXPECT_TRUE(contains(run.output, "already exists")) << run.output;
    EXPECT_TRUE(fs::is_empty(dir / "session"));
    run = run_calib("simulate-session --kind sphere --out " + quote((dir / "s2").string()), dir);
    EXPECT_NE(run.exit_code, 0);
    EXPECT_FALSE(fs::exists(dir / "s2"));
}

} // namespace
