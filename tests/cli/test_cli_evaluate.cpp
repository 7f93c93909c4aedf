// fpp-calib evaluate, run as a person would, on small synthetic clouds with
// known answers: a noisy tilted plane (fit, ground truth, comparison with a
// shifted copy), a partial 168 mm cylinder, an unorganised sphere; and bad
// inputs that must exit with 2, name what is wrong and leave no output.

#include "calib_run.hpp"
#include "test_support.hpp"

#include "fpp/capture_set.hpp"
#include "fpp/image_io.hpp"
#include "fpp/point_cloud.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>

namespace {

using fpp::Image;
using fpp::test::TempDir;
namespace fs = std::filesystem;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

using fpp::test::ToolRun;

std::string quote(const std::string& s) {
    return fpp::test::shell_quote(s);
}

std::string q(const fs::path& p) {
    return quote(p.string());
}

using fpp::test::run_calib;

// figures.csv as name -> value (checks the header and the three columns).
std::map<std::string, double> read_figures(const fs::path& file) {
    std::ifstream in(file);
    std::string line;
    std::getline(in, line);
    EXPECT_EQ(line, "name,value,unit");
    std::map<std::string, double> figures;
    while (std::getline(in, line)) {
        const auto a = line.find(','), b = line.rfind(',');
        EXPECT_NE(a, b) << line;
        figures[line.substr(0, a)] = std::stod(line.substr(a + 1, b - a - 1));
    }
    return figures;
}

double figure(const std::map<std::string, double>& f, const std::string& name) {
    const auto it = f.find(name);
    if (it == f.end()) {
        ADD_FAILURE() << "figures.csv has no " << name;
        return std::nan("");
    }
    return it->second;
}

void expect_png(const fs::path& file) {
    const cv::Mat image = cv::imread(file.string(), cv::IMREAD_UNCHANGED);
    EXPECT_FALSE(image.empty()) << file;
    EXPECT_EQ(image.type(), CV_8UC3) << file;
    EXPECT_GE(image.cols, 400) << file;
}

// A 80 x 60 camera (f = 100 px, principal point at the centre) looking at a
// tilted plane through (0, 0, 500); columns 0 and 1 see no surface.
constexpr int kW = 80, kH = 60;

struct Scene {
    Image<float> truth;      // noise-free
    fpp::PointCloud noisy;   // truth + N(0, 0.05 mm) along the plane normal
    fpp::PointCloud shifted; // noisy + 0.1 mm in Z
};

Scene plane_scene() {
    const double n[3] = {0.2, -0.1, -1.0};
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    const double nu[3] = {n[0] / len, n[1] / len, n[2] / len};
    Scene s;
    s.truth = Image<float>(kW, kH, 3, kNaN);
    s.noisy.xyz = Image<float>(kW, kH, 3, kNaN);
    s.shifted.xyz = Image<float>(kW, kH, 3, kNaN);
    std::mt19937 rng(17);
    std::normal_distribution<double> noise(0, 0.05);
    for (int y = 0; y < kH; ++y)
        for (int x = 2; x < kW; ++x) {
            const double d[3] = {(x - 39.5) / 100, (y - 29.5) / 100, 1};
            // (t d - (0, 0, 500)) . n = 0
            const double t = 500 * nu[2] / (d[0] * nu[0] + d[1] * nu[1] + d[2] * nu[2]);
            const double e = noise(rng);
            for (int c = 0; c < 3; ++c) {
                const double p = t * d[c];
                s.truth.at(x, y, c) = static_cast<float>(p);
                s.noisy.xyz.at(x, y, c) = static_cast<float>(p + e * nu[c]);
                s.shifted.xyz.at(x, y, c) =
                    static_cast<float>(p + e * nu[c] + (c == 2 ? 0.1 : 0.0));
            }
        }
    return s;
}

// A capture set (two frames) whose manifest lists the truth XYZ.
void write_truth_capture(const fs::path& folder, const Image<float>& truth) {
    fpp::CaptureManifest m;
    m.camera = {kW, kH};
    m.projector = {64, 48};
    m.frames = {"000.png", "001.png"};
    m.sequence = {fpp::WhiteBlock{}, fpp::BlackBlock{}};
    m.truth = fpp::TruthFiles{"truth_xyz.tiff", ""};
    std::vector<fpp::Frame> frames(2);
    for (fpp::Frame& f : frames)
        f.u8 = Image<std::uint8_t>(kW, kH, 1, 128);
    fpp::write_capture_set(folder, m, frames, fpp::TruthImages{&truth, nullptr});
}

// A PLY with x, y, z only (no organised size, no pixel indices).
void write_plain_ply(const fs::path& file, const std::vector<std::array<float, 3>>& points) {
    std::ofstream out(file, std::ios::binary);
    out << "ply\nformat binary_little_endian 1.0\nelement vertex " << points.size()
        << "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
    for (const auto& p : points)
        out.write(reinterpret_cast<const char*>(p.data()), 12);
}

class CliEvaluate : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        dir_ = new TempDir;
        const Scene s = plane_scene();
        fpp::write_ply(*dir_ / "sv.ply", s.noisy);
        fpp::write_ply(*dir_ / "hybrid.ply", s.shifted);
        write_truth_capture(*dir_ / "capture", s.truth);
    }
    static void TearDownTestSuite() {
        delete dir_;
        dir_ = nullptr;
    }
    static TempDir* dir_;
};

