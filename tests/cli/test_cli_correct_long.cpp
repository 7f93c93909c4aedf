// fpp-calib correct end to end, run as a person would: a hurried calibration
// session on the virtual scanner (camera binned 2x, 8 boards tilted at most
// 10 degrees, seed 2) whose depth scale is off by more than the ball bar's
// noise (k - 1 = -131 +- 32 ppm), calibrated, the ball bar simulated in the
// seven VDI/VDE 2634-2 positions, 2, 3, 5, 7 used for the correction and 1,
// 4, 6 held out. The held-out positions must come out within 0.010 mm, none
// worse beyond noise, and those reaching in depth (4, 6) better; on the same
// scenes without noise, the wall and the spheres after one rigid motion of
// the whole cloud; and a session reaching the image's corners, uncorrected.
// The refusals: test_cli_correct.cpp.

#include "ball_bar_scene.hpp"
#include "calib_run.hpp"
#include "test_support.hpp"

#include "fpp/calib/evaluation.hpp"
#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/coefficient_table.hpp"
#include "fpp/image_io.hpp"
#include "fpp/simulator/rig.hpp"
#include "rig_truth_table.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
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

std::vector<double> held_out_sd(const fs::path& verification_json) {
    std::ifstream in(verification_json);
    const nlohmann::json j = nlohmann::json::parse(in);
    return j["sphere_spacing_error_mm"].get<std::vector<double>>();
}

// The error against the truth after one rigid motion of the whole cloud
// (the camera frame's own place cannot be observed), RMS over the wall's
// points and over the two spheres' points (told apart by their true place:
// the wall is the plane Z = 575 mm, a sphere's points lie on it).
struct RigidFigures {
    double wall_rms = 0, spheres_rms = 0;
    std::size_t wall = 0, spheres = 0;
};
RigidFigures rigid_figures(const fs::path& xyz_tiff, const fs::path& capture,
                           const BallBarPlacement& p) {
    const fpp::Image<float> xyz = fpp::read_tiff_float(xyz_tiff);
    const fpp::Image<float> truth = fpp::read_tiff_float(capture / "truth_xyz.tiff");
    fpp::calib::CloudPoints cloud;
    cloud.organised = xyz.size();
    for (std::size_t i = 0; i < xyz.pixel_count(); ++i) {
        const float* v = xyz.data() + 3 * i;
        if (std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2])) {
            cloud.points.push_back({v[0], v[1], v[2]});
            cloud.pixels.push_back(static_cast<std::uint32_t>(i));
        }
    }
    const fpp::calib::TruthComparison t = fpp::calib::compare_with_truth(cloud, truth);
    const double n = std::hypot(p.axis[0], p.axis[1], p.axis[2]);
    std::array<fpp::Vec3, 2> centres;
    for (int s = 0; s < 2; ++s)
        for (int c = 0; c < 3; ++c)
            centres[std::size_t(s)][std::size_t(c)] =
                p.centre[std::size_t(c)] + (s ? 0.5 : -0.5) * p.length * p.axis[std::size_t(c)] / n;
    RigidFigures f;
    double wall2 = 0, spheres2 = 0;
    std::size_t k = 0;
    for (std::size_t i = 0; i < cloud.points.size(); ++i) {
        const float* r = truth.data() + 3 * std::size_t{cloud.pixels[i]};
        if (!(std::isfinite(r[0]) && std::isfinite(r[1]) && std::isfinite(r[2])))
            continue;
        const fpp::Vec3 ref{r[0], r[1], r[2]};
        const double d = t.distance_rigid_values[k++];
        bool on_sphere = false;
        for (const fpp::Vec3& c : centres)
            on_sphere |= std::hypot(ref[0] - c[0], ref[1] - c[1], ref[2] - c[2]) <
                         fpp::test::kBallDiameterMm / 2 + 0.01;
        if (std::abs(ref[2] - 575.0) < 0.01) {
            wall2 += d * d;
            ++f.wall;
        } else if (on_sphere) {
            spheres2 += d * d;
            ++f.spheres;
        }
    }
    f.wall_rms = std::sqrt(wall2 / double(std::max<std::size_t>(f.wall, 1)));
    f.spheres_rms = std::sqrt(spheres2 / double(std::max<std::size_t>(f.spheres, 1)));
    return f;
}

