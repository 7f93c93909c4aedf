// The paper's experiments on the virtual scanner (see paper_experiments.hpp):
// sessions, calibrations, scans and their measurement. The report and the
// targets are in paper_report.cpp.

#include "fpp/calib/paper_experiments.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/calib/calibration_report.hpp"
#include "fpp/calib/hybrid_calibrate.hpp"
#include "fpp/calib/hybrid_report.hpp"
#include "fpp/calib/plots.hpp"
#include "fpp/calib/report_folder.hpp"
#include "fpp/calib/shape_fit.hpp"
#include "fpp/calib/stereo_session.hpp"
#include "fpp/capture_set.hpp"
#include "fpp/error.hpp"
#include "fpp/parallel.hpp"
#include "fpp/sequences.hpp"
#include "fpp/sim/renderer.hpp"
#include "fpp/sim/scene.hpp"
#include "fpp/sim/session.hpp"
#include "fpp/table_kernel.hpp"
#include "paper_run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace fpp::calib {

namespace {

namespace fs = std::filesystem;
using namespace paper;

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

// Best wall time of `runs` calls (after one warm-up call that allocates).
template <class F> double best_seconds(int runs, F&& f) {
    f();
    double best = std::numeric_limits<double>::infinity();
    for (int r = 0; r < runs; ++r) {
        const auto start = Clock::now();
        f();
        best = std::min(best, seconds_since(start));
    }
    return best;
}

template <class T> Image<T> crop_image(const Image<T>& image, int x0, int y0, Size size) {
    if (image.empty())
        return {};
    Image<T> out(size, image.channels());
    const std::size_t row_values = std::size_t(size.width) * std::size_t(image.channels());
    for (int y = 0; y < size.height; ++y) {
        const T* src = image.row(y0 + y) + std::size_t(x0) * std::size_t(image.channels());
        std::copy(src, src + row_values, out.row(y));
    }
    return out;
}

void check_window(Size camera, int x0, int y0, Size size, const char* what) {
    if (size.width <= 0 || size.height <= 0 || x0 < 0 || y0 < 0 || x0 + size.width > camera.width ||
        y0 + size.height > camera.height)
        throw std::invalid_argument(std::string(what) + ": window outside the camera image");
}

double median(std::vector<double> v) {
    if (v.empty())
        return kNaN;
    const auto mid = v.begin() + std::ptrdiff_t(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return *mid;
}

double image_median(const Image<float>& image) {
    std::vector<double> v;
    v.reserve(image.pixel_count());
    for (std::size_t i = 0; i < image.pixel_count(); ++i)
        if (std::isfinite(image.data()[i]))
            v.push_back(double(image.data()[i]));
    return median(std::move(v));
}

// Keeps the pixels of `mask` (1 = set) whose (2r+1) x (2r+1) neighbourhood is
// all set (separable minimum filter; outside the image counts as unset).
void erode(std::vector<std::uint8_t>& mask, Size size, int r) {
    const int w = size.width, h = size.height;
    std::vector<std::uint8_t> tmp(mask.size());
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            std::uint8_t v = 1;
            for (int k = x - r; k <= x + r && v; ++k)
                v = (k >= 0 && k < w) ? mask[std::size_t(y) * std::size_t(w) + std::size_t(k)] : 0;
            tmp[std::size_t(y) * std::size_t(w) + std::size_t(x)] = v;
        }
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            std::uint8_t v = 1;
            for (int k = y - r; k <= y + r && v; ++k)
                v = (k >= 0 && k < h) ? tmp[std::size_t(k) * std::size_t(w) + std::size_t(x)] : 0;
            mask[std::size_t(y) * std::size_t(w) + std::size_t(x)] = v;
        }
}

