// fpp-calib correct, run as a person would, on bad input: each refusal
// exits 2, says why (naming the file) and writes neither output. The
// captures are the virtual scanner's ball bar (camera binned 2x) measured
// with the table of the rig's true geometry; the calibration is the rig's
// (the paper rig's, the same sizes). The end-to-end correction of a hurried session:
// test_cli_correct_long.cpp.

#include "ball_bar_scene.hpp"
#include "calib_run.hpp"
#include "rig_truth_table.hpp"
#include "test_support.hpp"

#include "fpp/calib/simulated_rig.hpp"
#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/coefficient_table.hpp"
#include "fpp/simulator/rig.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <vector>

namespace {

using fpp::test::BallBarPlacement;
using fpp::test::TempDir;
using fpp::test::ToolRun;
namespace fs = std::filesystem;

std::string q(const fs::path& p) {
    return fpp::test::shell_quote(p.string());
}

using fpp::test::run_calib;

fpp::sim::Rig rig(int binning) {
    fpp::sim::Rig r = fpp::sim::load_rig(fpp::sim::effects_rig_path()).binned_camera(binning);
    r.name = "effects-binned";
    return r;
}

class CliCorrect : public ::testing::Test {
protected:
    void SetUp() override {
        std::ofstream(dir_ / "rig.yaml") << fpp::sim::rig_to_yaml(rig(2));
        std::ofstream(dir_ / "rig4.yaml") << fpp::sim::rig_to_yaml(rig(4));
        fpp::write_table(dir_ / "table.fpt", fpp::test::rig_truth_table(rig(2)));
        // The paper rig's (the effects rig's lenses have terms the file
        // cannot hold): the refusals need its sizes only.
        fpp::calib::save_calibration(
            dir_ / "calib.yaml",
            fpp::calib::calibration_from_rig(fpp::sim::Rig::paper().binned_camera(2)));
        std::ofstream(dir_ / "bar.yaml") << fpp::test::ball_bar_artefact_yaml();
        std::string off = fpp::test::ball_bar_artefact_yaml();
        off.replace(off.find("150.000"), 7, "149.000");
        std::ofstream(dir_ / "bar-off.yaml") << off;
    }
    // VDI position k (1-based) simulated at `binning`.
    fs::path capture(int k, int binning = 2) {
        const std::string name = "position-" + std::to_string(k) + "-b" + std::to_string(binning);
        const fs::path folder = dir_ / name;
        if (fs::exists(folder))
            return folder;
        const BallBarPlacement p = fpp::test::vdi_ball_bar_positions().at(std::size_t(k - 1));
        std::ofstream(dir_ / (name + ".scene.yaml")) << fpp::test::ball_bar_scene_yaml(p);
        const ToolRun run =
            run_calib("simulate --rig " + q(dir_ / (binning == 2 ? "rig.yaml" : "rig4.yaml")) +
                          " --scene " + q(dir_ / (name + ".scene.yaml")) +
                          " --sequence gray-x --seed " + std::to_string(k) + " --out " + q(folder),
                      dir_.path());
        EXPECT_EQ(run.exit_code, 0) << run.output;
        return folder;
    }
    // A small checkerboard session (3 poses) at `binning`.
    fs::path session(int binning = 2) {
        const fs::path folder = dir_ / ("session-b" + std::to_string(binning));
        if (fs::exists(folder))
            return folder;
        const ToolRun run = run_calib("simulate-session --poses 3 --max-tilt-deg 14 --binning " +
                                          std::to_string(binning) + " --out " + q(folder),
                                      dir_.path());
        EXPECT_EQ(run.exit_code, 0) << run.output;
        return folder;
    }
    ToolRun correct(const std::string& captures, const std::string& artefact = "bar.yaml",
                    const fs::path& session_folder = {}) {
        const fs::path s = session_folder.empty() ? dir_ / "no-session" : session_folder;
        return run_calib("correct --artefact " + q(dir_ / artefact) + " --calib " +
                             q(dir_ / "calib.yaml") + " --session " + q(s) + " --table " +
                             q(dir_ / "table.fpt") + " --out-calib " + q(dir_ / "out.yaml") +
                             " --out-table " + q(dir_ / "out.fpt") + " " + captures,
                         dir_.path());
    }
    // Exit 2, the message holds every part, nothing written.
    void expect_refused(const ToolRun& run, const std::vector<std::string>& parts) {
        EXPECT_EQ(run.exit_code, 2) << run.output;
        for (const std::string& part : parts)
            EXPECT_NE(run.output.find(part), std::string::npos) << part << "\n" << run.output;
        EXPECT_FALSE(fs::exists(dir_ / "out.yaml"));
        EXPECT_FALSE(fs::exists(dir_ / "out.fpt"));
    }

    TempDir dir_;
};

TEST_F(CliCorrect, ACertificateOneMillimetreOffIsRefusedAsInconsistent) {
    const ToolRun run = correct(q(capture(2)) + " " + q(capture(3)) + " " + q(capture(5)),
                                "bar-off.yaml", session());
    expect_refused(run, {"refused as inconsistent, never corrected", "bar-off.yaml"});
}

TEST_F(CliCorrect, TooFewPositionsOrNoneReachingInDepthAreRefused) {
    const fs::path s = session();
    expect_refused(correct(q(capture(2)), "bar.yaml", s), {"at least 2 positions"});
    expect_refused(correct(q(capture(1)) + " " + q(capture(2)), "bar.yaml", s),
                   {"cannot be seen from lengths across", "position-1-b2"});
}

TEST_F(CliCorrect, ACaptureOfAnotherCameraSizeIsRefused) {
    expect_refused(correct(q(capture(2, 4)) + " " + q(capture(3)), "bar.yaml", session()),
                   {"table.fpt", "camera_size", "400x300"});
}

TEST_F(CliCorrect, OutputsThatExistOrCannotBeWrittenAreRefused) {
    std::ofstream(dir_ / "out.yaml") << "mine\n";
    const ToolRun exists = correct(q(capture(2)) + " " + q(capture(3)));
    EXPECT_EQ(exists.exit_code, 2) << exists.output;
    EXPECT_NE(exists.output.find("already exists"), std::string::npos) << exists.output;
    std::ifstream in(dir_ / "out.yaml");
    std::string kept;
    std::getline(in, kept);
    EXPECT_EQ(kept, "mine");
    fs::remove(dir_ / "out.yaml");
    const ToolRun nowhere = run_calib(
        "correct --artefact " + q(dir_ / "bar.yaml") + " --calib " + q(dir_ / "calib.yaml") +
            " --session " + q(dir_ / "s") + " --table " + q(dir_ / "table.fpt") + " --out-calib " +
            q(dir_ / "missing/out.yaml") + " --out-table " + q(dir_ / "out.fpt") + " " +
            q(dir_ / "x") + " " + q(dir_ / "y"),
        dir_.path());
    expect_refused(nowhere, {"--out-calib", "does not exist"});
}

TEST_F(CliCorrect, ASessionOfAnotherCameraIsRefused) {
    expect_refused(correct(q(capture(2)) + " " + q(capture(3)), "bar.yaml", session(4)),
                   {"not the session of this calibration", "capture.yaml"});
}

} // namespace
