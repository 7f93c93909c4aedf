// fpp-calib paper-experiments at reduced size (camera binned 4x, 400 x 300,
// fewer poses): the run completes, its figures show the accuracy relations the
// hybrid model must keep against SV (errors against ground truth on the
// noise-free scans, which isolate each model's own error), the tables load,
// and bad arguments exit non-zero and write nothing.

#include "test_support.hpp"

#include "fpp/calib/hybrid_calibrate.hpp"
#include "fpp/calib/paper_experiments.hpp"
#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/coefficient_table.hpp"
#include "fpp/image_io.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace {

using fpp::test::TempDir;
namespace fs = std::filesystem;

// Binning 4 with fewer poses than the paper's 15 + 30 (about 12 s in Release).
// The same configuration runs under the sanitizers: with fewer poses the
// calibration and the tables' phase range no longer cover the scans (6 + 14
// poses leave the cylinder outside every table's range), which would test
// nothing.
constexpr const char* kRunArguments =
    "--binning 4 --checkerboard-poses 8 --plane-poses 20 --timing-runs 2 --seed 2";
constexpr double kCameraPixels = 400.0 * 300.0;

using fpp::test::ToolRun;

std::string quote(const std::string& s) {
    return fpp::test::shell_quote(s);
}

ToolRun run_calib(const std::string& args, const fs::path& scratch) {
    return fpp::test::run_tool(FPP_CALIB_EXE, args, scratch);
}

