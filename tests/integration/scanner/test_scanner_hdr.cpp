// Real surfaces through the scanner on the virtual scanner: HDR exposure
// fusion on a scene with a matte white, a dark rubber-like and a glossy metal
// part; the predicted sigma_z of every point and the board's limit on it; the
// exposure list checked against the camera.
#include <gtest/gtest.h>

#include "fpp/coefficient_table.hpp"
#include "fpp/error.hpp"
#include "fpp/point_cloud.hpp"
#include "fpp/scanner/board_config.hpp"
#include "fpp/scanner/scanner.hpp"
#include "fpp/scanner/sim_board.hpp"
#include "fpp/simulator/renderer.hpp"
#include "rig_truth_table.hpp"
#include "sim_board_yaml.hpp"
#include "test_support.hpp"

#include <cmath>
#include <fstream>
#include <map>

namespace fs = std::filesystem;
using namespace fpp;
using namespace fpp::scanner;

namespace {

// The effects rig's sensor, as a photon transfer measurement would give it.
constexpr const char* kCameraNoise =
    ",\n         noise: {read_noise_dn: 1.0, gain_e_per_dn: 40, sensor_bit_depth: 8}";

void write_text(const fs::path& path, const std::string& text) {
    std::ofstream(path) << text;
}

struct Bench {
    fpp::test::TempDir dir;
    std::vector<std::string> lines;
    Logger log{[this](LogLevel, const std::string& m) { lines.push_back(m); }};
    bool table_written = false;

    // A board on the hdr-parts scene (camera binned 4: 400 x 300) with the
    // rig's truth table, so that errors are the scan's own.
    BoardConfig board(const std::string& name, const std::string& extra,
                      const std::string& camera_extra = kCameraNoise,
                      const std::string& scene = "hdr-parts") {
        fpp::test::SimBoardYaml b;
        b.name = name;
        b.store = dir / ("scans-" + name);
        b.table = "table.fpt";
        b.scene = scene;
        b.binning = 4;
        b.camera_extra = camera_extra;
        b.extra = extra;
        const fs::path file = dir / (name + ".yaml");
        write_text(file, b.text());
        BoardConfig config = read_board_config(file);
        if (!table_written) {
            SimBoard sim(config);
            write_table(dir / "table.fpt", fpp::test::rig_truth_table(sim.rig()));
            table_written = true;
        }
        return config;
    }
};

// Depth error against the truth along each pixel's ray (camera frame, mm),
// nothing removed, and coverage, per scene object; "all" over every object.
struct PartFigures {
    std::size_t visible = 0; // pixels seeing the part where the projector lights it
    std::size_t points = 0;  // of those, pixels with a point
    double sum2 = 0;
    double coverage() const { return visible ? double(points) / double(visible) : 0; }
    double rms() const { return points ? std::sqrt(sum2 / double(points)) : 0; }
};

std::map<std::string, PartFigures> figures_by_part(const PlyPoints& ply,
                                                   const sim::Renderer& renderer) {
    const Image<float>& truth = renderer.truth_xyz();
    const Image<float>& lit = renderer.truth_projector();
    const auto& objects = renderer.truth_object();
    std::vector<float> z(truth.pixel_count(), std::numeric_limits<float>::quiet_NaN());
    for (std::size_t i = 0; i < ply.size(); ++i)
        z[ply.pixel[i]] = ply.z[i];
    std::map<std::string, PartFigures> parts;
    for (std::size_t i = 0; i < truth.pixel_count(); ++i) {
        if (!std::isfinite(truth.data()[3 * i + 2]) || !std::isfinite(lit.data()[2 * i]))
            continue;
        const std::string part = renderer.object_name(objects.data()[i]);
        for (PartFigures* f : {&parts[part], &parts["all"]}) {
            ++f->visible;
            if (!std::isfinite(z[i]))
                continue;
            ++f->points;
            const double e = double(z[i]) - double(truth.data()[3 * i + 2]);
            f->sum2 += e * e;
        }
    }
    return parts;
}

void print_parts(const char* label, const std::map<std::string, PartFigures>& parts) {
    std::printf("%s:", label);
    for (const auto& [name, f] : parts)
        std::printf("  %s coverage %.2f %% (%zu of %zu), RMS %.4f mm;", name.c_str(),
                    100 * f.coverage(), f.points, f.visible, f.rms());
    std::printf("\n");
}

} // namespace