bool finite_point(const float* p) {
    return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

// The points of `cloud` at the pixels of `mask` (organised) where it has one.
CloudPoints masked_points(const PointCloud& cloud, const std::vector<std::uint8_t>& mask) {
    CloudPoints out;
    out.organised = cloud.size();
    const float* xyz = cloud.xyz.data();
    for (std::size_t i = 0; i < mask.size(); ++i)
        if (mask[i] && finite_point(xyz + 3 * i)) {
            out.points.push_back(
                {double(xyz[3 * i]), double(xyz[3 * i + 1]), double(xyz[3 * i + 2])});
            out.pixels.push_back(static_cast<std::uint32_t>(i));
        }
    return out;
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
    Run(const fs::path& folder, const PaperExperimentOptions& options)
        : folder_(folder), start_(Clock::now()) {
        record_.options = options;
    }

    PaperExperimentResult run() {
        setup_rig();
        simulate_sessions();
        calibrate_paper_procedure();
        calibrate_our_procedures();
        run_plane();
        run_shape("cylinder", "Experiment 2: cylinder (168 mm diameter, 215 mm long)",
                  FitKind::cylinder, kCylinderDiameter, cylinder_scene(), 12);
        run_shape("sphere", "Sphere (ours): 120 mm diameter", FitKind::sphere, kSphereDiameter,
                  sphere_scene(), 13);
        run_ball_bars();
        run_relief();
        if (!options().keep_sessions) {
            say("removing the calibration sessions (keep them with --keep-sessions)");
            fs::remove_all(folder_ / "sessions");
        }
        return finish();
    }

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

    // ---- setup
    void setup_rig() {
        const fs::path rig_path =
            options().rig.empty() ? sim::lens_defects_rig_path() : options().rig;
        record_.rig = sim::load_rig(rig_path);
        if (options().binning > 1)
            record_.rig = record_.rig.binned_camera(options().binning);
        clean_rig_ = rig();
        clean_rig_.sensor.read_noise_dn = 0;
        clean_rig_.sensor.gain_e_per_dn = 0; // no shot noise
        scan_sequence_ = standard_sequence("gray-x", rig().projector_size);
        decode_options_.threads = options().threads;
        report_ = folder_ / "report";
        fs::create_directories(report_);
        fs::create_directories(folder_ / "scans");
        fs::create_directories(folder_ / "sessions");
        say("rig '" + rig().name + "' (" + rig_path.string() + "), camera " +
            std::to_string(rig().camera_size.width) + " x " +
            std::to_string(rig().camera_size.height) + " (binning " +
            std::to_string(options().binning) + "), projector " +
            std::to_string(rig().projector_size.width) + " x " +
            std::to_string(rig().projector_size.height));
        // The reference: the rig's own model, defects and all.
        exact_calibration_ = calibration_from_rig(rig());
        Method exact;
        exact.key = "exact";
        exact.title = "SV with the rig's exact model (reference)";
        exact.procedure = Procedure::reference;
        exact.calibration = &exact_calibration_;
        exact.sv = make_sv(exact_calibration_);
        methods().push_back(std::move(exact));
    }

    std::unique_ptr<SvReconstructor> make_sv(const StereoCalibration& c) const {
        SvOptions sv;
        sv.threads = options().threads;
        return std::make_unique<SvReconstructor>(c, sv);
    }

    void write_session(const fs::path& folder, const sim::SessionOptions& session,
                       const Sequence& sequence, const std::string& what) {
        say("simulating " + what + ": " + std::to_string(session.poses) + " poses (" +
            std::to_string(frame_count(sequence)) + " frames each)");
        sim::write_session(folder, rig(), sequence, session, [&](int done, int total) {
            say("  pose " + std::to_string(done) + "/" + std::to_string(total));
        });
    }

    void simulate_sessions() {
        const auto start = Clock::now();
        paper_board_session_ = folder_ / "sessions" / "checkerboard";
        plane_session_ = folder_ / "sessions" / "planes";
        board_session_ = folder_ / "sessions" / "boards";
        const Sequence xy = standard_sequence("gray-xy", rig().projector_size);
        if (options().sv_calibration == SvCalibrationSource::checkerboard) {
            sim::SessionOptions board;
            board.kind = sim::SessionKind::checkerboard;
            board.poses = options().checkerboard_poses;
            board.seed = options().seed;
            write_session(paper_board_session_, board, xy,
                          "the paper's checkerboard session (its stereo calibration), gray-xy");
        }
        sim::SessionOptions planes;
        planes.kind = sim::SessionKind::plane;
        planes.poses = options().plane_poses;
        planes.seed = options().seed + 1;
        write_session(plane_session_, planes, scan_sequence_,
                      "the paper's flat-board session, gray-x (vertical fringes only)");
        sim::SessionOptions boards;
        boards.kind = sim::SessionKind::checkerboard;
        boards.poses = options().board_poses;
        boards.seed = options().seed + 2;
        write_session(board_session_, boards, xy,
                      "our checkerboard session (stereo and hybrid calibration), gray-xy");
        record_.seconds_sessions = seconds_since(start);
    }

    // ---- calibrations
    // A stereo calibration of a session; its summary and report.
    StereoCalibration calibrate_stereo(const fs::path& session, const StereoSessionOptions& so,
                                       const std::string& report, StereoSummary& summary) {
        const auto start = Clock::now();
        const SessionResult result = calibrate_session(session, so);
        write_calibration_report(folder_ / report, result);
        const StereoCalibration& c = result.stereo.calibration;
        summary.calibrated = true;
        summary.procedure = to_string(result.stereo.procedure);
        summary.poses = static_cast<int>(result.calibrated.size());
        summary.camera_rms = c.camera_rms;
        summary.projector_rms = c.projector_rms;
        summary.dense_rms = result.stereo.dense_rms;
        summary.camera_grid_max = c.camera_correction.largest_control_value();
        summary.projector_grid_max = c.projector_correction.largest_control_value();
        summary.camera_grid_smoothness = result.stereo.camera_grid_smoothness;
        summary.seconds = seconds_since(start);
        summary.origin = c.origin;
        say("  camera RMS " + fixed_text(c.camera_rms, 4) + " px, projector RMS " +
            fixed_text(c.projector_rms, 4) + " px, " + std::to_string(summary.poses) +
            " poses, " + fixed_text(summary.seconds, 1) + " s");
        return c;
    }

    // Writes a calibration file and returns the hash a table records.
    std::uint64_t save(const StereoCalibration& c, const std::string& name) {
        const std::string text = calibration_to_yaml(c);
        write_file_synced(folder_ / name, text);
        return fnv1a64(text.data(), text.size());
    }

    HybridOptions hybrid_options() const {
        HybridOptions ho;
        ho.threads = options().threads;
        ho.decode.threads = options().threads;
        ho.sv.threads = options().threads;
        ho.progress = indented();
        return ho;
    }

    // One table method per result, read back from its file as the scanner would.
    void add_tables(const std::vector<HybridResult>& results, Procedure procedure,
                    const std::string& prefix, const std::string& title) {
        for (const HybridResult& result : results) {
            Method m;
            m.model = result.table.info().model;
            const std::string model = to_string(m.model);
            m.key = prefix + "-" + model;
            m.title = title + ", " + model;
            m.procedure = procedure;
            const fs::path table_path = folder_ / ("table-" + m.key + ".fpt");
            write_table(table_path, result.table);
            write_hybrid_report(folder_ / ("hybrid-report-" + m.key), result);
            m.table = load_table(table_path, &rig().camera_size, false);
            m.usable_poses = result.usable_poses;
            m.poses = static_cast<int>(result.poses.size());
            m.pixels_modelled = result.pixels_modelled;
            m.fit_rms_z_median = image_median(result.rms_z);
            m.sigma_z_median = image_median(result.sigma_z);
            m.seconds = result.seconds_total;
            add("hybrid." + m.key + ".usable_poses", double(m.usable_poses), "");
            add("hybrid." + m.key + ".pixels_modelled", double(m.pixels_modelled), "");
            add("hybrid." + m.key + ".fit_rms_z_median", m.fit_rms_z_median, "mm");
            add("hybrid." + m.key + ".sigma_z_median", m.sigma_z_median, "mm");
            add("hybrid." + m.key + ".seconds", m.seconds, "s");
            say("  " + m.key + ": " + std::to_string(m.usable_poses) + " of " +
                std::to_string(m.poses) + " poses, " + std::to_string(m.pixels_modelled) +
                " pixels modelled, median Z fit RMS " + fixed_text(m.fit_rms_z_median, 4) +
                " mm");
            methods().push_back(std::move(m));
        }
    }

    // The paper's procedure: a joint stereo calibration (or the rig's
    // 5-coefficient model), then flat boards placed by SV, every model.
    void calibrate_paper_procedure() {
        if (options().sv_calibration == SvCalibrationSource::rig_model) {
            say("the paper's SV model: the rig's own lenses and pose within the 5-coefficient "
                "model (no stereo calibration; the distortion outside that model is left to SV)");
            paper_calibration_ = calibration_from_rig(rig());
            paper_calibration_.camera.drop_unmodelled_terms();
            paper_calibration_.projector.drop_unmodelled_terms();
            paper_calibration_.origin = "rig '" + rig().name + "', 5-coefficient part of its model";
            record_.paper_stereo.origin = paper_calibration_.origin;
        } else {
            say("the paper's stereo calibration (joint, no correction grids)");
            StereoSessionOptions so;
            so.compare_skew = false;
            so.decode.threads = options().threads;
            so.stereo.procedure = StereoProcedure::joint;
            so.stereo.camera_grid = {};
            so.stereo.projector_grid = {};
            so.progress = indented();
            paper_calibration_ =
                calibrate_stereo(paper_board_session_, so, "stereo-report-paper",
                                 record_.paper_stereo);
        }
        const std::uint64_t hash = save(paper_calibration_, "calib-paper.yaml");
        Method sv;
        sv.key = "sv-paper";
        sv.title = "SV, the paper's calibration";
        sv.procedure = Procedure::paper;
        sv.calibration = &paper_calibration_;
        sv.sv = make_sv(paper_calibration_);
        methods().push_back(std::move(sv));
        say("the paper's hybrid tables from the flat boards, every model");
        add_tables(calibrate_hybrid(plane_session_, paper_calibration_, hash, hybrid_options(),
                                    available_table_models()),
                   Procedure::paper, "paper", "paper's procedure");
    }

    // Ours: one checkerboard session gives the stereo calibration (camera
    // first, correction grids) and the tables (boards placed by the
    // camera); the same calibration with the paper's flat boards beside it.
    void calibrate_our_procedures() {
        say("our stereo calibration from the checkerboard session (camera first, correction "
            "grids)");
        StereoSessionOptions so;
        so.compare_skew = false;
        so.decode.threads = options().threads;
        so.progress = indented();
        const auto start = Clock::now();
        our_calibration_ = calibrate_stereo(board_session_, so, "stereo-report", record_.our_stereo);
        const std::uint64_t hash = save(our_calibration_, "calib.yaml");
        Method sv;
        sv.key = "sv";
        sv.title = "SV, our calibration";
        sv.procedure = Procedure::boards;
        sv.calibration = &our_calibration_;
        sv.sv = make_sv(our_calibration_);
        methods().push_back(std::move(sv));

        say("our hybrid tables from the same checkerboard session, every model");
        const auto hybrid_start = Clock::now();
        HybridOptions ho = hybrid_options();
        std::vector<HybridResult> boards =
            calibrate_hybrid(board_session_, our_calibration_, hash, ho, available_table_models());
        record_.seconds_boards_hybrid = seconds_since(hybrid_start);
        add("calibration.boards.seconds_stereo", record_.our_stereo.seconds, "s");
        add("calibration.boards.seconds_hybrid", record_.seconds_boards_hybrid, "s");
        add("calibration.boards.seconds", seconds_since(start), "s");
        const std::size_t first = count();
        add_tables(boards, Procedure::boards, "boards", "our procedure");
        for (std::size_t m = first; m < count(); ++m) {
            methods()[m].is_default = methods()[m].model == HybridOptions{}.model;
            // Cubic models keep to the boards' depth range (no margin beyond
            // it, see HybridOptions::model_depth_margin_mm): fewer depths.
            methods()[m].in_common = methods()[m].model == TableModel::rational;
        }
        // The same session's tables fitted to the boards' samples alone,
        // and to the stereo model's alone, for comparison.
        for (const HybridSamples samples : {HybridSamples::boards, HybridSamples::model}) {
            ho.samples = samples;
            const std::string key = samples == HybridSamples::boards ? "boards-only" : "model-only";
            say("our tables fitted to " + std::string(to_string(samples)) + " samples only");
            add_tables(calibrate_hybrid(board_session_, our_calibration_, hash, ho,
                                        {HybridOptions{}.model}),
                       Procedure::boards, key,
                       samples == HybridSamples::boards ? "our procedure, board samples only"
                                                        : "our procedure, stereo model only");
            // The boards alone reach fewer pixels and depths.
            methods().back().in_common = samples != HybridSamples::boards;
        }
        say("our stereo calibration with the paper's flat boards");
        add_tables(calibrate_hybrid(plane_session_, our_calibration_, hash, hybrid_options(),
                                    {HybridOptions{}.model}),
                   Procedure::planes, "planes", "our calibration, the paper's flat boards");
    }

    // ---- scans
    DecodeResult decode_capture(const sim::SimulatedCapture& capture,
                                const fs::path& folder) const {
        CaptureSet set;
        set.folder = folder;
        set.manifest = capture.manifest;
        set.frames = capture.frames;
        return decode(set, decode_options_);
    }

    Reconstructions reconstruct_all(const DecodeResult& decoded) const {
        Reconstructions r;
        r.clouds.resize(count());
        for (std::size_t m = 0; m < count(); ++m) {
            const Method& method = record_.methods[m];
            if (method.is_table())
                apply_table(method.table, decoded.proj_x, r.clouds[m]);
            else
                method.sv->reconstruct(decoded, ReconstructAxes::x, r.clouds[m]);
        }
        const std::size_t n = decoded.camera.area();
        r.common.assign(n, 1);
        r.points.assign(count(), 0);
        for (std::size_t m = 0; m < count(); ++m) {
            const float* xyz = r.clouds[m].xyz.data();
            for (std::size_t i = 0; i < n; ++i) {
                const bool ok = finite_point(xyz + 3 * i);
                r.points[m] += ok ? 1 : 0;
                if (!ok && record_.methods[m].in_common)
                    r.common[i] = 0;
            }
        }
        erode(r.common, decoded.camera, kEdgeMarginPx);
        r.common_count = std::size_t(std::count(r.common.begin(), r.common.end(), 1));
        return r;
    }

    // Simulates a scan (noisy, saved with truth; then noise-free),
    // reconstructs both with every method and records truth errors, shape
    // fits and figures. Returns the noisy scan's decode and reconstructions.
    struct NoisyScan {
        DecodeResult decoded;
        Reconstructions recon;
    };
    NoisyScan process_scan(ScanSummary& s, const sim::Scene& scene,
                           std::unique_ptr<sim::Renderer> renderer, int seed_index,
                           bool save = true) {
        const fs::path folder = folder_ / "scans" / s.key;
        say("scan '" + s.key + "': rendering with the rig's noise");
        if (!renderer)
            renderer = std::make_unique<sim::Renderer>(rig(), scene, options().threads);
        NoisyScan noisy;
        {
            const sim::SimulatedCapture capture =
                sim::simulate(*renderer, scan_sequence_, scan_seed(seed_index));
            if (save)
                sim::write_simulated_capture(folder, capture);
            noisy.decoded = decode_capture(capture, folder);
            noisy.recon = reconstruct_all(noisy.decoded);
            s.points = noisy.recon.points;
            s.common = noisy.recon.common_count;
            for (std::size_t m = 0; m < count(); ++m) {
                const TruthComparison t = compare_with_truth(
                    masked_points(noisy.recon.clouds[m], noisy.recon.common), capture.truth_xyz);
                s.truth_noisy.push_back(t.dz);
                s.shape_noisy.push_back(t.dz_shape);
                s.compared_noisy = t.compared;
                s.truth_pixels = t.truth_pixels;
            }
        }
        renderer.reset();
        say("scan '" + s.key + "': " + std::to_string(s.common) +
            " pixels with a point from every method");
        fit_shapes(s, noisy.recon, true);

        say("scan '" + s.key + "': rendering noise-free (read noise 0, no shot noise)");
        {
            const sim::Renderer clean(clean_rig_, scene, options().threads);
            const sim::SimulatedCapture capture =
                sim::simulate(clean, scan_sequence_, scan_seed(seed_index));
            const DecodeResult decoded = decode_capture(capture, folder);
            const Reconstructions recon = reconstruct_all(decoded);
            fit_shapes(s, recon, false);
            std::vector<TruthComparison> cmp;
            for (std::size_t m = 0; m < count(); ++m) {
                cmp.push_back(compare_with_truth(masked_points(recon.clouds[m], recon.common),
                                                 capture.truth_xyz));
                s.truth_clean.push_back(cmp.back().dz);
                s.shape_clean.push_back(cmp.back().dz_shape);
                s.distance_clean.push_back(cmp.back().distance);
                s.compared_clean = cmp.back().compared;
            }
            if (save) {
                // Error maps on one colour scale, the paper's SV's.
                const std::size_t reference = record_.find("sv-paper");
                const double limit = symmetric_limit(cmp[reference].dz_values);
                for (std::size_t m = 0; m < count(); ++m)
                    png("truth-" + s.key + "-" + record_.methods[m].key + ".png",
                        signed_map_figure(cmp[m].dz_map, limit,
                                          s.key + " noise-free: Z - Z true, " +
                                              record_.methods[m].title));
            }
        }
        for (std::size_t m = 0; m < count(); ++m) {
            const std::string k = record_.methods[m].key;
            add(s.key + ".points." + k, double(s.points[m]), "");
            add("truth." + s.key + ".noisy." + k + ".rms", s.truth_noisy[m].rms, "mm");
            add("truth." + s.key + ".noisy." + k + ".mean", s.truth_noisy[m].mean, "mm");
            add("truth." + s.key + ".noise_free." + k + ".rms", s.truth_clean[m].rms, "mm");
            add("truth." + s.key + ".noise_free." + k + ".mean", s.truth_clean[m].mean, "mm");
            add("truth." + s.key + ".noise_free." + k + ".std", s.truth_clean[m].stddev, "mm");
            add("truth." + s.key + ".noisy." + k + ".shape_rms", s.shape_noisy[m].rms, "mm");
            add("truth." + s.key + ".noise_free." + k + ".shape_rms", s.shape_clean[m].rms, "mm");
            add("truth." + s.key + ".noise_free." + k + ".distance_rms",
                s.distance_clean[m].rms, "mm");
        }
        add(s.key + ".truth_pixels", double(s.truth_pixels), "");
        add(s.key + ".common_points", double(s.common), "");
        std::string line = "scan '" + s.key + "' Z error vs truth, RMS noisy / noise-free:";
        for (std::size_t m = 0; m < count(); ++m)
            line += " " + record_.methods[m].key + " " + fixed_text(s.truth_noisy[m].rms, 4) +
                    " / " + fixed_text(s.truth_clean[m].rms, 4);
        say(line + " mm");
        return noisy;
    }

    // Shape fit of every method's points (the common pixels); for the noisy
    // scan also histograms and maps.
    void fit_shapes(ScanSummary& s, const Reconstructions& recon, bool noisy) {
        std::vector<double> fit_rms(count(), kNaN), diameter(count(), kNaN),
            diameter_error(count(), kNaN);
        if (s.fit == FitKind::none)
            return;
        std::vector<CloudPoints> points(count());
        std::vector<std::vector<double>> residuals(count());
        for (std::size_t m = 0; m < count(); ++m) {
            points[m] = masked_points(recon.clouds[m], recon.common);
            try {
                if (s.fit == FitKind::plane) {
                    const PlaneFit f = fit_plane(points[m].points);
                    fit_rms[m] = f.fit.rms;
                    residuals[m] = f.fit.residuals;
                } else if (s.fit == FitKind::cylinder) {
                    const CylinderFigures f =
                        cylinder_figures(points[m].points, s.nominal_diameter);
                    fit_rms[m] = f.fit.fit.rms;
                    diameter[m] = f.diameter;
                    diameter_error[m] = f.diameter_error.value_or(kNaN);
                    residuals[m] = f.fit.fit.residuals;
                } else {
                    const ProbingFigures f = probing_figures(points[m].points, s.nominal_diameter);
                    fit_rms[m] = f.fit.fit.rms;
                    diameter[m] = f.diameter;
                    diameter_error[m] = f.size_error.value_or(kNaN);
                    residuals[m] = f.fit.fit.residuals;
                }
            } catch (const FitError& e) {
                s.fit_note += record_.methods[m].title + (noisy ? "" : " (noise-free)") +
                              ": fit failed (" + e.what() + "). ";
            }
        }
        if (!noisy) {
            s.fit_rms_clean = fit_rms;
            s.diameter_clean = diameter;
            for (std::size_t m = 0; m < count(); ++m)
                if (std::isfinite(fit_rms[m])) {
                    add(s.key + ".fit_rms_noise_free." + record_.methods[m].key, fit_rms[m], "mm");
                    if (s.fit != FitKind::plane)
                        add(s.key + ".diameter_noise_free." + record_.methods[m].key,
                            diameter[m], "mm");
                }
            return;
        }
        s.fit_rms = fit_rms;
        s.diameter = diameter;
        s.diameter_error = diameter_error;
        const char* fit_name = s.fit == FitKind::plane      ? "plane"
                               : s.fit == FitKind::cylinder ? "cylinder"
                                                            : "sphere";
        for (std::size_t m = 0; m < count(); ++m) {
            if (!std::isfinite(s.fit_rms[m]))
                continue;
            const std::string& k = record_.methods[m].key;
            add(s.key + ".fit_rms." + k, s.fit_rms[m], "mm");
            if (s.fit != FitKind::plane) {
                add(s.key + ".diameter." + k, s.diameter[m], "mm");
                add(s.key + ".diameter_error." + k, s.diameter_error[m], "mm");
            }
        }
        const std::size_t reference = record_.find("sv-paper");
        if (residuals[reference].empty())
            return;
        const double limit = symmetric_limit(residuals[reference]);
        std::vector<HistogramSeries> series;
        for (std::size_t m = 0; m < count(); ++m)
            if (!residuals[m].empty() && (m == reference || record_.methods[m].is_default))
                series.push_back({record_.methods[m].title, residuals[m]});
        png(s.key + "-fit-histogram.png",
            histogram_figure(series, -limit, limit, std::string(fit_name) + " fit residual (mm)",
                             s.key + ": " + fit_name + "-fit residuals (noisy scan)"));
        for (std::size_t m = 0; m < count(); ++m)
            if (!residuals[m].empty())
                png(s.key + "-fit-map-" + record_.methods[m].key + ".png",
                    signed_map_figure(values_image(points[m], residuals[m]), limit,
                                      s.key + ": " + fit_name + "-fit residual, " +
                                          record_.methods[m].title));
    }

    static sim::Scene plane_scene() {
        sim::Scene scene;
        scene.add(std::make_unique<sim::Plane>(
            sim::Pose::from_euler_deg({0, 0, kPlaneDistance}, kPlaneTiltXDeg, kPlaneTiltYDeg, 0),
            kPlaneWidth, kPlaneHeight, 0.9));
        return scene;
    }
    static sim::Scene cylinder_scene() {
        sim::Scene scene;
        const double r = kCylinderDiameter / 2;
        scene.add(std::make_unique<sim::Cylinder>(Vec3{0, 0, kCylinderFront + r}, Vec3{0, 1, 0}, r,
                                                  kCylinderLength, 0.85));
        return scene;
    }
    static sim::Scene sphere_scene() {
        sim::Scene scene;
        scene.add(
            std::make_unique<sim::Sphere>(Vec3{0, 0, kSphereCentreZ}, kSphereDiameter / 2, 0.9));
        return scene;
    }
    static sim::Scene relief_scene(double scale) {
        std::vector<sim::ReliefBump> bumps = sim::Relief::face_bumps();
        for (sim::ReliefBump& b : bumps) {
            b.x0 *= scale;
            b.y0 *= scale;
            b.amplitude *= scale;
            b.radius_x *= scale;
            b.radius_y *= scale;
        }
        sim::Scene scene;
        scene.add(std::make_unique<sim::Relief>(
            sim::Pose{{0, 0, kReliefBaseZ}, {1, 0, 0, 0, 1, 0, 0, 0, 1}}, kReliefWidth * scale,
            kReliefHeight * scale, std::move(bumps), 0.85));
        return scene;
    }

    void run_shape(const std::string& key, const std::string& title, FitKind fit, double nominal,
                   const sim::Scene& scene, int seed_index) {
        ScanSummary s;
        s.key = key;
        s.title = title;
        s.fit = fit;
        s.nominal_diameter = nominal;
        process_scan(s, scene, nullptr, seed_index);
        record_.scans.push_back(std::move(s));
    }

    void run_plane() {
        ScanSummary s;
        s.key = "plane";
        s.title = "Experiment 1: inclined plane (230 x 175 mm, ~20 deg, 480 mm)";
        s.fit = FitKind::plane;
        const NoisyScan noisy = process_scan(s, plane_scene(), nullptr, 11);
        record_.scans.push_back(std::move(s));
        run_windows(noisy.decoded, noisy.recon);
    }

    // ---- VDI/VDE 2634-2 ball bar at seven places and directions in the
    // volume (its length across the field, in depth and along both
    // diagonals, near and far).
    void run_ball_bars() {
        // Centres of the spheres between about 430 and 530 mm: inside the
        // depths every calibration session reaches (board centres 400 to
        // 560 mm).
        const std::vector<std::pair<Vec3, Vec3>> places = {
            {{0, 0, 480}, {1, 0, 0}},         {{0, 0, 480}, {0.87, 0, 0.5}},
            {{0, 0, 480}, {-0.87, 0, 0.5}},   {{0, 0, 480}, {0.55, 0.66, 0.5}},
            {{0, 0, 480}, {0.7, 0.5, 0.5}},   {{0, 0, 480}, {-0.7, 0.5, 0.5}},
            {{0, 10, 500}, {0.9, 0.44, 0}}};
        for (std::size_t k = 0; k < places.size(); ++k) {
            BallBarPosition b;
            b.centre = places[k].first;
            b.axis = places[k].second;
            sim::Scene scene;
            sim::add_ball_bar(scene, b.centre, b.axis, kBallBarLength, kBallDiameter / 2, 0.85);
            ScanSummary s;
            s.key = "ball-bar-" + std::to_string(k + 1);
            s.title = "ball bar " + std::to_string(k + 1);
            say("ball bar " + std::to_string(k + 1) + " of " + std::to_string(places.size()));
            for (const bool noisy : {true, false}) {
                const sim::Renderer renderer(noisy ? rig() : clean_rig_, scene,
                                             options().threads);
                const sim::SimulatedCapture capture =
                    sim::simulate(renderer, scan_sequence_, scan_seed(20 + int(k)));
                const DecodeResult decoded = decode_capture(capture, folder_);
                const Reconstructions recon = reconstruct_all(decoded);
                std::vector<double>& spacing = noisy ? b.spacing_error : b.spacing_error_clean;
                for (std::size_t m = 0; m < count(); ++m) {
                    // Each method's own points (a table covers what its boards
                    // reached), away from the spheres' silhouettes.
                    std::vector<std::uint8_t> own(decoded.camera.area());
                    for (std::size_t i = 0; i < own.size(); ++i)
                        own[i] = finite_point(recon.clouds[m].xyz.data() + 3 * i) ? 1 : 0;
                    erode(own, decoded.camera, kEdgeMarginPx);
                    const CloudPoints points = masked_points(recon.clouds[m], own);
                    double error = kNaN, size = kNaN;
                    try {
                        const BallBarFigures f =
                            ball_bar_figures(points.points, kBallBarLength, kBallDiameter);
                        // Both spheres must be seen: one sphere split into
                        // two clusters (the other outside the method's
                        // range) is no ball bar.
                        if (f.fit.distance > 0.5 * kBallBarLength) {
                            error = f.spacing_error.value_or(kNaN);
                            size = std::max(std::fabs(f.size_error_first.value_or(kNaN)),
                                            std::fabs(f.size_error_second.value_or(kNaN)));
                        }
                    } catch (const FitError&) {
                        // NaN: no fit (too few points)
                    }
                    spacing.push_back(error);
                    if (noisy)
                        b.size_error.push_back(size);
                }
            }
            for (std::size_t m = 0; m < count(); ++m) {
                const std::string base =
                    "ball_bar." + std::to_string(k + 1) + "." + record_.methods[m].key;
                add(base + ".spacing_error", b.spacing_error[m], "mm");
                add(base + ".spacing_error_noise_free", b.spacing_error_clean[m], "mm");
                add(base + ".size_error", b.size_error[m], "mm");
            }
            record_.ball_bars.push_back(std::move(b));
        }
    }

    // ---- Experiment 3
    void run_relief() {
        const double target = kReliefPixelsFullSize / double(options().binning * options().binning);
        say("relief: sizing it so that about " + std::to_string(static_cast<long>(target)) +
            " camera pixels see it");
        double scale = 1;
        std::unique_ptr<sim::Renderer> renderer;
        std::size_t seen = 0;
        for (int round = 0; round < 3; ++round) {
            renderer = std::make_unique<sim::Renderer>(rig(), relief_scene(scale),
                                                       options().threads);
            const Image<float>& proj = renderer->truth_projector();
            seen = 0;
            for (std::size_t i = 0; i < proj.pixel_count(); ++i)
                seen += std::isfinite(proj.data()[2 * i]) ? 1 : 0;
            say("  scale " + fixed_text(scale, 4) + ": " + std::to_string(seen) +
                " lit pixels see it");
            if (seen == 0)
                throw std::runtime_error("relief: no camera pixel sees the relief");
            if (round == 2)
                break;
            scale = std::clamp(scale * std::sqrt(target / double(seen)), 0.3, 1.5);
        }
        ReliefSummary& relief = record_.relief;
        relief.scale = scale;
        relief.pixels_seen = seen;
        add("relief.scale", scale, "");
        add("relief.pixels_seen", double(seen), "");

        ScanSummary s;
        s.key = "relief";
        s.title = "Experiment 3: freeform relief (face)";
        s.fit = FitKind::none;
        const NoisyScan noisy = process_scan(s, relief_scene(scale), std::move(renderer), 14);
        record_.scans.push_back(std::move(s));

        // The paper's comparison: its SV against its hybrid tables, per pixel.
        const std::size_t sv = record_.find("sv-paper");
        const CloudPoints sv_points = cloud_points(noisy.recon.clouds[sv]);
        std::vector<std::vector<double>> differences;
        for (std::size_t m = 0; m < count(); ++m) {
            const Method& method = record_.methods[m];
            if (method.procedure != Procedure::paper || !method.is_table())
                continue;
            const CloudDistance d = compare_per_pixel(sv_points, cloud_points(noisy.recon.clouds[m]));
            relief.compared_methods.push_back(m);
            relief.distance_rms.push_back(d.distance.rms);
            relief.dz_rms.push_back(d.dz.rms);
            relief.matched.push_back(d.matched);
            add("relief.difference." + method.key + ".distance_rms", d.distance.rms, "mm");
            add("relief.difference." + method.key + ".dz_rms", d.dz.rms, "mm");
            png("relief-difference-" + method.key + ".png",
                signed_map_figure(d.dz_map, symmetric_limit(d.values),
                                  "relief: Z(SV) - Z(" + method.title + ")"));
            differences.push_back(d.values);
        }
        if (!differences.empty()) {
            std::vector<HistogramSeries> series;
            for (std::size_t k = 0; k < differences.size(); ++k)
                series.push_back({"SV - " + record_.methods[relief.compared_methods[k]].key,
                                  differences[k]});
            const double limit = symmetric_limit(differences[0]);
            png("relief-difference-histogram.png",
                histogram_figure(series, -limit, limit, "Z(SV) - Z(hybrid) per pixel (mm)",
                                 "relief: the paper's SV vs its hybrid tables"));
        }
        time_relief(noisy.decoded);
    }

    void time_relief(const DecodeResult& decoded) {
        const int runs = options().timing_runs;
        ReliefSummary& relief = record_.relief;
        say("relief: timing the reconstructions, one thread each, best of " + std::to_string(runs));
        relief.seconds.assign(count(), kNaN);
        PointCloud cloud;
        SvOptions one;
        one.threads = 1;
        ThreadPool single(1);
        for (std::size_t m = 0; m < count(); ++m) {
            const Method& method = record_.methods[m];
            if (method.procedure == Procedure::reference)
                continue;
            if (method.is_table()) {
                relief.seconds[m] = best_seconds(
                    runs, [&] { apply_table(method.table, decoded.proj_x, cloud, &single); });
            } else {
                const SvReconstructor sv(*method.calibration, one);
                relief.seconds[m] =
                    best_seconds(runs, [&] { sv.reconstruct(decoded, ReconstructAxes::x, cloud); });
            }
            add("relief.time." + method.key, relief.seconds[m], "s");
        }
        SvOptions iteration = one;
        iteration.solver = XOnlySolver::plane_iteration;
        const SvReconstructor sv(paper_calibration_, iteration);
        relief.seconds_sv_plane_iteration =
            best_seconds(runs, [&] { sv.reconstruct(decoded, ReconstructAxes::x, cloud); });
        add("relief.time.sv_plane_iteration", relief.seconds_sv_plane_iteration, "s");
    }

    // ---- Experiment 4: the paper's SV and our tables on N x N windows.
    void run_windows(const DecodeResult& decoded, const Reconstructions& full) {
        WindowSummary& windows = record_.windows;
        windows.methods.push_back(record_.find("sv-paper"));
        for (std::size_t m = 0; m < count(); ++m)
            if (record_.methods[m].procedure == Procedure::boards &&
                record_.methods[m].is_table() && record_.methods[m].key.starts_with("boards-"))
                windows.methods.push_back(m);
        const Size camera = decoded.camera;
        double cx = 0, cy = 0;
        std::size_t n = 0;
        for (int y = 0; y < camera.height; ++y)
            for (int x = 0; x < camera.width; ++x)
                if (full.common[std::size_t(y) * std::size_t(camera.width) + std::size_t(x)]) {
                    cx += x;
                    cy += y;
                    ++n;
                }
        if (n == 0)
            throw std::runtime_error("windows: the plane scan has no points");
        cx /= double(n);
        cy /= double(n);
        const int largest = std::min(camera.width, camera.height);
        for (int k = 1; k <= kWindowSizes; ++k) {
            const int size = std::min(
                largest, std::max(8, static_cast<int>(std::lround(double(kWindowStepFullSize * k) /
                                                                  double(options().binning)))));
            if (windows.sizes.empty() || size > windows.sizes.back())
                windows.sizes.push_back(size);
        }
        const int runs = options().timing_runs;
        say("windows: timing " + std::to_string(windows.sizes.size()) +
            " square windows of the plane scan, one thread each, best of " + std::to_string(runs));
        windows.seconds.assign(windows.methods.size(), {});
        ThreadPool single(1);
        SvOptions one;
        one.threads = 1;
        for (int size : windows.sizes) {
            const int x0 =
                std::clamp(static_cast<int>(std::lround(cx - size / 2.0)), 0, camera.width - size);
            const int y0 =
                std::clamp(static_cast<int>(std::lround(cy - size / 2.0)), 0, camera.height - size);
            const Size window{size, size};
            const DecodeResult cropped = crop_decode(decoded, x0, y0, window);
            std::size_t points = 0;
            for (std::size_t w = 0; w < windows.methods.size(); ++w) {
                const std::size_t m = windows.methods[w];
                const Method& method = record_.methods[m];
                PointCloud cloud;
                if (method.is_table()) {
                    const CoefficientTable table = crop_table(method.table, x0, y0, window);
                    windows.seconds[w].push_back(best_seconds(
                        runs, [&] { apply_table(table, cropped.proj_x, cloud, &single); }));
                } else {
                    const SvReconstructor sv(
                        crop_calibration(*method.calibration, x0, y0, window), one);
                    windows.seconds[w].push_back(best_seconds(
                        runs, [&] { sv.reconstruct(cropped, ReconstructAxes::x, cloud); }));
                }
                // The window's reconstruction must be the full image's, pixel for pixel.
                for (int y = 0; y < size; ++y)
                    for (int x = 0; x < size; ++x) {
                        const float* a = &cloud.xyz.at(x, y, 0);
                        const float* b = &full.clouds[m].xyz.at(x0 + x, y0 + y, 0);
                        const bool fa = finite_point(a), fb = finite_point(b);
                        if (w == 0 && fa)
                            ++points;
                        if (fa != fb) {
                            ++windows.crop_mismatched;
                            continue;
                        }
                        if (fa)
                            for (int c = 0; c < 3; ++c)
                                windows.crop_max_difference_mm =
                                    std::max(windows.crop_max_difference_mm,
                                             std::abs(double(a[c]) - double(b[c])));
                    }
            }
            windows.points.push_back(points);
        }
        for (std::size_t k = 0; k < windows.sizes.size(); ++k)
            for (std::size_t w = 0; w < windows.methods.size(); ++w)
                add("windows.n" + std::to_string(windows.sizes[k]) + ".time." +
                        record_.methods[windows.methods[w]].key,
                    windows.seconds[w][k], "s");
        add("windows.crop_max_difference", windows.crop_max_difference_mm, "mm");
        add("windows.crop_mismatched", double(windows.crop_mismatched), "");
        std::vector<PlotSeries> series;
        for (std::size_t w = 0; w < windows.methods.size(); ++w)
            series.push_back({record_.methods[windows.methods[w]].title, windows.seconds[w],
                              series_colour(w)});
        png("windows-timing.png",
            timing_plot(windows.sizes, series,
                        "Experiment 4: reconstruction time of N x N windows (one thread)"));
    }

    // ---- report
    PaperExperimentResult finish() {
        const std::vector<PaperTarget> targets = evaluate_targets(record_);
        for (const PaperTarget& t : targets)
            add("target." + t.key, t.met ? 1.0 : 0.0, "");
        PaperExperimentResult result;
        for (const Method& m : record_.methods)
            result.methods.push_back(m.key);
        result.default_method = record_.methods[record_.default_method()].key;
        result.seconds = seconds_since(start_);
        add("run.binning", double(options().binning), "");
        add("run.camera_width", double(rig().camera_size.width), "px");
        add("run.camera_height", double(rig().camera_size.height), "px");
        add("run.checkerboard_poses", double(options().checkerboard_poses), "");
        add("run.plane_poses", double(options().plane_poses), "");
        add("run.board_poses", double(options().board_poses), "");
        add("run.seconds_sessions", record_.seconds_sessions, "s");
        add("run.seconds", result.seconds, "s");
        for (const auto& [key, s] : {std::pair{"paper", &record_.paper_stereo},
                                     std::pair{"boards", &record_.our_stereo}}) {
            if (!s->calibrated)
                continue;
            add(std::string("calibration.") + key + ".camera_rms", s->camera_rms, "px");
            add(std::string("calibration.") + key + ".projector_rms", s->projector_rms, "px");
            add(std::string("calibration.") + key + ".poses_used", double(s->poses), "");
        }
        result.summary_markdown = summary_markdown(record_, targets);
        write_file_synced(report_ / "summary.md", result.summary_markdown);
        write_file_synced(report_ / "figures.csv", figures_csv(figures_));
        result.figures = figures_;
        result.targets = targets;
        return result;
    }

    fs::path folder_;
    Clock::time_point start_;
    Record record_;
    fs::path report_;
    sim::Rig clean_rig_;
    Sequence scan_sequence_;
    DecodeOptions decode_options_;
    fs::path paper_board_session_, plane_session_, board_session_;
    StereoCalibration exact_calibration_, paper_calibration_, our_calibration_;
    std::vector<Figure> figures_;
};

} // namespace

