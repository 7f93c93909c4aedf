// The hybrid calibration report on a hand-made HybridResult: the Markdown
// summary's fit-RMS table (median, 99 % and max of each map, NaN pixels
// left out), its checkerboard-only paragraph and figure list, and the
// report folder: the files it writes, poses.csv row by row, an earlier
// report replaced and a folder that is not a report refused untouched.

#include "test_support.hpp"

#include "fpp/calib/hybrid_report.hpp"
#include "fpp/calib/trueness.hpp"
#include "fpp/error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

namespace {

using fpp::BoardDescription;
using fpp::Image;
using fpp::calib::HybridPose;
using fpp::calib::HybridResult;
using fpp::test::TempDir;
namespace fs = std::filesystem;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

Image<float> image_of(const float (&v)[8]) {
    Image<float> im(4, 2);
    for (std::size_t k = 0; k < 8; ++k)
        im.data()[k] = v[k];
    return im;
}

HybridResult sample(BoardDescription::Kind board) {
    HybridResult r;
    r.board = board;
    // X: 7 finite values (one NaN) sorted 0.125 .. 2: median the 4th (0.5),
    // 99 % the 6th (index floor(0.99 * 6) = 5: 1.0), max 2.0.
    r.rms_x = image_of({0.5f, 0.25f, 0.125f, 1.0f, 2.0f, 0.75f, 0.375f, kNaN});
    r.rms_y = image_of({0.0625f, 0.0625f, 0.0625f, 0.0625f, 0.0625f, 0.0625f, 0.0625f, 0.0625f});
    // Z: 8 values sorted 0.01 0.01 0.02 0.03 0.04 0.05 0.06 0.09: median
    // index floor(3.5) = 3 (0.03, not the mean 0.035), 99 % index 6 (0.06).
    r.rms_z = image_of({0.03f, 0.01f, 0.04f, 0.01f, 0.05f, 0.09f, 0.02f, 0.06f});
    r.sigma_z = image_of({0.2f, 0.2f, 0.3f, 0.3f, kNaN, 0.4f, 0.4f, 0.5f});
    r.pose_count = Image<std::uint16_t>(4, 2);
    for (std::size_t k = 0; k < 8; ++k)
        r.pose_count.data()[k] = static_cast<std::uint16_t>(k % 3);
    r.pixels_modelled = 7;
    r.pixels_too_few_poses = 1;
    r.usable_poses = 2;

    HybridPose a;
    a.name = "pose-01";
    a.usable = true;
    a.points = 12345;
    a.outliers = 67;
    a.distance_mm = 456.7891;
    a.tilt_deg = 12.3456;
    a.plane_rms_mm = 0.012346;
    a.plane_max_mm = 0.098766;
    a.corner_rms_px = 0.123456;
    a.lit_fraction = 0.43211;
    a.samples = 2048;
    a.sv_offset_mm = -0.004321;
    a.sv_angle_deg = 0.012341;
    HybridPose b = a;
    b.name = "pose-02";
    b.distance_mm = 512.25;
    b.tilt_deg = -3.5;
    b.sv_offset_mm = 0.0025;
    HybridPose c;
    c.name = "pose-03";
    c.usable = false;
    c.skip_reason = "board not found, too dark";
    r.poses = {a, b, c};
    r.trueness.length_mm = 100;
    r.trueness.at = {fpp::calib::LengthSigma{400, 0.01, 0.002},
                     fpp::calib::LengthSigma{500, 0.02, 0.003},
                     fpp::calib::LengthSigma{600, 0.03, 0.004}};
    return r;
}

std::string read_text(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

bool has_line(const std::string& text, const std::string& line) {
    return text.find(line + "\n") != std::string::npos;
}

TEST(HybridSummaryMarkdown, FitRmsTableFromTheMaps) {
    const HybridResult r = sample(BoardDescription::Kind::plane);
    const std::string md = fpp::calib::hybrid_summary_markdown(r);
    // The result's own summary, verbatim in a code block, first.
    EXPECT_EQ(md.rfind("# Hybrid calibration\n\n```\n" + r.summary() + "```\n\n", 0), 0u) << md;
    EXPECT_TRUE(has_line(md, "| Fit RMS (mm) | median | 99 % | max |")) << md;
    EXPECT_TRUE(has_line(md, "| X | 0.5000 | 1.0000 | 2.0000 |")) << md;
    EXPECT_TRUE(has_line(md, "| Y | 0.0625 | 0.0625 | 0.0625 |")) << md;
    EXPECT_TRUE(has_line(md, "| Z | 0.0300 | 0.0600 | 0.0900 |")) << md;
    // The X, Y, Z rows in that order.
    EXPECT_LT(md.find("| X |"), md.find("| Y |"));
    EXPECT_LT(md.find("| Y |"), md.find("| Z |"));
}

TEST(HybridSummaryMarkdown, AllNaNMapGivesZeros) {
    HybridResult r = sample(BoardDescription::Kind::plane);
    r.rms_y = image_of({kNaN, kNaN, kNaN, kNaN, kNaN, kNaN, kNaN, kNaN});
    const std::string md = fpp::calib::hybrid_summary_markdown(r);
    EXPECT_TRUE(has_line(md, "| Y | 0.0000 | 0.0000 | 0.0000 |")) << md;
    EXPECT_TRUE(has_line(md, "| X | 0.5000 | 1.0000 | 2.0000 |")) << md;
}

TEST(HybridSummaryMarkdown, TruenessAndFiguresOfAPlaneSession) {
    const HybridResult r = sample(BoardDescription::Kind::plane);
    const std::string md = fpp::calib::hybrid_summary_markdown(r);
    EXPECT_NE(md.find(fpp::calib::trueness_summary(r.trueness)), std::string::npos) << md;
    EXPECT_NE(md.find("a 100 mm length at 500 mm"), std::string::npos) << md;
    EXPECT_TRUE(has_line(md, "Figures: fit-rms-x.png, fit-rms-y.png, fit-rms-z.png (per-pixel "
                             "fit RMS), sigma-z.png, samples.png, plane-residuals.png; poses.csv."))
        << md;
    EXPECT_EQ(md.find("sv-offsets.png"), std::string::npos) << md;
    EXPECT_EQ(md.find("placed by the camera alone"), std::string::npos) << md;
}

TEST(HybridSummaryMarkdown, CheckerboardSessionAddsItsParagraphAndFigure) {
    const std::string md =
        fpp::calib::hybrid_summary_markdown(sample(BoardDescription::Kind::checkerboard));
    EXPECT_NE(md.find("\nEach board is placed by the camera alone"), std::string::npos) << md;
    EXPECT_TRUE(has_line(md, "Figures: fit-rms-x.png, fit-rms-y.png, fit-rms-z.png (per-pixel "
                             "fit RMS), sigma-z.png, samples.png, plane-residuals.png, "
                             "sv-offsets.png; poses.csv."))
        << md;
}

TEST(WriteHybridReport, WritesEveryFileOfACheckerboardSession) {
    TempDir dir;
    const fs::path folder = dir / "report";
    const HybridResult r = sample(BoardDescription::Kind::checkerboard);
    fpp::calib::write_hybrid_report(folder, r);
    for (const char* name :
         {"summary.md", "poses.csv", "fit-rms-x.png", "fit-rms-y.png", "fit-rms-z.png",
          "sigma-z.png", "samples.png", "plane-residuals.png", "sv-offsets.png"}) {
        ASSERT_TRUE(fs::is_regular_file(folder / name)) << name;
        EXPECT_GT(fs::file_size(folder / name), 0u) << name;
    }
    // Nothing else (no temporary folder left beside or inside it).
    int files = 0;
    for ([[maybe_unused]] const auto& e : fs::directory_iterator(folder))
        ++files;
    EXPECT_EQ(files, 9);
    int entries = 0;
    for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir.path()))
        ++entries;
    EXPECT_EQ(entries, 1);
    EXPECT_EQ(read_text(folder / "summary.md"), fpp::calib::hybrid_summary_markdown(r));
    const std::string png = read_text(folder / "samples.png");
    EXPECT_EQ(png.substr(1, 3), "PNG");
}