TempDir* CliEvaluate::dir_ = nullptr;

TEST_F(CliEvaluate, Help) {
    const auto run = run_calib("evaluate --help", dir_->path());
    EXPECT_EQ(run.exit_code, 0);
    for (const char* option : {"--fit", "--nominal-diameter", "--nominal-length", "--truth",
                               "--compare", "--label", "--other-label", "--out"})
        EXPECT_NE(run.output.find(option), std::string::npos) << option;
}

TEST_F(CliEvaluate, PlaneFit) {
    TempDir out;
    const auto run = run_calib(
        "evaluate " + q(*dir_ / "sv.ply") + " --fit plane --out " + q(out / "r"), out.path());
    ASSERT_EQ(run.exit_code, 0) << run.output;
    const auto f = read_figures(out / "r" / "figures.csv");
    EXPECT_EQ(figure(f, "cloud.points"), 78.0 * 60);
    EXPECT_EQ(figure(f, "cloud.fit.points_used"), 78.0 * 60);
    EXPECT_NEAR(figure(f, "cloud.fit.rms"), 0.05, 0.005);
    // 4680 Gaussian residuals span about 7.4 sigma; 14 excluded trim the range.
    EXPECT_GT(figure(f, "cloud.plane.flatness"), 6 * 0.05);
    EXPECT_LT(figure(f, "cloud.plane.flatness"), 9.5 * 0.05);
    EXPECT_LT(figure(f, "cloud.plane.flatness_trimmed"), figure(f, "cloud.plane.flatness"));
    EXPECT_EQ(figure(f, "cloud.plane.trimmed_excluded"), 14.0);
    const double n[3] = {0.2, -0.1, -1.0};
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    EXPECT_NEAR(figure(f, "cloud.plane.normal_x"), n[0] / len, 1e-3);
    EXPECT_NEAR(figure(f, "cloud.plane.normal_z"), n[2] / len, 1e-3);
    expect_png(out / "r" / "fit-histogram.png");
    expect_png(out / "r" / "fit-map.png");
    EXPECT_TRUE(fs::exists(out / "r" / "summary.md"));
    EXPECT_NE(run.output.find("flatness"), std::string::npos);

    // Running again replaces the earlier report.
    const auto again = run_calib("evaluate " + q(*dir_ / "sv.ply") +
                                     " --fit plane --reject-sigma 3 --out " + q(out / "r"),
                                 out.path());
    ASSERT_EQ(again.exit_code, 0) << again.output;
    const auto g = read_figures(out / "r" / "figures.csv");
    EXPECT_GT(figure(g, "cloud.fit.points_rejected"), 0.0);
    EXPECT_LT(figure(g, "cloud.fit.points_rejected"), 40.0);
}