// The effects rig without shot and read noise (8-bit levels, gamma and blur
// kept), so that what is left against the truth is the calibration's.
void write_quiet_rig(const fs::path& file) {
    std::ifstream rig_in(fpp::sim::effects_rig_path());
    std::ostringstream rig_text;
    rig_text << rig_in.rdbuf();
    std::string quiet_rig = rig_text.str();
    for (const std::string key : {"read_noise_dn: 1.0", "gain_e_per_dn: 40"}) {
        const std::size_t at = quiet_rig.find(key);
        ASSERT_NE(at, std::string::npos) << key;
        quiet_rig.replace(at, key.size(), key.substr(0, key.find(':')) + ": 0");
    }
    std::ofstream(file) << quiet_rig;
}

// Ball bar position k (1-based) on the quiet rig, binned 2, reconstructed
// with each table: its wall and spheres after one rigid motion.
std::vector<RigidFigures> quiet_position_figures(const fs::path& dir, int k,
                                                 const std::vector<std::string>& tables) {
    const BallBarPlacement& p = fpp::test::vdi_ball_bar_positions().at(std::size_t(k - 1));
    const std::string quiet = "quiet-" + std::to_string(k);
    std::ofstream(dir / (quiet + ".scene.yaml")) << fpp::test::ball_bar_scene_yaml(p);
    ToolRun run = run_calib("simulate --rig " + q(dir / "quiet-rig.yaml") +
                                " --binning 2 --scene " + q(dir / (quiet + ".scene.yaml")) +
                                " --sequence gray-x --out " + q(dir / quiet),
                            dir);
    EXPECT_EQ(run.exit_code, 0) << run.output;
    std::vector<RigidFigures> figures;
    for (const std::string& table : tables) {
        const std::string cloud = quiet + "-" + fs::path(table).stem().string();
        run = run_calib("reconstruct " + q(dir / quiet) + " --table " + q(dir / table) + " --out " +
                            q(dir / (cloud + ".ply")) + " --xyz " + q(dir / (cloud + ".tiff")),
                        dir);
        EXPECT_EQ(run.exit_code, 0) << run.output;
        figures.push_back(run.exit_code == 0
                              ? rigid_figures(dir / (cloud + ".tiff"), dir / quiet, p)
                              : RigidFigures{1e9, 1e9, 0, 0});
    }
    return figures;
}

void write_truth_table(const fs::path& file) {
    fpp::write_table(file, fpp::test::rig_truth_table(
                               fpp::sim::load_rig(fpp::sim::effects_rig_path()).binned_camera(2)));
}

} // namespace

