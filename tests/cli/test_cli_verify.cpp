// fpp-calib verify, run as a person would, on the virtual scanner: a ball
// bar on its rod and stand before a wall, simulated in several of the VDI
// positions within the paper rig's volume, reconstructed with the table of
// the rig's true geometry (camera binned 2x); SD against the one the true
// sphere centres give; a glossy bar whose highlights leave holes; a figure
// beyond its MPE; and bad input, which exits 2, names what is wrong and
// writes no report.

#include "ball_bar_scene.hpp"
#include "calib_run.hpp"
#include "rig_truth_table.hpp"
#include "test_support.hpp"

#include "fpp/coefficient_table.hpp"
#include "fpp/simulator/rig.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <limits>
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

// The effects rig (gamma, defocus, noise) with the camera binned 2x: 800 x
// 600, a sphere about 85 px across.
fpp::sim::Rig small_rig() {
    fpp::sim::Rig rig = fpp::sim::load_rig(fpp::sim::effects_rig_path()).binned_camera(2);
    rig.name = "effects-half";
    return rig;
}

// SD of the true centres (the scene's) against the certificate's 150 mm.
double true_spacing_error(const BallBarPlacement& p) {
    return p.length - fpp::test::kBallBarLengthMm;
}

// Four of the seven positions (all seven: test_cli_verify_long.cpp), one
// bar 4 um longer than its certificate.
const std::vector<BallBarPlacement>& positions() {
    static const std::vector<BallBarPlacement> p = [] {
        const auto& all = fpp::test::vdi_ball_bar_positions();
        std::vector<BallBarPlacement> some = {all[0], all[1], all[4], all[6]};
        some[1].length += 0.004;
        return some;
    }();
    return p;
}

class CliVerify : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        dir_ = new TempDir;
        std::ofstream(*dir_ / "rig.yaml") << fpp::sim::rig_to_yaml(small_rig());
        fpp::write_table(*dir_ / "table.fpt", fpp::test::rig_truth_table(small_rig()));
        std::ofstream(*dir_ / "bar.yaml") << fpp::test::ball_bar_artefact_yaml();
    }
    static void TearDownTestSuite() {
        delete dir_;
        dir_ = nullptr;
    }
    static fs::path path(const std::string& name) { return *dir_ / name; }
    // A capture, simulated on first use (CTest runs each test in its own
    // process): position-1 .. position-4, glossy (position 1 with polished
    // spheres), one-sphere (the other beyond the image's right edge).
    static fs::path capture(const std::string& name) {
        const fs::path folder = path(name);
        if (fs::exists(folder))
            return folder;
        BallBarPlacement p;
        int seed = 1;
        if (name.rfind("position-", 0) == 0) {
            seed = std::stoi(name.substr(9));
            p = positions().at(std::size_t(seed - 1));
        } else if (name == "glossy") {
            p = positions()[0];
            p.material = "material: {albedo: 0.45, specular: 0.4, shininess: 300}";
            seed = 9;
        } else {
            p = {{150, -10, 480}, {1, 0, 0}};
            seed = 10;
        }
        const fs::path scene = path(name + ".scene.yaml");
        std::ofstream(scene) << fpp::test::ball_bar_scene_yaml(p);
        const ToolRun run = run_calib("simulate --rig " + q(path("rig.yaml")) + " --scene " +
                                          q(scene) + " --sequence gray-x --seed " +
                                          std::to_string(seed) + " --out " + q(folder),
                                      dir_->path());
        EXPECT_EQ(run.exit_code, 0) << run.output;
        return folder;
    }
    static std::string captures() {
        std::string s;
        for (std::size_t k = 0; k < positions().size(); ++k)
            s += " " + q(capture("position-" + std::to_string(k + 1)));
        return s;
    }
    static ToolRun verify(const std::string& args, const fs::path& report,
                          const std::string& artefact = "bar.yaml") {
        return run_calib("verify --artefact " + q(path(artefact)) + " --table " +
                             q(path("table.fpt")) + " --report " + q(report) + " " + args,
                         dir_->path());
    }

    static TempDir* dir_;
};

TempDir* CliVerify::dir_ = nullptr;

nlohmann::json read_json(const fs::path& file) {
    std::ifstream in(file);
    return nlohmann::json::parse(in);
}