TEST(ScannerHdr, FusedExposuresCoverDarkAndGlossyPartsAsWellAsTheWhiteOne) {
    Bench b;
    // One exposure that puts the white part near 200 of 255 DN, as today.
    // Points whose predicted sigma_z exceeds 0.2 mm (about five times the
    // white part's) are dropped in both: without it, one wrong fringe order
    // on a grazing, ambient-lit pixel of the metal (B 5.5 DN over A 115 DN at
    // the longest exposure, the only pass that decodes it) is 40 px off and
    // alone sets the metal's RMS.
    const std::string limit = "points: {max_sigma_z_mm: 0.2}\n";
    const BoardConfig single = b.board("single", limit);
    // Four passes, each an eighth of the one before: the dark part well
    // exposed, the metal's diffuse part, the white part, the highlight.
    const BoardConfig hdr =
        b.board("hdr", "hdr: {exposures_us: [256000, 32000, 8000, 1000]}\n" + limit);

    std::map<std::string, PartFigures> one, fused;
    ScanOutcome fused_outcome;
    int frames_per_pass = 0;
    {
        SimBoard sim(single);
        Scanner scanner(single, sim.devices(), b.log);
        const ScanOutcome out = scanner.scan(ScanMode::scan);
        one = figures_by_part(read_ply(out.folder / "cloud.ply"), sim.renderer());
    }
    {
        SimBoard sim(hdr);
        Scanner scanner(hdr, sim.devices(), b.log);
        fused_outcome = scanner.scan(ScanMode::scan);
        frames_per_pass = scanner.frames_per_scan();
        fused = figures_by_part(read_ply(fused_outcome.folder / "cloud.ply"), sim.renderer());
    }
    print_parts("single exposure 8000 us", one);
    print_parts("HDR 256000 + 32000 + 8000 + 1000 us", fused);
    ASSERT_TRUE(fused_outcome.fusion.has_value());
    ASSERT_EQ(fused_outcome.exposures_us.size(), 4u);
    EXPECT_EQ(fused_outcome.frames, 4 * frames_per_pass);
    for (const char* part : {"white", "dark", "metal"})
        ASSERT_GT(fused[part].visible, 1000u) << part;
    // The targets: 98 % of the true visible surface, and the dark
    // and glossy parts within 1.5x the white part's error.
    EXPECT_GE(fused["all"].coverage(), 0.98);
    EXPECT_LE(fused["dark"].rms(), 1.5 * fused["white"].rms());
    EXPECT_LE(fused["metal"].rms(), 1.5 * fused["white"].rms());
    // A single exposure loses most of the dark part and the highlight.
    EXPECT_LT(one["all"].coverage(), fused["all"].coverage() - 0.05);
    // Every pass was the best somewhere.
    for (std::size_t k = 0; k < 4; ++k)
        EXPECT_GT(fused_outcome.fusion->reference_pixels[k], 100u) << "pass " << k;
}

TEST(ScannerHdr, AutomaticExposuresComeFromPreviews) {
    Bench b;
    // The longest exposure that clips at most 85 % of the lit pixels (the
    // background, the white and the metal parts: the dark part is what it
    // is for), then a quarter of it, and so on while anything clips.
    const BoardConfig board =
        b.board("auto", "hdr: {auto: {max_saturated: 0.85, passes: 5, ratio: 4}}\n"
                        "points: {max_sigma_z_mm: 0.2}\n");
    SimBoard sim(board);
    Scanner scanner(board, sim.devices(), b.log);
    const ScanOutcome out = scanner.scan(ScanMode::scan);
    auto parts = figures_by_part(read_ply(out.folder / "cloud.ply"), sim.renderer());
    std::printf("automatic exposures:");
    for (double e : out.exposures_us)
        std::printf(" %.0f", e);
    std::printf(" us\n");
    print_parts("HDR, automatic exposures", parts);
    // From 8000 * 4^4 us (above the camera's 1 s: from 1 s) down by 4.
    ASSERT_GE(out.exposures_us.size(), 4u);
    EXPECT_LT(out.exposures_us[0], 1e6);
    EXPECT_GT(out.exposures_us[0], 8000.0 * 4);
    for (std::size_t k = 1; k < out.exposures_us.size(); ++k)
        EXPECT_DOUBLE_EQ(out.exposures_us[k], out.exposures_us[k - 1] / 4);
    EXPECT_TRUE(out.fusion.has_value());
    EXPECT_GE(parts["all"].coverage(), 0.98);
    EXPECT_LE(parts["dark"].rms(), 1.5 * parts["white"].rms());
    EXPECT_LE(parts["metal"].rms(), 1.5 * parts["white"].rms());
}