const char* to_string(SvCalibrationSource source) {
    return source == SvCalibrationSource::rig_model ? "rig-model" : "checkerboard";
}

SvCalibrationSource parse_sv_calibration_source(const std::string& name) {
    if (name == "checkerboard")
        return SvCalibrationSource::checkerboard;
    if (name == "rig-model")
        return SvCalibrationSource::rig_model;
    throw std::invalid_argument("unknown SV calibration source '" + name +
                                "' (checkerboard, rig-model)");
}

void PaperExperimentOptions::validate() const {
    if (binning < 1 || binning > 8)
        throw std::invalid_argument("binning: must be 1 to 8");
    if (checkerboard_poses < 3 || checkerboard_poses > 200)
        throw std::invalid_argument("checkerboard_poses: must be 3 to 200");
    if (plane_poses < 6 || plane_poses > 500)
        throw std::invalid_argument("plane_poses: must be 6 to 500 (a cubic per pixel needs "
                                    "at least 6 poses seeing it)");
    if (board_poses < 6 || board_poses > 500)
        throw std::invalid_argument("board_poses: must be 6 to 500");
    if (timing_runs < 1 || timing_runs > 100)
        throw std::invalid_argument("timing_runs: must be 1 to 100");
    if (threads < 0)
        throw std::invalid_argument("threads: must be >= 0");
}