bool says(const ToolRun& run, const std::string& part) {
    return run.output.find(part) != std::string::npos;
}

TEST_F(CliVerify, BallBarInFourPositionsMeetsTheTruth) {
    TempDir out;
    const fs::path report = out / "report";
    const ToolRun run = verify("--mpe-sd 0.02 --mpe-pf 0.5 --mpe-ps 0.05" + captures(), report);
    ASSERT_EQ(run.exit_code, 0) << run.output;
    for (const char* file : {"summary.md", "verification.json", "sd.png", "probing-form.png",
                             "probing-size.png", "residuals-1.png", "residuals-4.png"})
        EXPECT_TRUE(fs::is_regular_file(report / file)) << file;
    const nlohmann::json j = read_json(report / "verification.json");
    EXPECT_EQ(j["format"], "fpp-verification/1");
    EXPECT_EQ(j["verdict"], "pass");
    ASSERT_EQ(j["sphere_spacing_error_mm"].size(), positions().size());
    ASSERT_EQ(j["probing_form_mm"].size(), positions().size());
    for (std::size_t k = 0; k < positions().size(); ++k) {
        SCOPED_TRACE("position " + std::to_string(k + 1));
        const double sd = j["sphere_spacing_error_mm"][k].get<double>();
        const nlohmann::json& p = j["positions"][k];
        // The target: within 0.005 mm of the SD of the true centres.
        EXPECT_NEAR(sd, true_spacing_error(positions()[k]), 0.005);
        EXPECT_NEAR(p["truth_sphere_spacing_error_mm"].get<double>(),
                    true_spacing_error(positions()[k]), 0.0005);
        std::printf("position %zu: SD %+.4f mm, true %+.4f mm, from the true points %+.4f mm\n",
                    k + 1, sd, true_spacing_error(positions()[k]),
                    p["truth_sphere_spacing_error_mm"].get<double>());
        ASSERT_EQ(p["spheres"].size(), 2u);
        for (const nlohmann::json& s : p["spheres"]) {
            EXPECT_GT(s["coverage"].get<double>(), 0.4);
            EXPECT_GT(s["points_used"].get<int>(), 300);
            EXPECT_NEAR(s["probing_size_mm"].get<double>(), 0, 0.05);
            std::printf("  sphere %d: P_F %.4f P_S %+.4f coverage %.2f points %d\n",
                        s["sphere"].get<int>(), s["probing_form_mm"].get<double>(),
                        s["probing_size_mm"].get<double>(), s["coverage"].get<double>(),
                        s["points_used"].get<int>());
        }
    }
}

TEST_F(CliVerify, GlossySpheresAreFittedAroundTheirHighlightHoles) {
    TempDir out;
    const ToolRun matte = verify(q(capture("position-1")), out / "matte");
    ASSERT_EQ(matte.exit_code, 0) << matte.output;
    const ToolRun glossy = verify(q(capture("glossy")), out / "glossy");
    ASSERT_EQ(glossy.exit_code, 0) << glossy.output;
    const nlohmann::json a = read_json(out / "matte/verification.json");
    const nlohmann::json b = read_json(out / "glossy/verification.json");
    for (int s = 0; s < 2; ++s) {
        const double matte_coverage = a["positions"][0]["spheres"][s]["coverage"];
        const double glossy_coverage = b["positions"][0]["spheres"][s]["coverage"];
        std::printf("sphere %d: coverage %.2f matte, %.2f glossy\n", s + 1, matte_coverage,
                    glossy_coverage);
        EXPECT_LT(b["positions"][0]["spheres"][s]["points_used"].get<int>(),
                  a["positions"][0]["spheres"][s]["points_used"].get<int>());
    }
    EXPECT_NEAR(b["sphere_spacing_error_mm"][0].get<double>(), 0, 0.01);
}