TEST_F(CliEvaluate, CompareWithTruthAndLabels) {
    TempDir out;
    const auto run =
        run_calib("evaluate " + q(*dir_ / "sv.ply") + " --compare " + q(*dir_ / "hybrid.ply") +
                      " --fit plane --truth " + q(*dir_ / "capture") +
                      " --label SV --other-label hybrid --out " + q(out / "r"),
                  out.path());
    ASSERT_EQ(run.exit_code, 0) << run.output;
    const fs::path r = out / "r";
    const auto f = read_figures(r / "figures.csv");
    // The copy is 0.1 mm further in Z at every pixel.
    EXPECT_EQ(figure(f, "compare.matched"), 78.0 * 60);
    EXPECT_NEAR(figure(f, "compare.distance_rms"), 0.1, 1e-4);
    EXPECT_NEAR(figure(f, "compare.dz_mean"), -0.1, 1e-4);
    EXPECT_NEAR(figure(f, "compare.dz_stddev"), 0.0, 1e-4);
    // Against the truth: noise along the normal (3D RMS = sigma), full coverage.
    EXPECT_NEAR(figure(f, "cloud.truth.coverage"), 100.0, 1e-9);
    EXPECT_EQ(figure(f, "cloud.truth.compared"), 78.0 * 60);
    EXPECT_NEAR(figure(f, "cloud.truth.distance_rms"), 0.05, 0.005);
    EXPECT_NEAR(figure(f, "other.truth.dz_mean") - figure(f, "cloud.truth.dz_mean"), 0.1, 1e-4);
    // The 0.1 mm offset is not shape: both copies have the same shape error.
    EXPECT_NEAR(figure(f, "other.truth.dz_shape_rms"), figure(f, "cloud.truth.dz_shape_rms"), 1e-4);
    EXPECT_LT(figure(f, "other.truth.dz_shape_rms"), figure(f, "other.truth.dz_rms") - 0.05);
    EXPECT_NEAR(figure(f, "other.fit.rms"), figure(f, "cloud.fit.rms"), 1e-4);
    // One rigid motion of the whole cloud takes the 0.1 mm offset away and
    // leaves the noise: both copies alike, no worse than without it.
    EXPECT_NEAR(figure(f, "other.truth.rigid_shift"), 0.1, 0.005);
    EXPECT_NEAR(figure(f, "other.truth.rigid_distance_rms"),
                figure(f, "cloud.truth.rigid_distance_rms"), 1e-4);
    EXPECT_LE(figure(f, "cloud.truth.rigid_distance_rms"), figure(f, "cloud.truth.distance_rms"));
    EXPECT_LT(figure(f, "other.truth.rigid_distance_rms"), figure(f, "other.truth.distance_rms"));
    for (const char* png :
         {"fit-histogram.png", "fit-map.png", "fit-map-other.png", "truth-histogram.png",
          "truth-map.png", "truth-map-other.png", "difference-histogram.png", "difference-map.png"})
        expect_png(r / png);
    std::ifstream in(r / "summary.md");
    std::stringstream summary;
    summary << in.rdbuf();
    EXPECT_NE(summary.str().find("| SV | hybrid |"), std::string::npos) << summary.str();
    EXPECT_NE(summary.str().find("SV - hybrid"), std::string::npos);

    // Unorganised pairing works on the same files.
    const auto nearest =
        run_calib("evaluate " + q(*dir_ / "sv.ply") + " --compare " + q(*dir_ / "hybrid.ply") +
                      " --match nearest --out " + q(out / "n"),
                  out.path());
    ASSERT_EQ(nearest.exit_code, 0) << nearest.output;
    const auto g = read_figures(out / "n" / "figures.csv");
    // Nearest points lie at most 0.1 mm away (the own copy is a candidate).
    EXPECT_LE(figure(g, "compare.distance_max"), 0.1 + 1e-4);
    EXPECT_GT(figure(g, "compare.distance_rms"), 0.05);
    expect_png(out / "n" / "difference-histogram.png");
}

