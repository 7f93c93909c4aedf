// The paper's experiments on the virtual scanner (see paper_experiments.hpp).

#include "fpp/calib/paper_experiments.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/calib/calibration_report.hpp"
#include "fpp/calib/hybrid_calibrate.hpp"
#include "fpp/calib/hybrid_report.hpp"
#include "fpp/calib/plots.hpp"
#include "fpp/calib/report_folder.hpp"
#include "fpp/calib/shape_fit.hpp"
#include "fpp/calib/stereo_session.hpp"
#include "fpp/calib/sv_reconstruct.hpp"
#include "fpp/capture_set.hpp"
#include "fpp/error.hpp"
#include "fpp/parallel.hpp"
#include "fpp/sequences.hpp"
#include "fpp/sim/renderer.hpp"
#include "fpp/sim/rig.hpp"
#include "fpp/sim/scene.hpp"
#include "fpp/sim/session.hpp"
#include "fpp/table_kernel.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace fpp::calib {

namespace {

namespace fs = std::filesystem;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The paper's figures (Vargas et al., experiments 1 to 3).
constexpr double kPaperPlaneSv = 0.118, kPaperPlaneHybrid = 0.044;       // mm, plane-fit RMS
constexpr double kPaperCylinderSv = 0.076, kPaperCylinderHybrid = 0.059; // mm, cylinder-fit RMS
constexpr double kPaperReliefDistance = 0.075;                           // mm, SV vs hybrid
constexpr double kPaperReliefSvSeconds = 1.04, kPaperReliefHybridSeconds = 0.14;
constexpr double kPaperReliefPoints = 683047;

// Scenes (camera frame, mm).
constexpr double kPlaneWidth = 230, kPlaneHeight = 175, kPlaneDistance = 480;
constexpr double kPlaneTiltXDeg = 4, kPlaneTiltYDeg = -20; // ~20 deg to the optical axis
constexpr double kCylinderDiameter = 168, kCylinderLength = 215, kCylinderFront = 500;
constexpr double kSphereDiameter = 120, kSphereCentreZ = 520;
constexpr double kReliefPixelsFullSize = 680000; // camera pixels seeing the relief at 1600 x 1200
constexpr double kReliefBaseZ = 530;             // its base; heights rise towards the camera
constexpr double kReliefWidth = 160, kReliefHeight = 220; // Relief::face_bumps() at scale 1
constexpr int kWindowSizes = 8;
constexpr int kWindowStepFullSize = 100; // N = 100, 200, ..., 800 at full size

// Pixels this close to the edge of the reconstructed region are left out of
// fits and truth comparisons: at a silhouette a pixel's phase is blurred with
// its neighbours' (defocus) and its point is off the surface.
constexpr int kEdgeMarginPx = 2;

// Targets of the run.
constexpr double kPlaneRatioTarget = 0.5; // hybrid truth error <= half of SV's on the plane
constexpr double kSpeedupTarget = 50;     // hybrid at least this much faster on the relief

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

std::string seconds_text(double s) {
    if (!std::isfinite(s))
        return "-";
    if (s >= 1)
        return fixed_text(s, 3) + " s";
    if (s >= 1e-3)
        return fixed_text(s * 1e3, 2) + " ms";
    return fixed_text(s * 1e6, 1) + " us";
}

double median(std::vector<double> v) {
    if (v.empty())
        return kNaN;
    const auto mid = v.begin() + std::ptrdiff_t(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return *mid;
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

// One Markdown table row.
void table_row(std::ostream& md, const std::vector<std::string>& cells) {
    md << "|";
    for (const std::string& c : cells)
        md << " " << c << " |";
    md << "\n";
}

// ------------------------------------------------------------------ plots

struct PlotSeries {
    std::string label;
    std::vector<double> seconds; // one per window size; non-positive: no point
    cv::Scalar colour;
};

// "1 s", "100 ms", "10 us" for 10^e seconds.
std::string decade_label(int e) {
    int unit_exp = 0;
    const char* unit = "s";
    if (e < -6) {
        unit_exp = -9;
        unit = "ns";
    } else if (e < -3) {
        unit_exp = -6;
        unit = "us";
    } else if (e < 0) {
        unit_exp = -3;
        unit = "ms";
    }
    int mantissa = 1;
    for (int k = unit_exp; k < e; ++k)
        mantissa *= 10;
    return std::to_string(mantissa) + " " + unit;
}

// Reconstruction time against window size, log time axis (the models differ
// by orders of magnitude), one line and marker per series, with a legend.
cv::Mat timing_plot(const std::vector<int>& sizes, const std::vector<PlotSeries>& series,
                    const std::string& title) {
    const int width = 960, height = 620;
    const int left = 100, right = 30, top = 60, bottom = 80;
    cv::Mat image(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
    double lo = std::numeric_limits<double>::infinity(), hi = 0;
    for (const PlotSeries& s : series)
        for (double t : s.seconds)
            if (t > 0 && std::isfinite(t)) {
                lo = std::min(lo, t);
                hi = std::max(hi, t);
            }
    if (!(hi > 0) || sizes.empty())
        return image;
    const int e_lo = static_cast<int>(std::floor(std::log10(lo)));
    const int e_hi = std::max(e_lo + 1, static_cast<int>(std::ceil(std::log10(hi))));
    const double n_max = double(sizes.back()) * 1.05;
    const auto px = [&](double n) {
        return left + static_cast<int>(std::lround(n / n_max * double(width - left - right)));
    };
    const auto py = [&](double t) {
        const double f = (std::log10(t) - double(e_lo)) / double(e_hi - e_lo);
        return height - bottom - static_cast<int>(std::lround(f * double(height - top - bottom)));
    };
    const cv::Scalar axis(0, 0, 0), grid(220, 220, 220), text(40, 40, 40);
    const int font = cv::FONT_HERSHEY_SIMPLEX;
    for (int e = e_lo; e <= e_hi; ++e) {
        const int y = py(std::pow(10.0, double(e)));
        cv::line(image, {left, y}, {width - right, y}, grid, 1);
        cv::putText(image, decade_label(e), {8, y + 5}, font, 0.5, text, 1, cv::LINE_AA);
    }
    for (int n : sizes) {
        const int x = px(double(n));
        cv::line(image, {x, top}, {x, height - bottom}, grid, 1);
        const std::string label = std::to_string(n);
        cv::putText(image, label, {x - 4 * static_cast<int>(label.size()), height - bottom + 22},
                    font, 0.5, text, 1, cv::LINE_AA);
    }
    cv::line(image, {left, top}, {left, height - bottom}, axis, 1);
    cv::line(image, {left, height - bottom}, {width - right, height - bottom}, axis, 1);
    cv::putText(image, "window size N (N x N camera pixels)", {left + 220, height - 25}, font, 0.6,
                text, 1, cv::LINE_AA);
    cv::putText(image, title, {left, 35}, font, 0.65, text, 1, cv::LINE_AA);
    int legend_y = top + 20;
    for (const PlotSeries& s : series) {
        cv::Point previous{-1, -1};
        for (std::size_t i = 0; i < sizes.size() && i < s.seconds.size(); ++i) {
            if (!(s.seconds[i] > 0) || !std::isfinite(s.seconds[i]))
                continue;
            const cv::Point p{px(double(sizes[i])), py(s.seconds[i])};
            if (previous.x >= 0)
                cv::line(image, previous, p, s.colour, 2, cv::LINE_AA);
            cv::circle(image, p, 4, s.colour, cv::FILLED, cv::LINE_AA);
            previous = p;
        }
        cv::line(image, {left + 20, legend_y - 5}, {left + 60, legend_y - 5}, s.colour, 2,
                 cv::LINE_AA);
        cv::putText(image, s.label, {left + 70, legend_y}, font, 0.55, text, 1, cv::LINE_AA);
        legend_y += 24;
    }
    return image;
}

const cv::Scalar kSeriesColours[] = {
    {40, 40, 200},  // SV: red (BGR)
    {180, 90, 30},  // blue
    {60, 150, 40},  // green
    {150, 60, 140}, // purple
    {20, 140, 220}, // orange
};

cv::Scalar series_colour(std::size_t i) {
    return kSeriesColours[i % (sizeof(kSeriesColours) / sizeof(kSeriesColours[0]))];
}

// ------------------------------------------------------------------ the run

struct ModelRun {
    TableModel model;
    std::string name;
    CoefficientTable table;
    int usable_poses = 0;
    int poses = 0;
    std::size_t pixels_modelled = 0;
    double fit_rms_z_median = kNaN;
    double seconds = 0;
};

// Reconstructions of one decoded scan: SV (label 0), then each table.
struct Reconstructions {
    std::vector<PointCloud> clouds;
    std::vector<std::size_t> points;
    std::vector<std::uint8_t> common; // 1 where every cloud has a point
    std::size_t common_count = 0;
};

bool finite_point(const float* p) {
    return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

// The points of `cloud` at the pixels of `mask` (organised).
CloudPoints masked_points(const PointCloud& cloud, const std::vector<std::uint8_t>& mask) {
    CloudPoints out;
    out.organised = cloud.size();
    const float* xyz = cloud.xyz.data();
    for (std::size_t i = 0; i < mask.size(); ++i)
        if (mask[i]) {
            out.points.push_back(
                {double(xyz[3 * i]), double(xyz[3 * i + 1]), double(xyz[3 * i + 2])});
            out.pixels.push_back(static_cast<std::uint32_t>(i));
        }
    return out;
}

enum class FitKind { plane, cylinder, sphere, none };

struct ScanSummary {
    std::string key;   // figures.csv name part
    std::string title; // summary.md
    FitKind fit = FitKind::none;
    double nominal_diameter = 0;
    std::size_t truth_pixels = 0;
    std::size_t common = 0;
    std::vector<std::size_t> points;                       // per label
    std::vector<double> fit_rms, diameter, diameter_error; // per label (NaN: no fit), noisy scan
    std::vector<double> fit_rms_clean, diameter_clean;     // the same on the noise-free scan
    std::string fit_note;
    std::vector<ErrorStats> truth_noisy, truth_clean; // per label
    std::vector<ErrorStats> shape_noisy, shape_clean; // per label: bias and tilt removed
    std::size_t compared_noisy = 0, compared_clean = 0;
};

struct ReliefSummary {
    double scale = 1;
    std::size_t pixels_seen = 0;
    std::vector<double> distance_rms, dz_rms; // per model (SV - model, per pixel)
    std::vector<std::size_t> matched;         // per model
    std::vector<double> seconds;              // per label, one thread
    double seconds_sv_plane_iteration = kNaN; // the paper's SV iteration
};

struct WindowSummary {
    std::vector<int> sizes;
    std::vector<std::size_t> points;          // SV points per window
    std::vector<std::vector<double>> seconds; // [label][window]
    double crop_max_difference_mm = 0;        // cropped vs full-image reconstruction
    std::size_t crop_mismatched = 0;          // pixels with a point in one only
    int x0 = 0, y0 = 0;                       // largest window's corner
};

class Run {
  public:
    Run(const fs::path& folder, const PaperExperimentOptions& options)
        : folder_(folder), options_(options), start_(Clock::now()) {}

    PaperExperimentResult run() {
        setup_rig();
        simulate_sessions();
        calibrate_stereo();
        calibrate_hybrid_models();
        run_plane();
        run_shape("cylinder", "Experiment 2: cylinder (168 mm diameter, 215 mm long)",
                  FitKind::cylinder, kCylinderDiameter, cylinder_scene, 12);
        run_shape("sphere", "Sphere (ours): 120 mm diameter", FitKind::sphere, kSphereDiameter,
                  sphere_scene, 13);
        run_relief();
        if (!options_.keep_sessions) {
            say("removing the calibration sessions (keep them with --keep-sessions)");
            fs::remove_all(folder_ / "sessions");
        }
        return finish();
    }

  private:
    // ---- small utilities
    void say(const std::string& line) const {
        if (options_.progress)
            options_.progress(line);
    }
    std::function<void(const std::string&)> indented() const {
        return [this](const std::string& line) { say("  " + line); };
    }
    std::size_t labels() const { return 1 + models_.size(); }
    std::string label_key(std::size_t i) const { return i == 0 ? "sv" : models_[i - 1].name; }
    std::string label_title(std::size_t i) const {
        if (i == 0)
            return "SV (x only)";
        std::string t = "hybrid " + models_[i - 1].name;
        if (models_[i - 1].model == TableModel::polynomial)
            t += " (paper's)";
        if (models_[i - 1].name == default_model_)
            t += " (default)";
        return t;
    }
    void add(const std::string& name, double value, const std::string& unit) {
        figures_.push_back({name, value, unit});
    }
    void png(const std::string& name, const cv::Mat& image) { save_png(report_ / name, image); }
    std::uint64_t scan_seed(int k) const { return options_.seed * 1000 + std::uint64_t(k); }

    // ---- setup
    void setup_rig() {
        const fs::path rig_path =
            options_.rig.empty() ? sim::lens_defects_rig_path() : options_.rig;
        rig_ = sim::load_rig(rig_path);
        if (options_.binning > 1)
            rig_ = rig_.binned_camera(options_.binning);
        clean_rig_ = rig_;
        clean_rig_.sensor.read_noise_dn = 0;
        clean_rig_.sensor.gain_e_per_dn = 0; // no shot noise
        scan_sequence_ = standard_sequence("gray-x", rig_.projector_size);
        decode_options_.threads = options_.threads;
        default_model_ = to_string(HybridOptions{}.model);
        report_ = folder_ / "report";
        fs::create_directories(report_);
        fs::create_directories(folder_ / "scans");
        fs::create_directories(folder_ / "sessions");
        say("rig '" + rig_.name + "' (" + rig_path.string() + "), camera " +
            std::to_string(rig_.camera_size.width) + " x " +
            std::to_string(rig_.camera_size.height) + " (binning " +
            std::to_string(options_.binning) + "), projector " +
            std::to_string(rig_.projector_size.width) + " x " +
            std::to_string(rig_.projector_size.height));
    }

    void simulate_sessions() {
        const auto start = Clock::now();
        checkerboard_session_ = folder_ / "sessions" / "checkerboard";
        plane_session_ = folder_ / "sessions" / "planes";
        if (options_.sv_calibration == SvCalibrationSource::checkerboard) {
            sim::SessionOptions board;
            board.kind = sim::SessionKind::checkerboard;
            board.poses = options_.checkerboard_poses;
            board.seed = options_.seed;
            const Sequence board_sequence = standard_sequence("gray-xy", rig_.projector_size);
            say("simulating the checkerboard session: " + std::to_string(board.poses) +
                " poses, gray-xy (" + std::to_string(frame_count(board_sequence)) +
                " frames each)");
            sim::write_session(
                checkerboard_session_, rig_, board_sequence, board, [&](int done, int total) {
                    say("  pose " + std::to_string(done) + "/" + std::to_string(total));
                });
        }
        sim::SessionOptions planes;
        planes.kind = sim::SessionKind::plane;
        planes.poses = options_.plane_poses;
        planes.seed = options_.seed + 1;
        say("simulating the flat-board session: " + std::to_string(planes.poses) +
            " poses, gray-x, vertical fringes only (" +
            std::to_string(frame_count(scan_sequence_)) + " frames each)");
        sim::write_session(plane_session_, rig_, scan_sequence_, planes, [&](int done, int total) {
            say("  pose " + std::to_string(done) + "/" + std::to_string(total));
        });
        seconds_sessions_ = seconds_since(start);
    }

    void calibrate_stereo() {
        const auto start = Clock::now();
        if (options_.sv_calibration == SvCalibrationSource::rig_model) {
            say("SV model: the rig's own lenses and pose within the 5-coefficient model "
                "(no stereo calibration; the distortion outside that model is left to SV)");
            calibration_ = calibration_from_rig(rig_);
            calibration_.camera.drop_unmodelled_terms();
            calibration_.projector.drop_unmodelled_terms();
            calibration_.origin = "rig '" + rig_.name + "', 5-coefficient part of its model";
        } else {
            say("stereo calibration from the checkerboard session");
            StereoSessionOptions so;
            so.compare_skew = false;
            so.decode.threads = options_.threads;
            so.progress = indented();
            const SessionResult session = calibrate_session(checkerboard_session_, so);
            calibration_ = session.stereo.calibration;
            write_calibration_report(folder_ / "stereo-report", session);
            calibration_poses_ = static_cast<int>(session.calibrated.size());
            add("calibration.camera_rms", calibration_.camera_rms, "px");
            add("calibration.projector_rms", calibration_.projector_rms, "px");
            add("calibration.poses_used", double(calibration_poses_), "");
            say("stereo calibration: camera RMS " + fixed_text(calibration_.camera_rms, 4) +
                " px, projector RMS " + fixed_text(calibration_.projector_rms, 4) + " px, " +
                std::to_string(calibration_poses_) + " poses");
        }
        const std::string text = calibration_to_yaml(calibration_);
        write_file_synced(folder_ / "calib.yaml", text);
        calibration_hash_ = fnv1a64(text.data(), text.size());
        seconds_stereo_ = seconds_since(start);
        SvOptions sv;
        sv.threads = options_.threads;
        sv_ = std::make_unique<SvReconstructor>(calibration_, sv);
    }

    void calibrate_hybrid_models() {
        // One pass over the plane poses; every model is fitted to it.
        const std::vector<TableModel> models = available_table_models();
        say("hybrid calibration, every model from one pass over the poses");
        HybridOptions ho;
        ho.threads = options_.threads;
        ho.decode.threads = options_.threads;
        ho.sv.threads = options_.threads;
        ho.progress = indented();
        const std::vector<HybridResult> results =
            calibrate_hybrid(plane_session_, calibration_, calibration_hash_, ho, models);
        for (std::size_t k = 0; k < models.size(); ++k) {
            const TableModel model = models[k];
            const HybridResult& result = results[k];
            ModelRun m;
            m.model = model;
            m.name = to_string(model);
            const fs::path table_path = folder_ / ("table-" + m.name + ".fpt");
            write_table(table_path, result.table);
            write_hybrid_report(folder_ / ("hybrid-report-" + m.name), result);
            // Reconstruct with the table as the scanner would: read back from its file.
            m.table = load_table(table_path, &rig_.camera_size, false);
            m.usable_poses = result.usable_poses;
            m.poses = static_cast<int>(result.poses.size());
            m.pixels_modelled = result.pixels_modelled;
            std::vector<double> rms;
            rms.reserve(result.rms_z.pixel_count());
            for (std::size_t i = 0; i < result.rms_z.pixel_count(); ++i)
                if (std::isfinite(result.rms_z.data()[i]))
                    rms.push_back(double(result.rms_z.data()[i]));
            m.fit_rms_z_median = median(std::move(rms));
            m.seconds = result.seconds_total;
            add("hybrid." + m.name + ".usable_poses", double(m.usable_poses), "");
            add("hybrid." + m.name + ".pixels_modelled", double(m.pixels_modelled), "");
            add("hybrid." + m.name + ".fit_rms_z_median", m.fit_rms_z_median, "mm");
            add("hybrid." + m.name + ".seconds", m.seconds, "s");
            say("  " + m.name + ": " + std::to_string(m.usable_poses) + " of " +
                std::to_string(m.poses) + " poses, " + std::to_string(m.pixels_modelled) +
                " pixels modelled, median Z fit RMS " + fixed_text(m.fit_rms_z_median, 4) + " mm");
            models_.push_back(std::move(m));
        }
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
        r.clouds.resize(labels());
        sv_->reconstruct(decoded, ReconstructAxes::x, r.clouds[0]);
        for (std::size_t m = 0; m < models_.size(); ++m)
            apply_table(models_[m].table, decoded.proj_x, r.clouds[m + 1]);
        const std::size_t n = decoded.camera.area();
        r.common.assign(n, 1);
        r.points.assign(labels(), 0);
        for (std::size_t l = 0; l < labels(); ++l) {
            const float* xyz = r.clouds[l].xyz.data();
            for (std::size_t i = 0; i < n; ++i) {
                const bool ok = finite_point(xyz + 3 * i);
                r.points[l] += ok ? 1 : 0;
                if (!ok)
                    r.common[i] = 0;
            }
        }
        erode(r.common, decoded.camera, kEdgeMarginPx);
        r.common_count = std::size_t(std::count(r.common.begin(), r.common.end(), 1));
        return r;
    }

    // Simulates a scan (noisy, saved with truth; then noise-free), reconstructs
    // both with every model and records truth errors, shape fits and figures.
    // Returns the noisy scan's decode and reconstructions for later use.
    struct NoisyScan {
        DecodeResult decoded;
        Reconstructions recon;
    };
    NoisyScan process_scan(ScanSummary& s, const sim::Scene& scene,
                           std::unique_ptr<sim::Renderer> renderer, int seed_index) {
        const fs::path folder = folder_ / "scans" / s.key;
        say("scan '" + s.key + "': rendering with the rig's noise");
        if (!renderer)
            renderer = std::make_unique<sim::Renderer>(rig_, scene, options_.threads);
        NoisyScan noisy;
        {
            const sim::SimulatedCapture capture =
                sim::simulate(*renderer, scan_sequence_, scan_seed(seed_index));
            sim::write_simulated_capture(folder, capture);
            noisy.decoded = decode_capture(capture, folder);
            noisy.recon = reconstruct_all(noisy.decoded);
            s.points = noisy.recon.points;
            s.common = noisy.recon.common_count;
            for (std::size_t l = 0; l < labels(); ++l) {
                const TruthComparison t = compare_with_truth(
                    masked_points(noisy.recon.clouds[l], noisy.recon.common), capture.truth_xyz);
                s.truth_noisy.push_back(t.dz);
                s.shape_noisy.push_back(t.dz_shape);
                s.compared_noisy = t.compared;
                s.truth_pixels = t.truth_pixels;
            }
        }
        renderer.reset();
        say("scan '" + s.key + "': " + std::to_string(s.points[0]) + " SV points, " +
            std::to_string(s.common) + " pixels with a point from every model");
        fit_shapes(s, noisy.recon, true);

        say("scan '" + s.key + "': rendering noise-free (read noise 0, no shot noise)");
        {
            const sim::Renderer clean(clean_rig_, scene, options_.threads);
            const sim::SimulatedCapture capture =
                sim::simulate(clean, scan_sequence_, scan_seed(seed_index));
            const DecodeResult decoded = decode_capture(capture, folder);
            const Reconstructions recon = reconstruct_all(decoded);
            fit_shapes(s, recon, false);
            std::vector<TruthComparison> cmp;
            for (std::size_t l = 0; l < labels(); ++l) {
                cmp.push_back(compare_with_truth(masked_points(recon.clouds[l], recon.common),
                                                 capture.truth_xyz));
                s.truth_clean.push_back(cmp.back().dz);
                s.shape_clean.push_back(cmp.back().dz_shape);
                s.compared_clean = cmp.back().compared;
            }
            // Model error maps on one colour scale, SV's.
            const double limit = symmetric_limit(cmp[0].dz_values);
            for (std::size_t l = 0; l < labels(); ++l)
                png("truth-" + s.key + "-" + label_key(l) + ".png",
                    signed_map_figure(cmp[l].dz_map, limit,
                                      s.key + " noise-free: Z - Z true, " + label_title(l)));
        }
        for (std::size_t l = 0; l < labels(); ++l) {
            const std::string k = label_key(l);
            add(s.key + ".points." + k, double(s.points[l]), "");
            add("truth." + s.key + ".noisy." + k + ".rms", s.truth_noisy[l].rms, "mm");
            add("truth." + s.key + ".noisy." + k + ".mean", s.truth_noisy[l].mean, "mm");
            add("truth." + s.key + ".noisy." + k + ".std", s.truth_noisy[l].stddev, "mm");
            add("truth." + s.key + ".noise_free." + k + ".rms", s.truth_clean[l].rms, "mm");
            add("truth." + s.key + ".noise_free." + k + ".mean", s.truth_clean[l].mean, "mm");
            add("truth." + s.key + ".noise_free." + k + ".std", s.truth_clean[l].stddev, "mm");
            add("truth." + s.key + ".noisy." + k + ".shape_rms", s.shape_noisy[l].rms, "mm");
            add("truth." + s.key + ".noise_free." + k + ".shape_rms", s.shape_clean[l].rms, "mm");
        }
        add(s.key + ".truth_pixels", double(s.truth_pixels), "");
        add(s.key + ".common_points", double(s.common), "");
        add("truth." + s.key + ".noisy.compared", double(s.compared_noisy), "");
        add("truth." + s.key + ".noise_free.compared", double(s.compared_clean), "");
        std::string line = "scan '" + s.key + "' Z error vs truth, RMS noisy / noise-free:";
        for (std::size_t l = 0; l < labels(); ++l)
            line += " " + label_key(l) + " " + fixed_text(s.truth_noisy[l].rms, 4) + " / " +
                    fixed_text(s.truth_clean[l].rms, 4);
        say(line + " mm");
        return noisy;
    }

    // Shape fit of every model's points (the common pixels); for the noisy
    // scan also histograms and maps.
    void fit_shapes(ScanSummary& s, const Reconstructions& recon, bool noisy) {
        std::vector<double> fit_rms(labels(), kNaN), diameter(labels(), kNaN),
            diameter_error(labels(), kNaN);
        if (s.fit == FitKind::none)
            return;
        std::vector<CloudPoints> points(labels());
        std::vector<std::vector<double>> residuals(labels());
        for (std::size_t l = 0; l < labels(); ++l) {
            points[l] = masked_points(recon.clouds[l], recon.common);
            try {
                if (s.fit == FitKind::plane) {
                    const PlaneFit f = fit_plane(points[l].points);
                    fit_rms[l] = f.fit.rms;
                    residuals[l] = f.fit.residuals;
                } else if (s.fit == FitKind::cylinder) {
                    const CylinderFigures f =
                        cylinder_figures(points[l].points, s.nominal_diameter);
                    fit_rms[l] = f.fit.fit.rms;
                    diameter[l] = f.diameter;
                    diameter_error[l] = f.diameter_error.value_or(kNaN);
                    residuals[l] = f.fit.fit.residuals;
                } else {
                    const ProbingFigures f = probing_figures(points[l].points, s.nominal_diameter);
                    fit_rms[l] = f.fit.fit.rms;
                    diameter[l] = f.diameter;
                    diameter_error[l] = f.size_error.value_or(kNaN);
                    residuals[l] = f.fit.fit.residuals;
                }
            } catch (const FitError& e) {
                s.fit_note += label_title(l) + (noisy ? "" : " (noise-free)") + ": fit failed (" +
                              e.what() + "). ";
            }
        }
        if (!noisy) {
            s.fit_rms_clean = fit_rms;
            s.diameter_clean = diameter;
            for (std::size_t l = 0; l < labels(); ++l)
                if (std::isfinite(fit_rms[l])) {
                    add(s.key + ".fit_rms_noise_free." + label_key(l), fit_rms[l], "mm");
                    if (s.fit != FitKind::plane)
                        add(s.key + ".diameter_noise_free." + label_key(l), diameter[l], "mm");
                }
            return;
        }
        s.fit_rms = fit_rms;
        s.diameter = diameter;
        s.diameter_error = diameter_error;
        const char* fit_name = s.fit == FitKind::plane      ? "plane"
                               : s.fit == FitKind::cylinder ? "cylinder"
                                                            : "sphere";
        for (std::size_t l = 0; l < labels(); ++l) {
            if (!std::isfinite(s.fit_rms[l]))
                continue;
            add(s.key + ".fit_rms." + label_key(l), s.fit_rms[l], "mm");
            if (s.fit != FitKind::plane) {
                add(s.key + ".diameter." + label_key(l), s.diameter[l], "mm");
                add(s.key + ".diameter_error." + label_key(l), s.diameter_error[l], "mm");
            }
        }
        if (residuals[0].empty())
            return;
        const double limit = symmetric_limit(residuals[0]);
        std::vector<HistogramSeries> series;
        for (std::size_t l = 0; l < labels(); ++l)
            if (!residuals[l].empty())
                series.push_back({label_title(l), residuals[l]});
        png(s.key + "-fit-histogram.png",
            histogram_figure(series, -limit, limit, std::string(fit_name) + " fit residual (mm)",
                             s.key + ": " + fit_name + "-fit residuals (noisy scan)"));
        for (std::size_t l = 0; l < labels(); ++l)
            if (!residuals[l].empty())
                png(s.key + "-fit-map-" + label_key(l) + ".png",
                    signed_map_figure(values_image(points[l], residuals[l]), limit,
                                      s.key + ": " + fit_name + "-fit residual, " +
                                          label_title(l)));
        std::string line = "scan '" + s.key + "' " + fit_name + "-fit RMS:";
        for (std::size_t l = 0; l < labels(); ++l)
            line += " " + label_key(l) + " " + fixed_text(s.fit_rms[l], 4);
        say(line + " mm");
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
                   sim::Scene (*make)(), int seed_index) {
        ScanSummary s;
        s.key = key;
        s.title = title;
        s.fit = fit;
        s.nominal_diameter = nominal;
        const sim::Scene scene = make();
        process_scan(s, scene, nullptr, seed_index);
        scans_.push_back(std::move(s));
    }

    void run_plane() {
        ScanSummary s;
        s.key = "plane";
        s.title = "Experiment 1: inclined plane (230 x 175 mm, ~20 deg, 480 mm)";
        s.fit = FitKind::plane;
        const sim::Scene scene = plane_scene();
        const NoisyScan noisy = process_scan(s, scene, nullptr, 11);
        scans_.push_back(std::move(s));
        run_windows(noisy.decoded, noisy.recon);
    }

    // ---- Experiment 3
    void run_relief() {
        const double target = kReliefPixelsFullSize / double(options_.binning * options_.binning);
        say("relief: sizing it so that about " + std::to_string(static_cast<long>(target)) +
            " camera pixels see it");
        double scale = 1;
        std::unique_ptr<sim::Renderer> renderer;
        std::size_t seen = 0;
        for (int round = 0; round < 3; ++round) {
            const sim::Scene scene = relief_scene(scale);
            renderer = std::make_unique<sim::Renderer>(rig_, scene, options_.threads);
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
        relief_.scale = scale;
        relief_.pixels_seen = seen;
        add("relief.scale", scale, "");
        add("relief.pixels_seen", double(seen), "");
        add("relief.width", kReliefWidth * scale, "mm");
        add("relief.height", kReliefHeight * scale, "mm");

        ScanSummary s;
        s.key = "relief";
        s.title = "Experiment 3: freeform relief (face)";
        s.fit = FitKind::none;
        const sim::Scene scene = relief_scene(scale);
        const NoisyScan noisy = process_scan(s, scene, std::move(renderer), 14);
        scans_.push_back(std::move(s));

        // SV and each table, per pixel (each cloud's own points).
        const CloudPoints sv_points = cloud_points(noisy.recon.clouds[0]);
        std::vector<std::vector<double>> differences;
        for (std::size_t m = 0; m < models_.size(); ++m) {
            const CloudDistance d =
                compare_per_pixel(sv_points, cloud_points(noisy.recon.clouds[m + 1]));
            relief_.distance_rms.push_back(d.distance.rms);
            relief_.dz_rms.push_back(d.dz.rms);
            relief_.matched.push_back(d.matched);
            add("relief.difference." + models_[m].name + ".distance_rms", d.distance.rms, "mm");
            add("relief.difference." + models_[m].name + ".dz_rms", d.dz.rms, "mm");
            add("relief.difference." + models_[m].name + ".dz_mean", d.dz.mean, "mm");
            add("relief.difference." + models_[m].name + ".matched", double(d.matched), "");
            png("relief-difference-" + models_[m].name + ".png",
                signed_map_figure(d.dz_map, symmetric_limit(d.values),
                                  "relief: Z(SV) - Z(hybrid " + models_[m].name + ")"));
            differences.push_back(d.values);
        }
        if (!differences.empty()) {
            std::vector<HistogramSeries> series;
            for (std::size_t m = 0; m < models_.size(); ++m)
                series.push_back({"SV - " + models_[m].name, differences[m]});
            const double limit = symmetric_limit(differences[0]);
            png("relief-difference-histogram.png",
                histogram_figure(series, -limit, limit, "Z(SV) - Z(hybrid) per pixel (mm)",
                                 "relief: SV vs hybrid reconstructions"));
        }
        time_relief(noisy.decoded);
    }

    void time_relief(const DecodeResult& decoded) {
        const int runs = options_.timing_runs;
        say("relief: timing the reconstructions, one thread each, best of " + std::to_string(runs));
        relief_.seconds.assign(labels(), kNaN);
        PointCloud cloud;
        SvOptions one;
        one.threads = 1;
        {
            const SvReconstructor sv(calibration_, one);
            relief_.seconds[0] =
                best_seconds(runs, [&] { sv.reconstruct(decoded, ReconstructAxes::x, cloud); });
        }
        {
            SvOptions paper = one;
            paper.solver = XOnlySolver::plane_iteration;
            const SvReconstructor sv(calibration_, paper);
            relief_.seconds_sv_plane_iteration =
                best_seconds(runs, [&] { sv.reconstruct(decoded, ReconstructAxes::x, cloud); });
        }
        ThreadPool single(1);
        for (std::size_t m = 0; m < models_.size(); ++m)
            relief_.seconds[m + 1] = best_seconds(
                runs, [&] { apply_table(models_[m].table, decoded.proj_x, cloud, &single); });
        add("relief.time.sv", relief_.seconds[0], "s");
        add("relief.time.sv_plane_iteration", relief_.seconds_sv_plane_iteration, "s");
        std::string line = "relief: SV " + seconds_text(relief_.seconds[0]) +
                           " (paper's plane iteration " +
                           seconds_text(relief_.seconds_sv_plane_iteration) + ")";
        for (std::size_t m = 0; m < models_.size(); ++m) {
            const double speedup = relief_.seconds[0] / relief_.seconds[m + 1];
            add("relief.time." + models_[m].name, relief_.seconds[m + 1], "s");
            add("relief.speedup." + models_[m].name, speedup, "");
            line += ", " + models_[m].name + " " + seconds_text(relief_.seconds[m + 1]) + " (" +
                    fixed_text(speedup, 1) + "x)";
        }
        say(line);
    }

    // ---- Experiment 4
    void run_windows(const DecodeResult& decoded, const Reconstructions& full) {
        const Size camera = decoded.camera;
        // Centre: centroid of the plane's pixels.
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
                                                                  double(options_.binning)))));
            if (windows_.sizes.empty() || size > windows_.sizes.back())
                windows_.sizes.push_back(size);
        }
        const int runs = options_.timing_runs;
        say("windows: timing " + std::to_string(windows_.sizes.size()) +
            " square windows of the plane scan, one thread each, best of " + std::to_string(runs));
        windows_.seconds.assign(labels(), {});
        ThreadPool single(1);
        SvOptions one;
        one.threads = 1;
        for (int size : windows_.sizes) {
            const int x0 =
                std::clamp(static_cast<int>(std::lround(cx - size / 2.0)), 0, camera.width - size);
            const int y0 =
                std::clamp(static_cast<int>(std::lround(cy - size / 2.0)), 0, camera.height - size);
            windows_.x0 = x0;
            windows_.y0 = y0;
            const Size window{size, size};
            const DecodeResult cropped = crop_decode(decoded, x0, y0, window);
            std::vector<PointCloud> clouds(labels());
            {
                const SvReconstructor sv(crop_calibration(calibration_, x0, y0, window), one);
                windows_.seconds[0].push_back(best_seconds(
                    runs, [&] { sv.reconstruct(cropped, ReconstructAxes::x, clouds[0]); }));
            }
            for (std::size_t m = 0; m < models_.size(); ++m) {
                const CoefficientTable table = crop_table(models_[m].table, x0, y0, window);
                windows_.seconds[m + 1].push_back(best_seconds(
                    runs, [&] { apply_table(table, cropped.proj_x, clouds[m + 1], &single); }));
            }
            // The window's reconstructions must be the full image's, pixel for pixel.
            std::size_t points = 0;
            for (std::size_t l = 0; l < labels(); ++l)
                for (int y = 0; y < size; ++y)
                    for (int x = 0; x < size; ++x) {
                        const float* a = &clouds[l].xyz.at(x, y, 0);
                        const float* b = &full.clouds[l].xyz.at(x0 + x, y0 + y, 0);
                        const bool fa = finite_point(a), fb = finite_point(b);
                        if (l == 0 && fa)
                            ++points;
                        if (fa != fb) {
                            ++windows_.crop_mismatched;
                            continue;
                        }
                        if (fa)
                            for (int c = 0; c < 3; ++c)
                                windows_.crop_max_difference_mm =
                                    std::max(windows_.crop_max_difference_mm,
                                             std::abs(double(a[c]) - double(b[c])));
                    }
            windows_.points.push_back(points);
            std::string line = "  N = " + std::to_string(size) + ": SV " +
                               seconds_text(windows_.seconds[0].back());
            for (std::size_t m = 0; m < models_.size(); ++m)
                line += ", " + models_[m].name + " " + seconds_text(windows_.seconds[m + 1].back());
            say(line);
        }
        for (std::size_t w = 0; w < windows_.sizes.size(); ++w) {
            const std::string base = "windows.n" + std::to_string(windows_.sizes[w]);
            add(base + ".points", double(windows_.points[w]), "");
            for (std::size_t l = 0; l < labels(); ++l)
                add(base + ".time." + label_key(l), windows_.seconds[l][w], "s");
        }
        add("windows.crop_max_difference", windows_.crop_max_difference_mm, "mm");
        add("windows.crop_mismatched", double(windows_.crop_mismatched), "");
        std::vector<PlotSeries> series;
        for (std::size_t l = 0; l < labels(); ++l)
            series.push_back({label_title(l), windows_.seconds[l], series_colour(l)});
        png("windows-timing.png",
            timing_plot(windows_.sizes, series,
                        "Experiment 4: reconstruction time of N x N windows (one thread)"));
    }

    // ---- targets and report
    const ScanSummary* scan(const std::string& key) const {
        for (const ScanSummary& s : scans_)
            if (s.key == key)
                return &s;
        return nullptr;
    }

    void evaluate_targets() {
        for (std::size_t m = 0; m < models_.size(); ++m) {
            const std::size_t l = m + 1;
            const std::string name = models_[m].name;
            for (bool clean : {true, false}) {
                const std::string noise = clean ? "noise_free" : "noisy";
                const std::string noise_text = clean ? "noise-free" : "with noise";
                for (const char* key : {"plane", "cylinder", "sphere", "relief"}) {
                    const ScanSummary* s = scan(key);
                    if (!s)
                        continue;
                    const double sv = clean ? s->truth_clean[0].rms : s->truth_noisy[0].rms;
                    const double hy = clean ? s->truth_clean[l].rms : s->truth_noisy[l].rms;
                    const bool plane = std::string(key) == "plane";
                    const double bound = plane ? kPlaneRatioTarget * sv : sv;
                    PaperTarget t;
                    t.key = std::string(key) + (plane ? "_half_of_sv." : "_no_worse_than_sv.") +
                            noise + "." + name;
                    t.description = std::string(key) + ": hybrid " + name + " Z error vs truth " +
                                    (plane ? "<= 0.5 x SV's" : "<= SV's") + " (" + noise_text + ")";
                    t.met = hy <= bound;
                    t.detail = fixed_text(hy, 5) + " mm vs " + (plane ? "0.5 x " : "") +
                               fixed_text(sv, 5) + " mm";
                    targets_.push_back(t);
                    // The same on the error's shape (depth offset and tilt
                    // removed), what a correction onto planes can improve.
                    const double sv_shape = clean ? s->shape_clean[0].rms : s->shape_noisy[0].rms;
                    const double hy_shape = clean ? s->shape_clean[l].rms : s->shape_noisy[l].rms;
                    const double shape_bound = plane ? kPlaneRatioTarget * sv_shape : sv_shape;
                    PaperTarget shape;
                    shape.key = std::string(key) +
                                (plane ? "_shape_half_of_sv." : "_shape_no_worse_than_sv.") +
                                noise + "." + name;
                    shape.description = std::string(key) + ": hybrid " + name +
                                        " Z error shape vs truth (offset and tilt removed) " +
                                        (plane ? "<= 0.5 x SV's" : "<= SV's") + " (" + noise_text +
                                        ")";
                    shape.met = hy_shape <= shape_bound;
                    shape.detail = fixed_text(hy_shape, 5) + " mm vs " + (plane ? "0.5 x " : "") +
                                   fixed_text(sv_shape, 5) + " mm";
                    targets_.push_back(shape);
                }
            }
            if (!relief_.seconds.empty()) {
                const double speedup = relief_.seconds[0] / relief_.seconds[l];
                PaperTarget t;
                t.key = "relief_speedup_50x." + name;
                t.description = "relief: hybrid " + name +
                                " reconstruction at least 50x faster than SV (one thread each)";
                t.met = speedup >= kSpeedupTarget;
                t.detail = fixed_text(speedup, 1) + "x (" + seconds_text(relief_.seconds[0]) +
                           " vs " + seconds_text(relief_.seconds[l]) + "; " +
                           fixed_text(relief_.seconds_sv_plane_iteration / relief_.seconds[l], 1) +
                           "x against the paper's plane iteration)";
                targets_.push_back(t);
            }
        }
        for (const PaperTarget& t : targets_)
            add("target." + t.key, t.met ? 1.0 : 0.0, "");
    }

    std::string summary() const {
        std::ostringstream md;
        const auto row = [&](std::initializer_list<std::string> cells) {
            md << "|";
            for (const std::string& c : cells)
                md << " " << c << " |";
            md << "\n";
        };
        md << "# The paper's experiments on the virtual scanner\n\n";
        md << "Rig `" << rig_.name << "` with its effects (projector distortion outside the "
           << "stereo model, gamma, defocus, noise), camera " << rig_.camera_size.width << " x "
           << rig_.camera_size.height << " (binning " << options_.binning << "), seed "
           << options_.seed << ". ";
        if (options_.sv_calibration == SvCalibrationSource::checkerboard)
            md << "Stereo calibration from " << options_.checkerboard_poses
               << " checkerboard poses (gray-xy)";
        else
            md << "SV model: the rig's own lenses and pose restricted to the 5-coefficient model "
                  "(terms outside it dropped; no stereo calibration), i.e. SV with a known "
                  "model deficit";
        md << "; hybrid tables from " << options_.plane_poses
           << " flat-board poses (gray-x, vertical fringes only). Scans use gray-x; SV "
           << "reconstructs with the projector column only (the paper's SV). Models: SV, ";
        for (std::size_t m = 0; m < models_.size(); ++m)
            md << (m ? ", " : "") << "hybrid " << models_[m].name;
        md << " (default model: " << default_model_ << "; polynomial is the paper's).\n\n";
        md << "Shape fits and truth errors use the pixels where every model gives a point, "
              "at least "
           << kEdgeMarginPx
           << " px inside the edge of that region (silhouette pixels mix the phase of the "
              "surface with their neighbours'). "
              "Reconstruction times are phase to XYZ only (decoding is common to both), one "
              "thread each, best of "
           << options_.timing_runs << " runs after a warm-up.\n\n";
        md << "Reading the errors against ground truth: Z(point) - Z(true) per pixel, with its "
              "mean (bias) and spread (std). The hybrid calibration moves each flat-board pose "
              "onto its own best-fitting plane, so it can remove only the part of SV's error "
              "that bends planes; an error that keeps planes flat (a depth bias, a slight scale "
              "or tilt of space such as a calibration leaves) is passed on to every table. The "
              "shape RMS is the Z error less its own best a + b X + c Y (depth offset and tilt "
              "taken out): the part of the error against the truth that such a correction can "
              "reach. The fit RMS of the noise-free scans is each model's error against its "
              "own best shape.\n\n";

        md << "## The paper's figures beside ours\n\n";
        row({"figure", "paper SV", "paper hybrid", "our SV", "our " + default_model_,
             "our polynomial"});
        row({"---", "---:", "---:", "---:", "---:", "---:"});
        const auto ours = [&](const ScanSummary* s, const std::string& name) {
            if (!s)
                return std::string("-");
            for (std::size_t l = 0; l < labels(); ++l)
                if (label_key(l) == name)
                    return fixed_text(s->fit_rms[l], 4);
            return std::string("-");
        };
        const ScanSummary* plane = scan("plane");
        const ScanSummary* cylinder = scan("cylinder");
        row({"plane-fit RMS, inclined plane (mm)", fixed_text(kPaperPlaneSv, 3),
             fixed_text(kPaperPlaneHybrid, 3), ours(plane, "sv"), ours(plane, default_model_),
             ours(plane, "polynomial")});
        row({"cylinder-fit RMS (mm)", fixed_text(kPaperCylinderSv, 3),
             fixed_text(kPaperCylinderHybrid, 3), ours(cylinder, "sv"),
             ours(cylinder, default_model_), ours(cylinder, "polynomial")});
        const auto relief_time = [&](const std::string& name) {
            for (std::size_t l = 0; l < labels() && l < relief_.seconds.size(); ++l)
                if (label_key(l) == name)
                    return seconds_text(relief_.seconds[l]);
            return std::string("-");
        };
        row({"relief reconstruction time (one thread)", seconds_text(kPaperReliefSvSeconds),
             seconds_text(kPaperReliefHybridSeconds), relief_time("sv"),
             relief_time(default_model_), relief_time("polynomial")});
        const auto relief_distance = [&](const std::string& name) {
            for (std::size_t m = 0; m < models_.size() && m < relief_.distance_rms.size(); ++m)
                if (models_[m].name == name)
                    return fixed_text(relief_.distance_rms[m], 4);
            return std::string("-");
        };
        row({"relief: RMS distance SV vs hybrid (mm)", "-", fixed_text(kPaperReliefDistance, 3),
             "-", relief_distance(default_model_), relief_distance("polynomial")});
        const ScanSummary* relief = scan("relief");
        row({"relief points", "-", std::to_string(static_cast<long>(kPaperReliefPoints)),
             relief ? std::to_string(relief->points[0]) : "-", "-", "-"});
        md << "\nThe paper's times are of its own implementation on its authors' PC; ours are of "
              "this build on this machine. The SV figure above uses our Newton solver; the "
              "paper's plane iteration took "
           << seconds_text(relief_.seconds_sv_plane_iteration) << ".\n\n";

        md << "## Calibration\n\n";
        if (options_.sv_calibration == SvCalibrationSource::checkerboard)
            md << "Stereo: camera RMS " << fixed_text(calibration_.camera_rms, 4)
               << " px, projector RMS " << fixed_text(calibration_.projector_rms, 4) << " px, "
               << calibration_poses_ << " poses (report: `stereo-report/`).\n\n";
        else
            md << "SV model: " << calibration_.origin << " (`calib.yaml`).\n\n";
        row({"hybrid model", "poses used", "pixels modelled", "median Z fit RMS (mm)", "time"});
        row({"---", "---:", "---:", "---:", "---:"});
        for (const ModelRun& m : models_)
            row({m.name, std::to_string(m.usable_poses) + " / " + std::to_string(m.poses),
                 std::to_string(m.pixels_modelled) + " / " +
                     std::to_string(rig_.camera_size.area()),
                 fixed_text(m.fit_rms_z_median, 4), seconds_text(m.seconds)});
        md << "\nTables: `table-<model>.fpt`; reports: `hybrid-report-<model>/`.\n\n";

        for (const ScanSummary& s : scans_) {
            md << "## " << s.title << "\n\n";
            if (s.key == "relief")
                md << "Relief scaled by " << fixed_text(relief_.scale, 3) << " ("
                   << fixed_text(kReliefWidth * relief_.scale, 1) << " x "
                   << fixed_text(kReliefHeight * relief_.scale, 1) << " mm), seen by "
                   << relief_.pixels_seen << " lit camera pixels.\n\n";
            md << "Pixels with a true surface: " << s.truth_pixels
               << "; compared (a point from every model, " << kEdgeMarginPx
               << " px inside the edge): " << s.common << ".\n\n";
            const bool fitted = s.fit != FitKind::none;
            const bool round = s.fit == FitKind::cylinder || s.fit == FitKind::sphere;
            std::vector<std::string> head{"model", "points"};
            if (fitted)
                head.insert(head.end(), {"fit RMS (mm)", "fit RMS, noise-free (mm)"});
            if (round)
                head.insert(head.end(), {"diameter (mm)", "diameter error (mm)"});
            head.insert(head.end(), {"Z error RMS (mm)", "Z error RMS, noise-free (mm)",
                                     "mean (bias), noise-free (mm)", "std, noise-free (mm)",
                                     "shape RMS, noise-free (mm)"});
            table_row(md, head);
            std::vector<std::string> align{"---"};
            align.resize(head.size(), "---:");
            table_row(md, align);
            for (std::size_t l = 0; l < labels(); ++l) {
                std::vector<std::string> cells{label_title(l), std::to_string(s.points[l])};
                if (fitted)
                    cells.insert(cells.end(),
                                 {fixed_text(s.fit_rms[l], 4), fixed_text(s.fit_rms_clean[l], 4)});
                if (round)
                    cells.insert(cells.end(), {fixed_text(s.diameter[l], 3),
                                               fixed_text(s.diameter_error[l], 3)});
                cells.insert(cells.end(), {fixed_text(s.truth_noisy[l].rms, 4),
                                           fixed_text(s.truth_clean[l].rms, 4),
                                           fixed_text(s.truth_clean[l].mean, 4),
                                           fixed_text(s.truth_clean[l].stddev, 4),
                                           fixed_text(s.shape_clean[l].rms, 4)});
                table_row(md, cells);
            }
            if (!s.fit_note.empty())
                md << "\n" << s.fit_note << "\n";
            md << "\nFigures: ";
            if (fitted)
                md << "`" << s.key << "-fit-histogram.png`, `" << s.key
                   << "-fit-map-<model>.png`, ";
            md << "`truth-" << s.key << "-<model>.png` (noise-free Z error maps).\n\n";
            if (s.key == "relief") {
                row({"SV vs", "pixels", "RMS 3D distance (mm)", "RMS Z difference (mm)",
                     "time, one thread", "speed-up over SV"});
                row({"---", "---:", "---:", "---:", "---:", "---:"});
                for (std::size_t m = 0; m < models_.size(); ++m)
                    row({"hybrid " + models_[m].name, std::to_string(relief_.matched[m]),
                         fixed_text(relief_.distance_rms[m], 4), fixed_text(relief_.dz_rms[m], 4),
                         seconds_text(relief_.seconds[m + 1]),
                         fixed_text(relief_.seconds[0] / relief_.seconds[m + 1], 1) + "x"});
                md << "\nSV itself: " << seconds_text(relief_.seconds[0])
                   << " (Newton along the epipolar line), "
                   << seconds_text(relief_.seconds_sv_plane_iteration)
                   << " (the paper's plane iteration). Figures: `relief-difference-<model>.png`, "
                      "`relief-difference-histogram.png`.\n\n";
            }
        }

        md << "## Experiment 4: N x N windows of the plane scan\n\n";
        md << "SV runs on the cropped camera (principal point shifted), the kernel on the "
              "cropped table; both give the full image's points to "
           << fixed_text(windows_.crop_max_difference_mm * 1e3, 3) << " um ("
           << windows_.crop_mismatched << " pixels with a point in one only).\n\n";
        {
            std::vector<std::string> head{"N", "SV points"};
            for (std::size_t l = 0; l < labels(); ++l)
                head.push_back(label_key(l));
            md << "|";
            for (const std::string& h : head)
                md << " " << h << " |";
            md << "\n|";
            for (std::size_t i = 0; i < head.size(); ++i)
                md << (i == 0 ? " --- |" : " ---: |");
            md << "\n";
            for (std::size_t w = 0; w < windows_.sizes.size(); ++w) {
                md << "| " << windows_.sizes[w] << " | " << windows_.points[w] << " |";
                for (std::size_t l = 0; l < labels(); ++l)
                    md << " " << seconds_text(windows_.seconds[l][w]) << " |";
                md << "\n";
            }
        }
        md << "\nFigure: `windows-timing.png`.\n\n";

        md << "## Targets\n\n";
        row({"target", "met", "numbers"});
        row({"---", "---", "---"});
        for (const PaperTarget& t : targets_)
            row({t.description, t.met ? "yes" : "**no**", t.detail});
        md << "\nAll figures: `figures.csv` (name,value,unit).\n";
        return md.str();
    }

    PaperExperimentResult finish() {
        evaluate_targets();
        PaperExperimentResult result;
        for (const ModelRun& m : models_)
            result.models.push_back(m.name);
        result.default_model = default_model_;
        result.seconds = seconds_since(start_);
        add("run.binning", double(options_.binning), "");
        add("run.sv_calibration_rig_model",
            options_.sv_calibration == SvCalibrationSource::rig_model ? 1.0 : 0.0, "");
        add("run.camera_width", double(rig_.camera_size.width), "px");
        add("run.camera_height", double(rig_.camera_size.height), "px");
        add("run.checkerboard_poses", double(options_.checkerboard_poses), "");
        add("run.plane_poses", double(options_.plane_poses), "");
        add("run.seconds_sessions", seconds_sessions_, "s");
        add("run.seconds_stereo", seconds_stereo_, "s");
        add("run.seconds", result.seconds, "s");
        add("paper.plane.fit_rms.sv", kPaperPlaneSv, "mm");
        add("paper.plane.fit_rms.hybrid", kPaperPlaneHybrid, "mm");
        add("paper.cylinder.fit_rms.sv", kPaperCylinderSv, "mm");
        add("paper.cylinder.fit_rms.hybrid", kPaperCylinderHybrid, "mm");
        add("paper.relief.distance_rms", kPaperReliefDistance, "mm");
        add("paper.relief.time.sv", kPaperReliefSvSeconds, "s");
        add("paper.relief.time.hybrid", kPaperReliefHybridSeconds, "s");
        add("paper.relief.points", kPaperReliefPoints, "");
        result.summary_markdown = summary();
        write_file_synced(report_ / "summary.md", result.summary_markdown);
        write_file_synced(report_ / "figures.csv", figures_csv(figures_));
        result.figures = figures_;
        result.targets = targets_;
        return result;
    }

    fs::path folder_;
    PaperExperimentOptions options_;
    Clock::time_point start_;
    fs::path report_;
    sim::Rig rig_, clean_rig_;
    Sequence scan_sequence_;
    DecodeOptions decode_options_;
    std::string default_model_;
    fs::path checkerboard_session_, plane_session_;
    StereoCalibration calibration_;
    std::uint64_t calibration_hash_ = 0;
    int calibration_poses_ = 0;
    std::unique_ptr<SvReconstructor> sv_;
    std::vector<ModelRun> models_;
    std::vector<ScanSummary> scans_;
    ReliefSummary relief_;
    WindowSummary windows_;
    std::vector<Figure> figures_;
    std::vector<PaperTarget> targets_;
    double seconds_sessions_ = 0, seconds_stereo_ = 0;
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