TEST_F(CliVerify, ASingleSphereAndAFlatPlate) {
    TempDir out;
    // The sphere certificate on the capture that holds one sphere in view.
    const fs::path artefacts = fpp::test::source_dir() / "board/sim/artefacts";
    const ToolRun sphere =
        run_calib("verify --artefact " + q(artefacts / "sphere-30.yaml") + " --table " +
                      q(path("table.fpt")) + " --mpe-pf 0.5 --mpe-ps 0.05 --report " +
                      q(out / "sphere") + " " + q(capture("one-sphere")),
                  out.path());
    ASSERT_EQ(sphere.exit_code, 0) << sphere.output;
    const nlohmann::json s = read_json(out / "sphere/verification.json");
    EXPECT_EQ(s["artefact"]["kind"], "sphere");
    EXPECT_EQ(s["sphere_spacing_error_mm"].size(), 0u);
    ASSERT_EQ(s["probing_size_mm"].size(), 1u);
    EXPECT_NEAR(s["probing_size_mm"][0][0].get<double>(), 0, 0.05);

    // A 200 x 150 mm plate, tilted, before the wall.
    const fs::path scene = out / "plate.yaml";
    std::ofstream(scene)
        << "format: fpp-scene/1\nshapes:\n"
           "  - {type: plane, name: wall, centre: [0, 0, 575], size: [420, 330], albedo: 0.8}\n"
           "  - {type: plane, name: plate, centre: [0, 0, 470], euler_deg: [10, -15, 5],\n"
           "     size: [200, 150], albedo: 0.85}\n";
    const ToolRun sim = run_calib("simulate --rig " + q(path("rig.yaml")) + " --scene " + q(scene) +
                                      " --sequence gray-x --out " + q(out / "plate"),
                                  out.path());
    ASSERT_EQ(sim.exit_code, 0) << sim.output;
    const ToolRun plate =
        run_calib("verify --artefact " + q(artefacts / "flat-200x150.yaml") + " --table " +
                      q(path("table.fpt")) + " --mpe-flatness 0.3 --report " + q(out / "flat") +
                      " " + q(out / "plate"),
                  out.path());
    ASSERT_EQ(plate.exit_code, 0) << plate.output;
    const nlohmann::json f = read_json(out / "flat/verification.json");
    ASSERT_EQ(f["flatness_mm"].size(), 1u);
    const double flatness = f["flatness_mm"][0].get<double>();
    std::printf("plate: F %.4f mm, extent %.1f x %.1f mm\n", flatness,
                f["positions"][0]["plane"]["extent_mm"][0].get<double>(),
                f["positions"][0]["plane"]["extent_mm"][1].get<double>());
    EXPECT_GT(flatness, 0);
    EXPECT_LT(flatness, 0.3);
    EXPECT_EQ(f["verdict"], "pass");
    EXPECT_TRUE(fs::is_regular_file(out / "flat/flatness.png"));
}

TEST_F(CliVerify, AFigureBeyondItsMpeFailsTheVerification) {
    TempDir out;
    const ToolRun run = verify("--mpe-pf 0.001 " + q(capture("position-1")), out / "report");
    EXPECT_EQ(run.exit_code, 4) << run.output;
    EXPECT_TRUE(says(run, "verification failed: P_F")) << run.output;
    const nlohmann::json j = read_json(out / "report/verification.json");
    EXPECT_EQ(j["verdict"], "fail");
    EXPECT_EQ(j["figures"][1]["verdict"], "fail");
    EXPECT_EQ(j["figures"][0]["verdict"], "none"); // SD: no MPE given
}

// Bad input: exit 2, the message names `parts`, no report written.
void expect_refused(const ToolRun& run, const fs::path& report,
                    const std::vector<std::string>& parts) {
    EXPECT_EQ(run.exit_code, 2) << run.output;
    for (const std::string& part : parts)
        EXPECT_TRUE(says(run, part)) << "missing '" << part << "' in\n" << run.output;
    EXPECT_FALSE(fs::exists(report)) << run.output;
}

TEST_F(CliVerify, RefusesACertificateOneMillimetreOff) {
    std::ofstream(path("bar-151.yaml"))
        << "format: fpp-artefact/1\nkind: ball-bar\nsphere_diameters_mm: [30, 30]\n"
           "centre_distance_mm: 151.000\nuncertainty_mm: 0.001\n";
    TempDir out;
    const ToolRun run = verify(q(capture("position-1")), out / "report", "bar-151.yaml");
    expect_refused(run, out / "report",
                   {"bar-151.yaml: centre_distance_mm", "far more than a scanner could be off"});
}