std::vector<TableModel> available_table_models() {
    // The paper's polynomial first.
    return {TableModel::polynomial, TableModel::ray, TableModel::rational};
}

StereoCalibration crop_calibration(const StereoCalibration& calibration, int x0, int y0,
                                   Size size) {
    check_window(calibration.camera_size, x0, y0, size, "crop_calibration");
    if (!calibration.camera_correction.empty())
        throw std::invalid_argument("crop_calibration: a camera with a correction grid");
    StereoCalibration out = calibration;
    out.camera_size = size;
    // u = fu xd + skew yd + cu: the window's pixel u - x0 has principal point cu - x0.
    out.camera.cu -= double(x0);
    out.camera.cv -= double(y0);
    out.origin = calibration.origin + " (camera window " + std::to_string(size.width) + " x " +
                 std::to_string(size.height) + " at " + std::to_string(x0) + ", " +
                 std::to_string(y0) + ")";
    return out;
}

CoefficientTable crop_table(const CoefficientTable& table, int x0, int y0, Size size) {
    check_window(table.info().camera, x0, y0, size, "crop_table");
    TableInfo info = table.info();
    info.camera = size;
    CoefficientTable out(info);
    const int planes = table.planes();
    for (int y = 0; y < size.height; ++y)
        for (int x = 0; x < size.width; ++x)
            for (int p = 0; p < planes; ++p)
                out.set(p, x, y, table.get(p, x0 + x, y0 + y));
    return out;
}