TEST_F(CliEvaluate, PartialCylinder) {
    // A 168 mm pipe, axis along Y at Z = 600, seen by a 100 x 80 camera with
    // f = 400 px: about 100 degrees of arc; radial noise 0.05 mm. Diameter
    // tolerance 0.06 mm = 5 x its Monte Carlo sigma (test_shape_fit.cpp).
    fpp::PointCloud cloud;
    cloud.xyz = Image<float>(100, 80, 3, kNaN);
    std::mt19937 rng(23);
    std::normal_distribution<double> noise(0, 0.05);
    for (int y = 0; y < 80; ++y)
        for (int x = 0; x < 100; ++x) {
            const double d[3] = {(x - 49.5) / 400, (y - 39.5) / 400, 1};
            // (t dx)^2 + (t dz - 600)^2 = 84^2, nearest root
            const double a = d[0] * d[0] + 1, b = -1200, c = 600.0 * 600 - 84.0 * 84;
            const double disc = b * b - 4 * a * c;
            if (disc < 0)
                continue;
            const double t = (-b - std::sqrt(disc)) / (2 * a);
            const double p[3] = {t * d[0], t * d[1], t * d[2]};
            const double r[2] = {p[0] / 84, (p[2] - 600) / 84}; // unit radial (x, z)
            const double e = noise(rng);
            cloud.xyz.at(x, y, 0) = static_cast<float>(p[0] + e * r[0]);
            cloud.xyz.at(x, y, 1) = static_cast<float>(p[1]);
            cloud.xyz.at(x, y, 2) = static_cast<float>(p[2] + e * r[1]);
        }
    TempDir out;
    fpp::write_ply(out / "pipe.ply", cloud);
    const auto run = run_calib("evaluate " + q(out / "pipe.ply") +
                                   " --fit cylinder --nominal-diameter 168 --out " + q(out / "r"),
                               out.path());
    ASSERT_EQ(run.exit_code, 0) << run.output;
    const auto f = read_figures(out / "r" / "figures.csv");
    EXPECT_NEAR(figure(f, "cloud.cylinder.diameter_error"), 0.0, 0.06);
    EXPECT_NEAR(figure(f, "cloud.cylinder.diameter"), 168.0, 0.06);
    EXPECT_NEAR(figure(f, "cloud.fit.rms"), 0.05, 0.005);
    EXPECT_GT(figure(f, "cloud.cylinder.arc"), 80.0);
    EXPECT_LT(figure(f, "cloud.cylinder.arc"), 130.0);
    EXPECT_NEAR(std::abs(figure(f, "cloud.cylinder.axis_y")), 1.0, 1e-6);
    expect_png(out / "r" / "fit-map.png");
}

TEST_F(CliEvaluate, UnorganisedSphere) {
    std::mt19937 rng(29);
    std::normal_distribution<double> n01, noise(0, 0.01);
    std::vector<std::array<float, 3>> points;
    while (points.size() < 1500) {
        const double d[3] = {n01(rng), n01(rng), n01(rng)};
        const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (d[2] / len > -0.3)
            continue;
        const double r = 12.7 + noise(rng);
        points.push_back({static_cast<float>(r * d[0] / len), static_cast<float>(r * d[1] / len),
                          static_cast<float>(500 + r * d[2] / len)});
    }
    TempDir out;
    write_plain_ply(out / "ball.ply", points);
    const auto run = run_calib("evaluate " + q(out / "ball.ply") +
                                   " --fit sphere --nominal-diameter 25.4 --out " + q(out / "r"),
                               out.path());
    ASSERT_EQ(run.exit_code, 0) << run.output;
    const auto f = read_figures(out / "r" / "figures.csv");
    EXPECT_NEAR(figure(f, "cloud.sphere.size_error"), 0.0, 0.01);
    EXPECT_NEAR(figure(f, "cloud.fit.rms"), 0.01, 0.001);
    EXPECT_GT(figure(f, "cloud.sphere.form"), 5 * 0.01);
    expect_png(out / "r" / "fit-histogram.png");
    EXPECT_FALSE(fs::exists(out / "r" / "fit-map.png")); // no pixel indices
    EXPECT_NE(run.output.find("no camera pixel indices"), std::string::npos) << run.output;
}

// ---------------------------------------------------------------- bad input