TEST_F(CliVerify, RefusesAMalformedArtefactFileNamingTheKey) {
    std::ofstream(path("bar-bad.yaml"))
        << "format: fpp-artefact/1\nkind: ball-bar\nsphere_diameters_mm: [30, 30]\n"
           "centre_distance_mm: 150\n";
    TempDir out;
    expect_refused(verify(q(capture("position-1")), out / "report", "bar-bad.yaml"), out / "report",
                   {"bar-bad.yaml: uncertainty_mm: missing field"});
}

TEST_F(CliVerify, RefusesAMissingSphereNamingTheCapture) {
    TempDir out;
    expect_refused(verify(q(capture("one-sphere")), out / "report"), out / "report",
                   {"one-sphere: spheres: found 1 of the 2", "missing"});
}

TEST_F(CliVerify, ASphereWhereTheTableHasNoModelIsBlamedOnTheTable) {
    // The table of a session whose boards never reached the right part of
    // the view (no model from column 500 on): the right sphere of position 1
    // (about column 610) is not measured, and the refusal says why.
    TempDir out;
    fpp::CoefficientTable table = fpp::test::rig_truth_table(small_rig());
    for (int y = 0; y < table.info().camera.height; ++y)
        for (int x = 500; x < table.info().camera.width; ++x)
            table.set(fpp::table_plane::centre, x, y, std::numeric_limits<float>::quiet_NaN());
    fpp::write_table(out / "left-only.fpt", table);
    const ToolRun run = run_calib("verify --artefact " + q(path("bar.yaml")) + " --table " +
                                      q(out / "left-only.fpt") + " --report " + q(out / "report") +
                                      " " + q(capture("position-1")),
                                  out.path());
    expect_refused(run, out / "report",
                   {"position-1: sphere", "left-only.fpt gives no point at",
                    "where the calibration session's boards did not reach"});
}

TEST_F(CliVerify, RefusesACaptureOfAnotherCameraSize) {
    TempDir out;
    fpp::sim::Rig rig = small_rig().binned_camera(2); // 400 x 300
    const fs::path rig_file = out / "rig-400.yaml";
    std::ofstream(rig_file) << fpp::sim::rig_to_yaml(rig);
    std::ofstream(out / "scene.yaml") << fpp::test::ball_bar_scene_yaml(positions()[0]);
    const ToolRun sim =
        run_calib("simulate --rig " + q(rig_file) + " --scene " + q(out / "scene.yaml") +
                      " --sequence gray-x --out " + q(out / "small"),
                  out.path());
    ASSERT_EQ(sim.exit_code, 0) << sim.output;
    expect_refused(verify(q(capture("position-1")) + " " + q(out / "small"), out / "report"),
                   out / "report", {"small/capture.yaml: camera", "400x300", "800x600"});
}

TEST_F(CliVerify, RefusesACaptureTheScannerMadeWithAnotherTable) {
    TempDir out;
    const fs::path scan = out / "scan-20261129-040000-000";
    fs::create_directories(scan);
    fs::copy(capture("position-1"), scan / "capture", fs::copy_options::recursive);
    std::ofstream(scan / "scan.json")
        << R"({"format": "fpp-scan/1", "table": {"path": "/var/lib/fpp-scanner/table.fpt",)"
        << R"( "model": "rational", "file_fnv1a64": "0123456789abcdef"}})";
    expect_refused(verify(q(scan / "capture"), out / "report"), out / "report",
                   {"scan.json: table.file_fnv1a64", "another table", "--any-table"});
    const ToolRun anyway = verify("--any-table " + q(scan / "capture"), out / "report");
    EXPECT_EQ(anyway.exit_code, 0) << anyway.output;
}

TEST_F(CliVerify, RefusesBadOptions) {
    TempDir out;
    expect_refused(verify("--mpe-sd -1 " + q(capture("position-1")), out / "report"),
                   out / "report", {"--mpe-sd", "positive"});
    expect_refused(verify("--mpe-flatness 0.01 " + q(capture("position-1")), out / "report"),
                   out / "report", {"--mpe-flatness", "has no flat"});
    expect_refused(
        verify(q(capture("position-1")) + " " + q(capture("position-1")), out / "report"),
        out / "report", {"given twice"});
}

} // namespace