TEST(WriteHybridReport, PosesCsvRows) {
    TempDir dir;
    const fs::path folder = dir / "report";
    fpp::calib::write_hybrid_report(folder, sample(BoardDescription::Kind::checkerboard));
    const std::string csv = read_text(folder / "poses.csv");
    const std::string expected =
        "pose,usable,points,outliers,distance_mm,tilt_deg,plane_rms_mm,plane_max_mm,"
        "corner_rms_px,lit_fraction,samples,sv_offset_mm,sv_angle_deg,reason\n"
        "pose-01,1,12345,67,456.789,12.346,0.01235,0.09877,0.12346,0.4321,2048,-0.00432,0.01234,\n"
        "pose-02,1,12345,67,512.250,-3.500,0.01235,0.09877,0.12346,0.4321,2048,0.00250,0.01234,\n"
        "pose-03,0,0,0,0.000,0.000,0.00000,0.00000,0.00000,0.0000,0,0.00000,0.00000,"
        "board not found; too dark\n";
    EXPECT_EQ(csv, expected);
}

TEST(WriteHybridReport, PlaneSessionHasNoSvOffsetFigure) {
    TempDir dir;
    const fs::path folder = dir / "report";
    fpp::calib::write_hybrid_report(folder, sample(BoardDescription::Kind::plane));
    EXPECT_TRUE(fs::is_regular_file(folder / "plane-residuals.png"));
    EXPECT_FALSE(fs::exists(folder / "sv-offsets.png"));
}

TEST(WriteHybridReport, ReplacesAnEarlierReport) {
    TempDir dir;
    const fs::path folder = dir / "report";
    fpp::calib::write_hybrid_report(folder, sample(BoardDescription::Kind::checkerboard));
    ASSERT_TRUE(fs::exists(folder / "sv-offsets.png"));
    const HybridResult plane = sample(BoardDescription::Kind::plane);
    fpp::calib::write_hybrid_report(folder, plane);
    EXPECT_EQ(read_text(folder / "summary.md"), fpp::calib::hybrid_summary_markdown(plane));
    // The earlier report's checkerboard-only figure is gone with it.
    EXPECT_FALSE(fs::exists(folder / "sv-offsets.png"));
}

TEST(WriteHybridReport, RefusesAFolderThatIsNotAReport) {
    TempDir dir;
    const fs::path folder = dir / "photos";
    fs::create_directories(folder);
    { std::ofstream(folder / "holiday.txt") << "keep me\n"; }
    EXPECT_THROW(fpp::calib::write_hybrid_report(folder, sample(BoardDescription::Kind::plane)),
                 fpp::InputError);
    EXPECT_EQ(read_text(folder / "holiday.txt"), "keep me\n");
    EXPECT_FALSE(fs::exists(folder / "summary.md"));
    // A regular file in the report's place is refused too.
    const fs::path file = dir / "report.md";
    { std::ofstream(file) << "notes\n"; }
    EXPECT_THROW(fpp::calib::write_hybrid_report(file, sample(BoardDescription::Kind::plane)),
                 fpp::InputError);
    EXPECT_EQ(read_text(file), "notes\n");
}

} // namespace