TEST(CliCorrectLong, AHurriedSessionsDepthScaleIsCorrectedAndTheHeldOutPositionsImprove) {
    TempDir dir;
    const std::string rig = q(fpp::sim::effects_rig_path());
    ToolRun run = run_calib("simulate-session --binning 2 --poses 8 --max-tilt-deg 10 --seed 2 "
                            "--out " +
                                q(dir / "session"),
                            dir.path());
    ASSERT_EQ(run.exit_code, 0) << run.output;
    run = run_calib("calibrate " + q(dir / "session") + " --out " + q(dir / "calib.yaml") +
                        " --table " + q(dir / "table.fpt"),
                    dir.path());
    ASSERT_EQ(run.exit_code, 0) << run.output;
    std::ofstream(dir / "bar.yaml") << fpp::test::ball_bar_artefact_yaml();
    for (int k = 1; k <= 7; ++k) {
        const BallBarPlacement& p = fpp::test::vdi_ball_bar_positions().at(std::size_t(k - 1));
        const std::string name = "pos-" + std::to_string(k);
        std::ofstream(dir / (name + ".scene.yaml")) << fpp::test::ball_bar_scene_yaml(p);
        run = run_calib("simulate --rig " + rig + " --binning 2 --scene " +
                            q(dir / (name + ".scene.yaml")) + " --sequence gray-x --seed " +
                            std::to_string(k) + " --out " + q(dir / name),
                        dir.path());
        ASSERT_EQ(run.exit_code, 0) << run.output;
    }
    const auto pos = [&](int k) { return q(dir / ("pos-" + std::to_string(k))); };
    run = run_calib("correct --artefact " + q(dir / "bar.yaml") + " --calib " +
                        q(dir / "calib.yaml") + " --session " + q(dir / "session") + " --table " +
                        q(dir / "table.fpt") + " --out-calib " + q(dir / "corrected.yaml") +
                        " --out-table " + q(dir / "corrected.fpt") + " " + pos(2) + " " + pos(3) +
                        " " + pos(5) + " " + pos(7) + " --held-out " + pos(1) + " " + pos(4) + " " +
                        pos(6) + " --report " + q(dir / "report"),
                    dir.path());
    ASSERT_EQ(run.exit_code, 0) << run.output;
    ASSERT_TRUE(fs::exists(dir / "corrected.yaml"));
    ASSERT_TRUE(fs::exists(dir / "corrected.fpt"));
    // The corrected calibration says what was done to it.
    const fpp::calib::StereoCalibration corrected =
        fpp::calib::load_calibration(dir / "corrected.yaml");
    ASSERT_TRUE(corrected.depth_correction.has_value());
    EXPECT_NEAR(corrected.depth_correction->before_ppm, -131, 15);
    EXPECT_LT(std::abs(corrected.depth_correction->after_ppm),
              2 * corrected.depth_correction->after_sigma_ppm);
    EXPECT_NEAR(corrected.depth_correction->focal_scale, 1 - 131e-6, 40e-6);
    EXPECT_EQ(corrected.depth_correction->positions, 4);
    EXPECT_EQ(corrected.depth_correction->artefact, "virtual ball bar");
    EXPECT_FALSE(fpp::calib::load_calibration(dir / "calib.yaml").depth_correction);

    const std::vector<double> before = held_out_sd(dir / "report/before/verification.json");
    const std::vector<double> after = held_out_sd(dir / "report/after/verification.json");
    ASSERT_EQ(before.size(), 3U);
    ASSERT_EQ(after.size(), 3U);
    for (std::size_t i = 0; i < 3; ++i) {
        EXPECT_LE(std::abs(after[i]), 0.010) << "held-out " << i << "\n" << run.output;
        EXPECT_LE(std::abs(after[i]), std::abs(before[i]) + 0.002) << "held-out " << i << "\n"
                                                                   << run.output;
    }
    // A depth scale k changes a sphere seen from one side by about
    // 0.5 x 30 mm x |k - 1| in diameter (measured: worst P_S 0.0072 -> 0.0093
    // mm for k - 1 = -131 ppm): P_S may grow by that, and by no more than
    // 1 um beyond it.
    const auto worst_size = [](const fs::path& json_file) {
        std::ifstream in(json_file);
        double worst = 0;
        for (const auto& position : nlohmann::json::parse(in)["probing_size_mm"])
            for (const auto& v : position)
                worst = std::max(worst, std::abs(v.get<double>()));
        return worst;
    };
    const double k_minus_1 = std::abs(corrected.depth_correction->focal_scale - 1);
    EXPECT_LE(worst_size(dir / "report/after/verification.json"),
              worst_size(dir / "report/before/verification.json") + 0.5 * 30 * k_minus_1 + 0.001);
    // Positions 4 and 6 reach in depth: the correction must show there
    // (measured: +0.0085 -> +0.0036 and +0.0036 -> -0.0009 mm).
    EXPECT_LT(std::abs(after[1]), std::abs(before[1]) - 0.002) << run.output;
    EXPECT_LT(std::abs(after[2]), std::abs(before[2]) - 0.001) << run.output;

    // The wall and the spheres of every held-out position against the truth
    // after one rigid motion of each whole cloud, on captures of the same
    // scenes without noise: with the rig's true geometry as the table (the
    // floor: 8-bit levels, gamma, blur and the table model's own error),
    // before and after the correction.
    write_quiet_rig(dir / "quiet-rig.yaml");
    write_truth_table(dir / "truth.fpt");
    for (int k : {1, 4, 6}) {
        const std::vector<RigidFigures> f =
            quiet_position_figures(dir.path(), k, {"truth.fpt", "table.fpt", "corrected.fpt"});
        std::printf("position %d after one rigid motion, RMS (true table / before / after): "
                    "wall %.4f / %.4f / %.4f mm (%zu points), spheres %.4f / %.4f / %.4f mm "
                    "(%zu points)\n",
                    k, f[0].wall_rms, f[1].wall_rms, f[2].wall_rms, f[2].wall, f[0].spheres_rms,
                    f[1].spheres_rms, f[2].spheres_rms, f[2].spheres);
        // Measured (true table / before / after, mm): spheres 0.0126-0.0138 /
        // 0.0221-0.0235 / 0.0143-0.0157: the bound is 0.022, and the
        // depth scale was most of what separated them from the floor. The wall
        // (0.0117 / 0.0201 / 0.0201-0.0203) keeps what a depth scale cannot
        // move: lateral error outside the image's central half, where a
        // hurried session's boards never reached (0.0122 mm RMS there against
        // 0.0017 inside it and the floor's 0.0029); the 0.018 is not
        // met by a depth-scale correction of such a session (a session that
        // reaches there meets it uncorrected: the test below).
        EXPECT_LE(f[2].spheres_rms, 0.022) << "position " << k;
        EXPECT_LT(f[2].spheres_rms, f[1].spheres_rms - 0.004) << "position " << k;
        EXPECT_LE(f[2].wall_rms, f[1].wall_rms + 0.0005) << "position " << k;
        EXPECT_GT(f[2].wall_rms, f[0].wall_rms) << "the floor is below any calibration";
    }
}

