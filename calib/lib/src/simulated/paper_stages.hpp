#pragma once
// Internal to fpp-calib paper-experiments (paper_experiments.hpp): the run
// itself, one object whose stages are defined in three files:
// paper_experiments.cpp (the order, sessions, calibrations, figures file),
// paper_scans.cpp (the scans against the truth, ball bars, relief) and
// paper_timing.cpp (the relief's timings and Experiment 4's windows).

#include "fpp/calib/hybrid_calibrate.hpp"
#include "fpp/calib/report_folder.hpp"
#include "fpp/calib/stereo_session.hpp"
#include "fpp/pattern_block.hpp"
#include "fpp/point_cloud.hpp"
#include "fpp/simulator/renderer.hpp"
#include "fpp/simulator/scene.hpp"
#include "fpp/simulator/session.hpp"
#include "paper_run.hpp"

#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace fpp::calib::paper {

using Clock = std::chrono::steady_clock;

inline double seconds_since(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

inline bool finite_point(const float* p) {
    return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

// Reconstructions of one decoded scan, one per method.
struct Reconstructions {
    std::vector<PointCloud> clouds;
    std::vector<std::size_t> points;
    std::vector<std::uint8_t> common; // 1 where every cloud has a point
    std::size_t common_count = 0;
};

class Run {
public:
    Run(const std::filesystem::path& folder, const PaperExperimentOptions& options);

    PaperExperimentResult run();

private:
    // ---- small utilities
    const PaperExperimentOptions& options() const { return record_.options; }
    std::vector<Method>& methods() { return record_.methods; }
    std::size_t count() const { return record_.methods.size(); }
    void say(const std::string& line) const {
        if (options().progress)
            options().progress(line);
    }
    std::function<void(const std::string&)> indented() const {
        return [this](const std::string& line) { say("  " + line); };
    }
    void add(const std::string& name, double value, const std::string& unit) {
        figures_.push_back({name, value, unit});
    }
    void png(const std::string& name, const cv::Mat& image) { save_png(report_ / name, image); }
    std::uint64_t scan_seed(int k) const { return options().seed * 1000 + std::uint64_t(k); }
    const sim::Rig& rig() const { return record_.rig; }

    // ---- setup (paper_experiments.cpp)
    void setup_rig();
    // An SV method reconstructing with `calibration` (which the run keeps).
    void add_sv_method(std::string key, std::string title, Procedure procedure,
                       const StereoCalibration& calibration);
    // How far `calibration`'s camera frame turned from the rig's; added as
    // figure `figure` in mrad.
    FrameTurn frame_turn(const StereoCalibration& calibration, const std::string& figure);
    void write_session(const std::filesystem::path& folder, const sim::SessionOptions& session,
                       const Sequence& sequence, const std::string& what);
    void simulate_sessions();

    // ---- calibrations (paper_experiments.cpp)
    // A stereo calibration of a session; its summary and report.
    StereoCalibration calibrate_stereo(const std::filesystem::path& session,
                                       const StereoSessionOptions& so, const std::string& report,
                                       StereoSummary& summary);
    // Writes a calibration file and returns the hash a table records.
    std::uint64_t save(const StereoCalibration& c, const std::string& name);
    HybridOptions hybrid_options() const;
    // One table method per result, read back from its file as the scanner would.
    void add_tables(const std::vector<HybridResult>& results, Procedure procedure,
                    const std::string& prefix, const std::string& title);
    // The paper's procedure: a joint stereo calibration (or the rig's
    // 5-coefficient model), then flat boards placed by SV, every model.
    void calibrate_paper_procedure();
    // Ours: one checkerboard session gives the stereo calibration (camera
    // first, correction grids) and the tables (boards placed by the
    // camera); the same calibration with the paper's flat boards beside it.
    void calibrate_our_procedures();

    // ---- scans (paper_scans.cpp)
    DecodeResult decode_capture(const sim::SimulatedCapture& capture,
                                const std::filesystem::path& folder) const;
    Reconstructions reconstruct_all(const DecodeResult& decoded) const;
    // Simulates a scan (noisy, saved with truth; then noise-free),
    // reconstructs both with every method and records truth errors, shape
    // fits and figures. Returns the noisy scan's decode and reconstructions.
    struct NoisyScan {
        DecodeResult decoded;
        Reconstructions recon;
    };
    NoisyScan process_scan(ScanSummary& s, const sim::Scene& scene,
                           std::unique_ptr<sim::Renderer> renderer, int seed_index,
                           bool save = true);
    // Shape fit of every method's points (the common pixels); for the noisy
    // scan also histograms and maps.
    void fit_shapes(ScanSummary& s, const Reconstructions& recon, bool noisy);
    static sim::Scene plane_scene();
    static sim::Scene cylinder_scene();
    static sim::Scene sphere_scene();
    static sim::Scene relief_scene(double scale);
    void run_shape(const std::string& key, const std::string& title, FitKind fit, double nominal,
                   const sim::Scene& scene, int seed_index);
    void run_plane();
    // ---- VDI/VDE 2634-2 ball bar at seven places and directions in the
    // volume (its length across the field, in depth and along both
    // diagonals, near and far).
    void run_ball_bars();
    // ---- Experiment 3
    void run_relief();

    // ---- timings (paper_timing.cpp)
    void time_relief(const DecodeResult& decoded);
    // ---- Experiment 4: the paper's SV and our tables on N x N windows.
    void run_windows(const DecodeResult& decoded, const Reconstructions& full);

    // ---- report (paper_experiments.cpp)
    PaperExperimentResult finish();

    std::filesystem::path folder_;
    Clock::time_point start_;
    Record record_;
    std::filesystem::path report_;
    sim::Rig clean_rig_;
    Sequence scan_sequence_;
    DecodeOptions decode_options_;
    std::filesystem::path paper_board_session_, plane_session_, board_session_;
    StereoCalibration exact_calibration_, paper_calibration_, our_calibration_;
    std::vector<Figure> figures_;
};

} // namespace fpp::calib::paper