std::string read_text(const fs::path& path) {
    std::ifstream in(path);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

bool contains(const std::string& text, const std::string& what) {
    return text.find(what) != std::string::npos;
}

std::vector<std::string> listing(const fs::path& folder) {
    std::vector<std::string> names;
    for (const auto& e : fs::recursive_directory_iterator(folder))
        names.push_back(fs::relative(e.path(), folder).string());
    std::sort(names.begin(), names.end());
    return names;
}

// One run of the command (once per process and rig).
struct Shared {
    TempDir dir;
    fs::path out;
    ToolRun run;
    std::map<std::string, double> figures;

    double figure(const std::string& name) const {
        const auto it = figures.find(name);
        EXPECT_NE(it, figures.end()) << "figures.csv has no " << name;
        return it == figures.end() ? std::nan("") : it->second;
    }
};

Shared* run_with(const std::string& rig_arguments) {
    auto* r = new Shared;
    r->out = r->dir / "paper";
    r->run = run_calib("paper-experiments --out " + quote(r->out.string()) + " " + kRunArguments +
                           rig_arguments,
                       r->dir.path());
    std::ifstream in(r->out / "report" / "figures.csv");
    std::string line;
    std::getline(in, line); // header
    while (std::getline(in, line)) {
        const auto a = line.find(','), b = line.rfind(',');
        if (a == std::string::npos || b == a)
            continue;
        r->figures[line.substr(0, a)] = std::stod(line.substr(a + 1, b - a - 1));
    }
    return r;
}

// The rig with effects, on which the stereo model fits (board/sim/paper-rig-effects.yaml).
Shared& shared() {
    static Shared* s = run_with(
        " --rig " + quote((fpp::test::source_dir() / "board/sim/paper-rig-effects.yaml").string()));
    return *s;
}

// The command's default rig: the same with lens defects that bend SV's surfaces.
Shared& lens_defects() {
    static Shared* s = run_with("");
    return *s;
}

double figure(const std::string& name) {
    return shared().figure(name);
}

std::string default_model() {
    return fpp::to_string(fpp::calib::HybridOptions{}.model);
}

std::vector<std::string> models() {
    std::vector<std::string> names;
    for (fpp::TableModel m : fpp::calib::available_table_models())
        names.push_back(fpp::to_string(m));
    return names;
}

TEST(CliPaperExperiments, RunsWritesItsOutputsAndKeepsTheAccuracyRelations) {
    const Shared& s = shared();
    ASSERT_EQ(s.run.exit_code, 0) << s.run.output;
    EXPECT_TRUE(contains(s.run.output, "targets met")) << s.run.output;
    EXPECT_TRUE(contains(s.run.output, "stereo calibration")) << s.run.output; // progress
    EXPECT_EQ(figure("run.camera_width"), 400);
    EXPECT_EQ(figure("run.camera_height"), 300);
    EXPECT_LT(figure("calibration.camera_rms"), 0.1);
    EXPECT_LT(figure("calibration.projector_rms"), 0.1);

    // Each model's own error (noise-free scans, pixel by pixel against the
    // true surface) for the default hybrid model: no worse than SV on the
    // plane, the cylinder and the sphere. The paper's factor of two on the
    // plane is NOT reached on the simulated rig: its stereo calibration
    // absorbs most of the distortion outside the 5-coefficient model, and what
    // is left mostly keeps planes flat (a depth bias), which a correction onto
    // each board's best plane cannot see. The command reports that target as
    // not met (target.plane_half_of_sv.*); here the relation that holds is
    // guarded.
    const std::string m = default_model();
    const double plane_sv = figure("truth.plane.noise_free.sv.rms");
    EXPECT_GT(plane_sv, 0.01); // the rig's effects and the calibration leave SV an error
    for (const char* scene : {"plane", "cylinder", "sphere"}) {
        const std::string base = std::string("truth.") + scene + ".noise_free.";
        EXPECT_LE(figure(base + m + ".rms"), figure(base + "sv.rms")) << scene;
        EXPECT_LT(figure(base + m + ".rms"), 0.15) << scene;
        // Most of what SV sees is compared (edges beyond the calibrated
        // volume and a 2 px silhouette margin are left out).
        EXPECT_GT(figure(std::string(scene) + ".common_points"),
                  0.9 * figure(std::string(scene) + ".points.sv"))
            << scene;
    }
    // Every target is reported, met or not.
    for (const std::string& model : models())
        for (const char* key :
             {"target.plane_half_of_sv.noise_free.", "target.cylinder_no_worse_than_sv.noise_free.",
              "target.sphere_no_worse_than_sv.noise_free.", "target.relief_no_worse_than_sv.noisy.",
              "target.relief_speedup_50x."}) {
            const double met = figure(key + model);
            EXPECT_TRUE(met == 0 || met == 1) << key << model;
        }
    EXPECT_EQ(figure("target.cylinder_no_worse_than_sv.noise_free." + m), 1);
    EXPECT_EQ(figure("target.sphere_no_worse_than_sv.noise_free." + m), 1);

    // Shape figures: the paper's shapes are measured to their nominal size.
    EXPECT_NEAR(figure("cylinder.diameter." + m), 168.0, 0.5);
    EXPECT_NEAR(figure("sphere.diameter." + m), 120.0, 0.5);
    // Noise-free flatness of the plane: every model well below the noise.
    for (const std::string& model : models())
        EXPECT_LT(figure("plane.fit_rms_noise_free." + model), 0.015) << model;

    // The relief is sized to ~680,000 pixels at full size (/ 16 here).
    EXPECT_NEAR(figure("relief.pixels_seen"), 680000.0 / 16.0, 0.1 * 680000.0 / 16.0);
    EXPECT_GT(figure("relief.points.sv"), 0.9 * figure("relief.pixels_seen"));
    EXPECT_LT(figure("relief.difference." + m + ".distance_rms"), 0.05);
    EXPECT_GT(figure("relief.time.sv"), 0);
    EXPECT_GT(figure("relief.speedup." + m), 1); // the kernel is faster than SV's solver

    // Windows: eight sizes N = 25 .. 200; the cropped reconstructions are the
    // full image's.
    for (int n = 25; n <= 200; n += 25) {
        const std::string base = "windows.n" + std::to_string(n);
        EXPECT_EQ(figure(base + ".points"), double(n) * double(n)) << n; // inside the plane
        EXPECT_GT(figure(base + ".time.sv"), 0) << n;
        EXPECT_GT(figure(base + ".time." + m), 0) << n;
    }
    EXPECT_LT(figure("windows.crop_max_difference"), 1e-3);
    EXPECT_EQ(figure("windows.crop_mismatched"), 0);

    // Outputs.
    const fpp::calib::StereoCalibration c = fpp::calib::load_calibration(s.out / "calib.yaml");
    EXPECT_EQ(c.camera_size, (fpp::Size{400, 300}));
    const fpp::Size camera{400, 300};
    ASSERT_FALSE(models().empty());
    for (const std::string& model : models()) {
        const fpp::CoefficientTable table =
            fpp::load_table(s.out / ("table-" + model + ".fpt"), &camera);
        EXPECT_EQ(fpp::to_string(table.info().model), model);
        EXPECT_TRUE(table.has_model(200, 150)) << model;
        EXPECT_GT(figure("hybrid." + model + ".pixels_modelled"), 0.95 * kCameraPixels) << model;
        EXPECT_TRUE(fs::exists(s.out / ("hybrid-report-" + model) / "summary.md")) << model;
        // Every model gets a row in every comparison.
        EXPECT_GE(figure("truth.relief.noise_free." + model + ".rms"), 0) << model;
    }
    EXPECT_TRUE(fs::exists(s.out / "stereo-report" / "summary.md"));
    for (const char* scan : {"plane", "cylinder", "sphere", "relief"}) {
        EXPECT_TRUE(fs::exists(s.out / "scans" / scan / "capture.yaml")) << scan;
        EXPECT_TRUE(fs::exists(s.out / "scans" / scan / "truth_xyz.tiff")) << scan;
    }
    EXPECT_FALSE(fs::exists(s.out / "sessions")); // removed without --keep-sessions

    const std::string summary = read_text(s.out / "report" / "summary.md");
    for (const char* paper : {"0.118", "0.044", "0.076", "0.059", "1.040 s", "683047"})
        EXPECT_TRUE(contains(summary, paper)) << paper << "\n" << summary;
    EXPECT_TRUE(contains(summary, "## Targets")) << summary;
    for (const std::string png :
         {"plane-fit-histogram.png", "plane-fit-map-sv.png", "cylinder-fit-histogram.png",
          "sphere-fit-map-sv.png", "relief-difference-histogram.png", "windows-timing.png",
          "truth-plane-sv.png"}) {
        const fs::path path = s.out / "report" / png;
        ASSERT_TRUE(fs::exists(path)) << png;
        const fpp::PngInfo info = fpp::read_png_info(path);
        EXPECT_EQ(info.channels, 3) << png;
        EXPECT_GT(info.size.width, 300) << png;
    }
    EXPECT_TRUE(fs::exists(s.out / "report" / ("plane-fit-map-" + m + ".png")));
    // Nothing but the output folder (no temporary left).
    EXPECT_EQ(listing(s.dir.path()).size(), listing(s.out).size() + 1);
}

TEST(CliPaperExperiments, ExistingOutputFolderIsRefusedAndLeftAlone) {
    TempDir logs, dir;
    const fs::path out = dir / "taken";
    fs::create_directories(out);
    std::ofstream(out / "keep.txt") << "mine\n";
    const std::vector<std::string> before = listing(dir.path());
    const ToolRun run =
        run_calib("paper-experiments --binning 4 --out " + quote(out.string()), logs.path());
    EXPECT_EQ(run.exit_code, 2) << run.output;
    EXPECT_TRUE(contains(run.output, "already exists")) << run.output;
    EXPECT_EQ(listing(dir.path()), before);
    EXPECT_EQ(read_text(out / "keep.txt"), "mine\n");
}

TEST(CliPaperExperiments, BadArgumentsExitNonZeroAndWriteNothing) {
    TempDir logs, dir;
    const fs::path log = logs.path();
    // Missing parent folder.
    ToolRun run = run_calib("paper-experiments --binning 4 --out " +
                                quote((dir / "no" / "such" / "out").string()),
                            log);
    EXPECT_EQ(run.exit_code, 2) << run.output;
    EXPECT_TRUE(contains(run.output, "does not exist")) << run.output;
    // Out-of-range options are refused before anything is done.
    for (const char* bad : {"--binning 0", "--binning 9", "--plane-poses 3",
                            "--checkerboard-poses 2", "--timing-runs 0"}) {
        run = run_calib(std::string("paper-experiments ") + bad + " --out " +
                            quote((dir / "out").string()),
                        log);
        EXPECT_NE(run.exit_code, 0) << bad << "\n" << run.output;
    }
    // --out is required.
    run = run_calib("paper-experiments --binning 4", log);
    EXPECT_NE(run.exit_code, 0) << run.output;
    EXPECT_TRUE(listing(dir.path()).empty());
}

} // namespace

