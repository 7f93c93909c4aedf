// The projector response on the device, end to end on the virtual scanner:
// the scanner captures a ramp of grey levels, its fit becomes the board's
// projector_response, and the scanner's 3- and 4-step patterns rendered
// through its inverse decode as a linear projector's would.
#include <gtest/gtest.h>

#include "fpp/capture_set.hpp"
#include "fpp/decoder.hpp"
#include "fpp/error.hpp"
#include "fpp/projector_response.hpp"
#include "fpp/scanner/board_config.hpp"
#include "fpp/scanner/scanner.hpp"
#include "fpp/scanner/sim_board.hpp"
#include "fpp/simulator/rig.hpp"
#include "sim_board_yaml.hpp"
#include "test_support.hpp"

#include <cmath>
#include <fstream>

namespace fs = std::filesystem;
using namespace fpp;
using namespace fpp::scanner;

namespace {

void write_text(const fs::path& path, const std::string& text) {
    std::ofstream(path) << text;
}

// White, black, an N-step phase block of period 20 along x and its
// complementary Gray code (the `gray-x` sequence with N steps), as board
// file blocks.
std::string sequence_blocks(int steps) {
    return "\n  - {pattern: white}\n  - {pattern: black}\n"
           "  - {pattern: phase, axis: x, period: 20, steps: " +
           std::to_string(steps) +
           "}\n"
           "  - {pattern: gray, axis: x, period: 20, bits: 6, complementary: true}";
}

struct ResponseBoard {
    fpp::test::TempDir dir;
    Logger log{[](LogLevel, const std::string&) {}};

    // A board on `rig` (a rig file) scanning the inclined plane with an
    // N-step sequence, optionally through a measured response.
    BoardConfig board(const fs::path& rig, int steps, const std::string& response = "") {
        fpp::test::SimBoardYaml b;
        b.store = dir / "scans";
        b.rig = rig;
        b.scene = "inclined-plane";
        b.binning = 4;
        b.sequence = sequence_blocks(steps);
        if (!response.empty())
            b.extra = "projector_response: " + response + "\n";
        const fs::path file = dir / ("board-" + std::to_string(steps) + ".yaml");
        write_text(file, b.text());
        return read_board_config(file);
    }
};

// RMS of the decoded projector x against the truth, over pixels decoded in
// both captures given (camera frame pixels, projector pixels).
struct CoordinateError {
    double rms = 0;
    std::size_t n = 0;
};

CoordinateError coordinate_error(const DecodeResult& d, const Image<float>& truth_projector,
                                 const Image<std::uint8_t>& also_valid) {
    CoordinateError e;
    double sum2 = 0;
    for (std::size_t i = 0; i < d.mask.pixel_count(); ++i) {
        const float t = truth_projector.data()[2 * i];
        if (!(d.mask.data()[i] & kDecodeValid) || !(also_valid.data()[i] & kDecodeValid) ||
            !std::isfinite(t))
            continue;
        const double err = double(d.proj_x.data()[i]) - double(t);
        sum2 += err * err;
        ++e.n;
    }
    e.rms = e.n ? std::sqrt(sum2 / double(e.n)) : 0;
    return e;
}

// One capture-mode scan of `board`, decoded.
DecodeResult scan_and_decode(const BoardConfig& board, const Logger& log, Image<float>& truth) {
    SimBoard sim(board);
    Scanner scanner(board, sim.devices(), log);
    const ScanOutcome out = scanner.scan(ScanMode::capture);
    truth = sim.renderer().truth_projector();
    return decode(read_capture_set(out.folder / "capture"));
}

} // namespace

TEST(ScannerResponse, MeasuredResponseMakesThreeAndFourStepsAsGoodAsALinearProjector) {
    ResponseBoard f;
    // The effects rig: gamma 2.2, 0.5 % black level, shot and read noise.
    const fs::path gamma_rig = sim::effects_rig_path();
    sim::Rig linear = sim::load_rig(gamma_rig);
    linear.projector_optics.gamma = 1.0;
    const fs::path linear_rig = f.dir / "linear-rig.yaml";
    write_text(linear_rig, sim::rig_to_yaml(linear));

    // The ramp, captured by the scanner itself, fitted and stored.
    const fs::path response_file = f.dir / "projector-response.yaml";
    {
        const BoardConfig board = f.board(gamma_rig, 8);
        SimBoard sim(board);
        Scanner scanner(board, sim.devices(), f.log);
        const ResponseRamp ramp = scanner.capture_ramp();
        ASSERT_EQ(ramp.frames.size(), ramp.levels.size());
        const ProjectorResponse response = fit_projector_response(ramp);
        // The rig's truth: ((l/255)^2.2 + b - b) / (1 + b - b) once the black level is removed.
        for (const int level : {64, 128, 192})
            EXPECT_NEAR(response.at(level), std::pow(level / 255.0, 2.2), 0.01) << level;
        save_projector_response(response_file, response);
        // The display holds the scan's patterns again: a scan still works.
        EXPECT_NO_THROW(scanner.scan(ScanMode::capture));
    }

    for (const int steps : {3, 4, 8}) {
        Image<float> truth;
        const DecodeResult lin = scan_and_decode(f.board(linear_rig, steps), f.log, truth);
        const DecodeResult raw = scan_and_decode(f.board(gamma_rig, steps), f.log, truth);
        const DecodeResult comp =
            scan_and_decode(f.board(gamma_rig, steps, response_file.string()), f.log, truth);
        const CoordinateError e_lin = coordinate_error(lin, truth, comp.mask);
        const CoordinateError e_raw = coordinate_error(raw, truth, lin.mask);
        const CoordinateError e_comp = coordinate_error(comp, truth, lin.mask);
        std::printf("%d steps: projector x RMS error, linear projector %.4f px (%zu pixels), "
                    "gamma 2.2 as is %.4f px, through the measured response %.4f px "
                    "(%.2fx linear)\n",
                    steps, e_lin.rms, e_lin.n, e_raw.rms, e_comp.rms, e_comp.rms / e_lin.rms);
        ASSERT_GT(e_lin.n, 50000u);
        if (steps < 8) {
            EXPECT_LE(e_comp.rms, 1.3 * e_lin.rms) << steps << " steps";
        }
        // Gamma 2.2 ruins 3 steps (its second and fourth harmonics alias onto
        // the fringe); at 4 steps only the weak third harmonic is left.
        if (steps == 3) {
            EXPECT_GT(e_raw.rms, 3.0 * e_lin.rms) << "gamma left no error?";
        }
        // 8 steps barely see gamma: the compensated patterns are no worse
        // than today's.
        if (steps == 8) {
            EXPECT_LE(e_comp.rms, 1.05 * e_raw.rms);
        }
    }
}

TEST(ScannerResponse, ABadResponseFileIsRefusedAtStartNamingIt) {
    ResponseBoard f;
    const fs::path bad = f.dir / "bad-response.yaml";
    write_text(bad, "format: fpp-projector-response/1\nlevels: [0, 128, 255]\n"
                    "emitted: [0, 0.7, 0.5]\n");
    const BoardConfig board = f.board(sim::effects_rig_path(), 3, bad.string());
    SimBoard sim(board);
    try {
        Scanner scanner(board, sim.devices(), f.log);
        ADD_FAILURE() << "a non-monotonic response was accepted";
    } catch (const InputError& e) {
        EXPECT_EQ(e.file(), bad) << e.what();
    }
}