void expect_rejected(const ToolRun& run, const fs::path& out,
                     std::initializer_list<std::string> phrases) {
    EXPECT_EQ(run.exit_code, 2) << run.output;
    for (const std::string& p : phrases)
        EXPECT_NE(run.output.find(p), std::string::npos) << "'" << p << "' not in:\n" << run.output;
    EXPECT_FALSE(fs::exists(out)) << "output left behind";
}

TEST_F(CliEvaluate, BadInputsLeaveNoOutput) {
    TempDir out;
    const fs::path r = out / "r";
    const std::string sv = q(*dir_ / "sv.ply");

    expect_rejected(
        run_calib("evaluate " + q(out / "missing.ply") + " --fit plane --out " + q(r), out.path()),
        r, {"missing.ply", "no such file"});
    expect_rejected(run_calib("evaluate " + sv + " --out " + q(r), out.path()), r,
                    {"nothing to evaluate"});
    expect_rejected(
        run_calib("evaluate " + sv + " --fit plane --nominal-length 300 --out " + q(r), out.path()),
        r, {"--nominal-length", "ball-bar"});

    // No pixel indices, but the ground truth needs them.
    write_plain_ply(out / "plain.ply", {{0, 0, 500}, {1, 0, 500}, {0, 1, 500}, {1, 1, 501}});
    expect_rejected(run_calib("evaluate " + q(out / "plain.ply") + " --truth " +
                                  q(*dir_ / "capture") + " --out " + q(r),
                              out.path()),
                    r, {"plain.ply", "pixel indices"});
    expect_rejected(
        run_calib("evaluate " + sv + " --compare " + q(out / "plain.ply") + " --out " + q(r),
                  out.path()),
        r, {"plain.ply", "--match nearest"});

    // Clouds of different organised sizes.
    fpp::PointCloud small;
    small.xyz = Image<float>(40, 30, 3, 500.0f);
    fpp::write_ply(out / "small.ply", small);
    expect_rejected(
        run_calib("evaluate " + sv + " --compare " + q(out / "small.ply") + " --out " + q(r),
                  out.path()),
        r, {"small.ply", "40 x 30", "80 x 60"});
    expect_rejected(run_calib("evaluate " + q(out / "small.ply") + " --truth " +
                                  q(*dir_ / "capture") + " --out " + q(r),
                              out.path()),
                    r, {"small.ply", "40 x 30"});

    // Too few points for the fit; a fit that fails (a plane is no sphere).
    write_plain_ply(out / "three.ply", {{0, 0, 500}, {1, 0, 500}, {0, 1, 500}});
    expect_rejected(
        run_calib("evaluate " + q(out / "three.ply") + " --fit sphere --out " + q(r), out.path()),
        r, {"three.ply", "at least 4"});
    expect_rejected(run_calib("evaluate " + sv + " --fit sphere --out " + q(r), out.path()), r,
                    {"sv.ply", "--fit sphere", "curvature"});
    expect_rejected(run_calib("evaluate " + sv + " --fit cylinder --out " + q(r), out.path()), r,
                    {"sv.ply", "--fit cylinder"});

    // A capture set without ground truth.
    fpp::CaptureManifest m;
    m.camera = {kW, kH};
    m.projector = {64, 48};
    m.frames = {"000.png"};
    m.sequence = {fpp::WhiteBlock{}};
    std::vector<fpp::Frame> frames(1);
    frames[0].u8 = Image<std::uint8_t>(kW, kH, 1, 100);
    fpp::write_capture_set(out / "plain-capture", m, frames);
    expect_rejected(
        run_calib("evaluate " + sv + " --truth " + q(out / "plain-capture") + " --out " + q(r),
                  out.path()),
        r, {"capture.yaml", "truth.xyz"});

    // An output folder that is not a report is left alone.
    fs::create_directory(out / "data");
    std::ofstream(out / "data" / "keep.txt") << "x";
    const auto run =
        run_calib("evaluate " + sv + " --fit plane --out " + q(out / "data"), out.path());
    EXPECT_EQ(run.exit_code, 2) << run.output;
    EXPECT_NE(run.output.find("not an earlier report"), std::string::npos);
    EXPECT_TRUE(fs::exists(out / "data" / "keep.txt"));
    EXPECT_FALSE(fs::exists(out / "data" / "figures.csv"));
}

} // namespace