// The default rig's lens defects bend SV's surfaces by about the paper's
// 0.118 mm; the hybrid tables remove the bend, as the paper's Fig. 6 and 7.
// (Against the truth they cannot remove the depth bias and tilt the
// calibration takes on from those defects; see the report.)
TEST(CliPaperExperiments, LensDefectsRigReproducesThePapersFlatteningOfSvErrors) {
    const Shared& d = lens_defects();
    ASSERT_EQ(d.run.exit_code, 0) << d.run.output;
    const std::string m = default_model();
    const double plane_sv = d.figure("plane.fit_rms_noise_free.sv");
    EXPECT_GT(plane_sv, 0.06);
    EXPECT_LT(plane_sv, 0.2);
    EXPECT_LT(d.figure("plane.fit_rms_noise_free." + m), 0.25 * plane_sv);
    EXPECT_LT(d.figure("cylinder.fit_rms_noise_free." + m),
              0.25 * d.figure("cylinder.fit_rms_noise_free.sv"));
    // With noise, as the paper measured: SV near its 0.118 mm, the hybrid
    // below its 0.044 mm.
    EXPECT_LT(d.figure("plane.fit_rms." + m), 0.5 * d.figure("plane.fit_rms.sv"));
    EXPECT_LT(d.figure("plane.fit_rms." + m), 0.044);
    EXPECT_LT(d.figure("calibration.projector_rms"), 0.3); // below the real rigs' 0.28 px
    // Against the truth, with each error's depth offset and tilt taken out
    // (what a correction onto planes can reach): the hybrid at most half of
    // SV's on the plane, and no worse on the cylinder, sphere and relief.
    for (const char* key : {"plane_shape_half_of_sv", "cylinder_shape_no_worse_than_sv",
                            "sphere_shape_no_worse_than_sv", "relief_shape_no_worse_than_sv"})
        EXPECT_EQ(d.figure(std::string("target.") + key + ".noise_free." + m), 1) << key;
    EXPECT_LT(d.figure("truth.plane.noise_free." + m + ".shape_rms"),
              0.25 * d.figure("truth.plane.noise_free.sv.shape_rms"));
}