TEST(ScannerHdr, PointsCarrySigmaZAndTheBoardsLimitDropsTheNoisyOnes) {
    Bench b;
    const BoardConfig free = b.board("free", "", kCameraNoise, "composite");
    const BoardConfig limited =
        b.board("limited", "points: {max_sigma_z_mm: 0.05}\n", kCameraNoise, "composite");
    const BoardConfig unknown = b.board("unknown", "", "", "composite");
    PlyPoints all, kept;
    ScanOutcome out_limited;
    {
        SimBoard sim(free);
        Scanner scanner(free, sim.devices(), b.log);
        all = read_ply(scanner.scan(ScanMode::scan).folder / "cloud.ply");
    }
    {
        SimBoard sim(limited);
        Scanner scanner(limited, sim.devices(), b.log);
        out_limited = scanner.scan(ScanMode::scan);
        kept = read_ply(out_limited.folder / "cloud.ply");
    }
    ASSERT_EQ(all.sigma_z.size(), all.size());
    ASSERT_EQ(kept.sigma_z.size(), kept.size());
    std::size_t above = 0;
    for (float s : all.sigma_z)
        above += s > 0.05f;
    std::printf("sigma_z over 0.05 mm: %zu of %zu points; the limited scan kept %zu\n", above,
                all.size(), kept.size());
    ASSERT_GT(above, 100u); // the limit has something to drop
    EXPECT_EQ(out_limited.dropped_by_sigma, above);
    EXPECT_EQ(kept.size(), all.size() - above);
    for (float s : kept.sigma_z)
        ASSERT_LE(s, 0.05f);
    // Without camera.noise the points carry no sigma_z.
    SimBoard sim(unknown);
    Scanner scanner(unknown, sim.devices(), b.log);
    EXPECT_TRUE(read_ply(scanner.scan(ScanMode::scan).folder / "cloud.ply").sigma_z.empty());
}

TEST(ScannerHdr, AnExposureTheCameraCannotSetIsRefusedAtStartNamingTheRange) {
    Bench b;
    const BoardConfig board = b.board("far", "hdr: {exposures_us: [8000, 5000000]}\n");
    SimBoard sim(board);
    try {
        Scanner scanner(board, sim.devices(), b.log);
        ADD_FAILURE() << "an exposure of 5 s was accepted";
    } catch (const InputError& e) {
        EXPECT_EQ(e.field(), "hdr.exposures_us[1]") << e.what();
        EXPECT_NE(std::string(e.what()).find("range"), std::string::npos) << e.what();
    }
}

TEST(ScannerHdr, BadHdrAndPointsFieldsAreRefusedNamingThem) {
    Bench b;
    auto refused = [&](const std::string& extra, const std::string& camera_extra,
                       const std::string& field) {
        try {
            b.board("bad", extra, camera_extra);
            ADD_FAILURE() << "accepted: " << extra;
        } catch (const InputError& e) {
            EXPECT_EQ(e.field(), field) << e.what();
        }
    };
    refused("hdr: {exposures_us: []}\n", kCameraNoise, "hdr.exposures_us");
    refused("hdr: {exposures_us: [8000, -1]}\n", kCameraNoise, "hdr.exposures_us[1]");
    refused("hdr: {exposures_us: [8000], auto: {max_saturated: 0.01, passes: 2, ratio: 4}}\n",
            kCameraNoise, "hdr");
    refused("hdr: {auto: {max_saturated: 1.5, passes: 2, ratio: 4}}\n", kCameraNoise,
            "hdr.auto.max_saturated");
    refused("hdr: {auto: {max_saturated: 0.01, passes: 2, ratio: 1}}\n", kCameraNoise,
            "hdr.auto.ratio");
    refused("points: {max_sigma_z_mm: 0.05}\n", "", "points.max_sigma_z_mm");
    refused("", ",\n         noise: {read_noise_dn: -1, gain_e_per_dn: 40, sensor_bit_depth: 8}",
            "camera.noise.read_noise_dn");
    refused("", ",\n         noise: {read_noise_dn: 1, gain_e_per_dn: 40, sensor_bit_depth: 20}",
            "camera.noise.sensor_bit_depth");
}