// What the hurried session lacked: an 8-pose session of simulate-session's
// default spread (tilts up to about 28 degrees, boards over the whole view)
// holds the wall and the spheres within the 0.018 / 0.022 mm after
// one rigid motion, with no correction (measured: wall 0.0159-0.0160,
// spheres 0.0148-0.0163 mm; over fewer of the wall's pixels than the hurried
// table, 263-268 k against 329-334 k: this table leaves more of the wall, at
// 575 mm beyond the session's boards, without a point).
TEST(CliCorrectLong, ASessionReachingTheImageCornersHoldsTheWallWithoutCorrection) {
    TempDir dir;
    ToolRun run = run_calib(
        "simulate-session --binning 2 --poses 8 --seed 5 --out " + q(dir / "session"), dir.path());
    ASSERT_EQ(run.exit_code, 0) << run.output;
    run = run_calib("calibrate " + q(dir / "session") + " --out " + q(dir / "calib.yaml") +
                        " --table " + q(dir / "table.fpt"),
                    dir.path());
    ASSERT_EQ(run.exit_code, 0) << run.output;
    write_quiet_rig(dir / "quiet-rig.yaml");
    for (int k : {1, 4}) {
        const RigidFigures f = quiet_position_figures(dir.path(), k, {"table.fpt"}).at(0);
        std::printf("position %d after one rigid motion: wall %.4f mm (%zu points), spheres %.4f "
                    "mm (%zu points)\n",
                    k, f.wall_rms, f.wall, f.spheres_rms, f.spheres);
        EXPECT_LE(f.wall_rms, 0.018) << "position " << k;
        EXPECT_LE(f.spheres_rms, 0.022) << "position " << k;
    }
}