DecodeResult crop_decode(const DecodeResult& decoded, int x0, int y0, Size size) {
    check_window(decoded.camera, x0, y0, size, "crop_decode");
    DecodeResult out;
    out.camera = size;
    out.proj_x = crop_image(decoded.proj_x, x0, y0, size);
    out.proj_y = crop_image(decoded.proj_y, x0, y0, size);
    out.modulation = crop_image(decoded.modulation, x0, y0, size);
    out.mean = crop_image(decoded.mean, x0, y0, size);
    out.mask = crop_image(decoded.mask, x0, y0, size);
    out.method_x = decoded.method_x;
    out.method_y = decoded.method_y;
    return out;
}

PaperExperimentResult run_paper_experiments(const fs::path& out_argument,
                                            const PaperExperimentOptions& options) {
    fs::path out = out_argument.lexically_normal();
    if (out.has_parent_path() && !out.has_filename())
        out = out.parent_path(); // "dir/" names "dir"
    if (out.empty())
        throw InputError(out_argument, "", "no output folder given");
    std::error_code ec;
    if (fs::exists(fs::symlink_status(out, ec)))
        throw InputError(out, "", "already exists; the experiments are written into a new folder");
    const fs::path parent = out.has_parent_path() ? out.parent_path() : fs::path(".");
    if (!fs::is_directory(parent, ec))
        throw InputError(out, "", "its parent folder " + parent.string() + " does not exist");
    options.validate();

    PaperExperimentResult result;
    write_folder_atomically(out, [&](const fs::path& temp) {
        Run run(temp, options);
        result = run.run();
    });
    if (options.progress)
        options.progress("wrote " + out.string());
    return result;
}

} // namespace fpp::calib
