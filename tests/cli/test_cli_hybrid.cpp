// fpp-calib hybrid and reconstruct --table, run as a person would: a stereo
// calibration from a checkerboard session, a table from the same session
// (boards placed by the camera) and from a plane session (the paper's), a
// scan reconstructed with each; `calibrate`, both from one reading; bad input gives exit code 2, a
// message naming the file and what is wrong, and nothing written. Camera binned 4x (400 x 300) so
// that each step takes a second or two.

#include "test_support.hpp"

#include "fpp/coefficient_table.hpp"
#include "fpp/point_cloud.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

namespace {

using fpp::test::file_bytes;

using fpp::test::shell_quote;
using fpp::test::TempDir;
using fpp::test::ToolRun;
namespace fs = std::filesystem;

ToolRun run_calib(const std::string& args, const TempDir& scratch) {
    return fpp::test::run_tool(fpp::test::calib_exe(), args, scratch.path());
}

bool contains(const std::string& text, const std::string& what) {
    return text.find(what) != std::string::npos;
}

// Sessions, calibration and table made once for the tests of this file.
struct Made {
    TempDir dir;
    fs::path calib, boards, planes, table, report;
};

const Made& made() {
    static Made* m = [] {
        auto* out = new Made;
        const fs::path boards = out->boards = out->dir / "boards";
        out->planes = out->dir / "planes";
        out->calib = out->dir / "calib.yaml";
        out->table = out->dir / "table.fpt";
        out->report = out->dir / "report";
        auto must = [&](const std::string& args) {
            const ToolRun run = run_calib(args, out->dir);
            EXPECT_EQ(run.exit_code, 0) << args << "\n" << run.output;
        };
        must("simulate-session --poses 10 --binning 4 --out " + shell_quote(boards));
        must("stereo " + shell_quote(boards) + " --out " + shell_quote(out->calib));
        must("simulate-session --kind plane --sequence gray-x --poses 8 --binning 4 --out " +
             shell_quote(out->planes));
        return out;
    }();
    return *m;
}

// A simulated scan of the inclined plane (camera binned 4 x 4) reconstructed
// with `table` into `cloud`; the reconstruct run, or the simulate run if that
// failed.
ToolRun scan_inclined_plane(const TempDir& dir, const fs::path& table, const fs::path& cloud) {
    const fs::path scan = dir / "scan";
    const ToolRun sim = run_calib(
        "simulate --rig " +
            shell_quote(fpp::test::source_dir() / "board/sim/paper-rig-effects.yaml") +
            " --scene inclined-plane --sequence gray-x --binning 4 --out " + shell_quote(scan),
        dir);
    if (sim.exit_code != 0)
        return sim;
    return run_calib("reconstruct " + shell_quote(scan) + " --table " + shell_quote(table) +
                         " --out " + shell_quote(cloud),
                     dir);
}

TEST(CliHybrid, TableFromPlanesReconstructsAScan) {
    const Made& m = made();
    TempDir dir;
    const fs::path table = dir / "table.fpt", report = dir / "report";
    const ToolRun hybrid =
        run_calib("hybrid " + shell_quote(m.planes) + " --calib " + shell_quote(m.calib) +
                      " --out " + shell_quote(table) + " --report " + shell_quote(report),
                  dir);
    ASSERT_EQ(hybrid.exit_code, 0) << hybrid.output;
    EXPECT_TRUE(contains(hybrid.output, "poses: 8 of 8 used")) << hybrid.output;
    EXPECT_TRUE(contains(hybrid.output, "hybrid model: rational")) << hybrid.output;
    const fpp::Size camera{400, 300};
    const fpp::CoefficientTable loaded = fpp::load_table(table, &camera);
    EXPECT_EQ(loaded.info().model, fpp::TableModel::rational);
    for (const char* f : {"summary.md", "poses.csv", "fit-rms-x.png", "fit-rms-y.png",
                          "fit-rms-z.png", "samples.png", "sigma-z.png", "plane-residuals.png"})
        EXPECT_TRUE(fs::exists(report / f)) << f;

    const fs::path cloud = dir / "cloud.ply";
    const ToolRun rec = scan_inclined_plane(dir, table, cloud);
    ASSERT_EQ(rec.exit_code, 0) << rec.output;
    EXPECT_TRUE(contains(rec.output, "error against ground truth")) << rec.output;
    const fpp::PlyPoints points = fpp::read_ply(cloud);
    // The inclined plane fills about 98 % of the field.
    EXPECT_GT(points.size(), 110000u);
    EXPECT_EQ(points.organised.width, 400);
    EXPECT_TRUE(contains(points.comments.front(), "hybrid model (rational"));
}

// One checkerboard session gives the stereo calibration and the table.
TEST(CliHybrid, TableFromTheCheckerboardSessionReconstructsAScan) {
    const Made& m = made();
    TempDir dir;
    const fs::path table = dir / "table.fpt", report = dir / "report";
    const ToolRun hybrid =
        run_calib("hybrid " + shell_quote(m.boards) + " --calib " + shell_quote(m.calib) +
                      " --out " + shell_quote(table) + " --report " + shell_quote(report),
                  dir);
    ASSERT_EQ(hybrid.exit_code, 0) << hybrid.output;
    EXPECT_TRUE(contains(hybrid.output, "procedure: checkerboards placed by the camera; fitted "
                                        "to boards+model"))
        << hybrid.output;
    EXPECT_TRUE(contains(hybrid.output, "poses: 10 of 10 used")) << hybrid.output;
    for (const char* f : {"summary.md", "poses.csv", "sv-offsets.png", "samples.png"})
        EXPECT_TRUE(fs::exists(report / f)) << f;
    const fs::path cloud = dir / "cloud.ply";
    const ToolRun rec = scan_inclined_plane(dir, table, cloud);
    ASSERT_EQ(rec.exit_code, 0) << rec.output;
    // The boards of 10 poses reach most of the plane.
    EXPECT_GT(fpp::read_ply(cloud).size(), 90000u);
}

// `calibrate` does both from one reading of the session: the calibration
// file byte for byte as `stereo` writes it, and every coefficient of the
// table as `hybrid` fits it from that file.
TEST(CliHybrid, CalibrateWritesWhatStereoAndThenHybridWrite) {
    const Made& m = made();
    TempDir dir;
    const fs::path calib = dir / "calib.yaml", table = dir / "table.fpt";
    const fs::path stereo_report = dir / "stereo-report", hybrid_report = dir / "hybrid-report";
    ToolRun run =
        run_calib("calibrate " + shell_quote(m.boards) + " --out " + shell_quote(calib) +
                      " --table " + shell_quote(table) + " --stereo-report " +
                      shell_quote(stereo_report) + " --hybrid-report " + shell_quote(hybrid_report),
                  dir);
    ASSERT_EQ(run.exit_code, 0) << run.output;
    EXPECT_TRUE(contains(run.output, "calibrated from 10 of 10 poses")) << run.output;
    EXPECT_TRUE(contains(run.output, "poses: 10 of 10 used")) << run.output;
    EXPECT_EQ(file_bytes(calib), file_bytes(m.calib));
    EXPECT_TRUE(fs::exists(stereo_report / "summary.md"));
    EXPECT_TRUE(fs::exists(hybrid_report / "sv-offsets.png"));

    const fs::path separate = dir / "separate.fpt";
    ASSERT_EQ(run_calib("hybrid " + shell_quote(m.boards) + " --calib " + shell_quote(m.calib) +
                            " --out " + shell_quote(separate),
                        dir)
                  .exit_code,
              0);
    const fpp::CoefficientTable a = fpp::load_table(table), b = fpp::load_table(separate);
    EXPECT_EQ(a.info().calibration_hash, b.info().calibration_hash);
    ASSERT_EQ(a.planes(), b.planes());
    ASSERT_EQ(a.info().camera, b.info().camera);
    int modelled = 0, differing = 0;
    for (int y = 0; y < a.info().camera.height; ++y)
        for (int x = 0; x < a.info().camera.width; ++x) {
            modelled += a.has_model(x, y) ? 1 : 0;
            for (int p = 0; p < a.planes(); ++p) {
                const float u = a.get(p, x, y), v = b.get(p, x, y);
                differing += (u == v || (std::isnan(u) && std::isnan(v))) ? 0 : 1;
            }
        }
    EXPECT_GT(modelled, 100000);
    EXPECT_EQ(differing, 0);

    // A plane session (the paper's) is not one session for both, and an
    // output that is a folder is refused before any work.
    const fs::path other = dir / "other.yaml";
    run = run_calib("calibrate " + shell_quote(m.planes) + " --out " + shell_quote(other) +
                        " --table " + shell_quote(dir / "other.fpt"),
                    dir);
    EXPECT_EQ(run.exit_code, 2) << run.output;
    EXPECT_TRUE(contains(run.output, "board.yaml")) << run.output;
    EXPECT_FALSE(fs::exists(other));
    run = run_calib("calibrate " + shell_quote(m.boards) + " --out " + shell_quote(other) +
                        " --table " + shell_quote(dir.path()),
                    dir);
    EXPECT_EQ(run.exit_code, 2) << run.output;
    EXPECT_TRUE(contains(run.output, "--table names the table file")) << run.output;
    EXPECT_FALSE(fs::exists(other));
}

TEST(CliHybrid, BadInputExitsWithTwoAndWritesNothing) {
    const Made& m = made();
    TempDir dir;
    // A checkerboard whose square size is not the stereo calibration's.
    const fs::path table = dir / "t.fpt", session = dir / "boards";
    fs::copy(m.boards, session, fs::copy_options::recursive);
    {
        std::stringstream read;
        read << std::ifstream(session / "board.yaml").rdbuf();
        std::string text = read.str();
        const std::size_t at = text.find("square_size: 15");
        ASSERT_NE(at, std::string::npos) << text;
        text.replace(at, 15, "square_size: 14");
        std::ofstream(session / "board.yaml") << text;
    }
    ToolRun run = run_calib("hybrid " + shell_quote(session) + " --calib " + shell_quote(m.calib) +
                                " --out " + shell_quote(table),
                            dir);
    EXPECT_EQ(run.exit_code, 2) << run.output;
    EXPECT_TRUE(contains(run.output, "board.yaml")) << run.output;
    EXPECT_TRUE(contains(run.output, "square_size")) << run.output;
    EXPECT_FALSE(fs::exists(table));

    // A table with one flipped bit in its coefficients.
    ASSERT_EQ(run_calib("hybrid " + shell_quote(m.planes) + " --calib " + shell_quote(m.calib) +
                            " --out " + shell_quote(table),
                        dir)
                  .exit_code,
              0);
    {
        std::fstream f(table, std::ios::in | std::ios::out | std::ios::binary);
        f.seekg(-100, std::ios::end);
        char c = 0;
        f.read(&c, 1);
        c = static_cast<char>(c ^ 0x10);
        f.seekp(-100, std::ios::end);
        f.write(&c, 1);
    }
    const fs::path scan = dir / "scan", cloud = dir / "cloud.ply";
    ASSERT_EQ(
        run_calib("simulate --scene plane --sequence gray-x --binning 4 --out " + shell_quote(scan),
                  dir)
            .exit_code,
        0);
    run = run_calib("reconstruct " + shell_quote(scan) + " --table " + shell_quote(table) +
                        " --out " + shell_quote(cloud),
                    dir);
    EXPECT_EQ(run.exit_code, 2) << run.output;
    EXPECT_TRUE(contains(run.output, "t.fpt")) << run.output;
    EXPECT_TRUE(contains(run.output, "crc")) << run.output;
    EXPECT_FALSE(fs::exists(cloud));

    // Both models at once.
    run = run_calib("reconstruct " + shell_quote(scan) + " --table " + shell_quote(table) +
                        " --calib " + shell_quote(m.calib) + " --out " + shell_quote(cloud),
                    dir);
    EXPECT_EQ(run.exit_code, 2) << run.output;
    EXPECT_TRUE(contains(run.output, "exactly one model")) << run.output;
    EXPECT_FALSE(fs::exists(cloud));
}

} // namespace
