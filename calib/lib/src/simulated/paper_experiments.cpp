// The paper's experiments on the virtual scanner (see paper_experiments.hpp):
// the run's order, the calibration sessions, the calibrations and their
// tables, and the figures file (the stages are declared in paper_stages.hpp).
// The scans are in paper_scans.cpp, the timings in paper_timing.cpp, the
// report and the targets in paper_report.cpp.

#include "fpp/calib/paper_experiments.hpp"
#include "fpp/calib/simulated_rig.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/calib/calibration_report.hpp"
#include "fpp/calib/hybrid_calibrate.hpp"
#include "fpp/calib/hybrid_report.hpp"
#include "fpp/calib/plots.hpp"
#include "fpp/calib/report_folder.hpp"
#include "fpp/calib/stereo_session.hpp"
#include "fpp/coefficient_table.hpp"
#include "fpp/enum_names.hpp"
#include "fpp/error.hpp"
#include "fpp/fnv1a.hpp"
#include "fpp/sequences.hpp"
#include "fpp/simulator/session.hpp"
#include "paper_stages.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace fpp::calib {

namespace fs = std::filesystem;

namespace paper {

namespace {

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

} // namespace

Run::Run(const fs::path& folder, const PaperExperimentOptions& options)
    : folder_(folder), start_(Clock::now()) {
    record_.options = options;
}

PaperExperimentResult Run::run() {
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

void Run::setup_rig() {
    const fs::path rig_path = options().rig.empty() ? sim::lens_defects_rig_path() : options().rig;
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
        std::to_string(rig().camera_size.width) + " x " + std::to_string(rig().camera_size.height) +
        " (binning " + std::to_string(options().binning) + "), projector " +
        std::to_string(rig().projector_size.width) + " x " +
        std::to_string(rig().projector_size.height));
    // The reference: the rig's own model, defects and all.
    exact_calibration_ = calibration_from_rig(rig());
    add_sv_method("exact", "SV with the rig's exact model (reference)", Procedure::reference,
                  exact_calibration_);
}

void Run::add_sv_method(std::string key, std::string title, Procedure procedure,
                        const StereoCalibration& calibration) {
    SvOptions options_sv;
    options_sv.threads = options().threads;
    Method sv;
    sv.key = std::move(key);
    sv.title = std::move(title);
    sv.procedure = procedure;
    sv.calibration = &calibration;
    sv.sv = std::make_unique<SvReconstructor>(calibration, options_sv);
    methods().push_back(std::move(sv));
}

FrameTurn Run::frame_turn(const StereoCalibration& calibration, const std::string& figure) {
    const FrameTurn turn = camera_frame_turn(calibration, rig().camera);
    add(figure, 1000 * turn.angle_rad, "mrad");
    return turn;
}

void Run::write_session(const fs::path& folder, const sim::SessionOptions& session,
                        const Sequence& sequence, const std::string& what) {
    say("simulating " + what + ": " + std::to_string(session.poses) + " poses (" +
        std::to_string(frame_count(sequence)) + " frames each)");
    sim::write_session(folder, rig(), sequence, session, [&](int done, int total) {
        say("  pose " + std::to_string(done) + "/" + std::to_string(total));
    });
}

void Run::simulate_sessions() {
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

StereoCalibration Run::calibrate_stereo(const fs::path& session, const StereoSessionOptions& so,
                                        const std::string& report, StereoSummary& summary) {
    const auto start = Clock::now();
    const SessionResult result = calibrate_session(session, so);
    summary.seconds = seconds_since(start); // the calibration, not its report
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
    summary.origin = c.origin;
    say("  camera RMS " + fixed_text(c.camera_rms, 4) + " px, projector RMS " +
        fixed_text(c.projector_rms, 4) + " px, " + std::to_string(summary.poses) + " poses, " +
        fixed_text(summary.seconds, 1) + " s");
    return c;
}

std::uint64_t Run::save(const StereoCalibration& c, const std::string& name) {
    const std::string text = calibration_to_yaml(c);
    write_file_synced(folder_ / name, text);
    return fnv1a64(text.data(), text.size());
}

HybridOptions Run::hybrid_options() const {
    HybridOptions ho;
    ho.threads = options().threads;
    ho.decode.threads = options().threads;
    ho.sv.threads = options().threads;
    ho.progress = indented();
    return ho;
}

void Run::add_tables(const std::vector<HybridResult>& results, Procedure procedure,
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
            " pixels modelled, median Z fit RMS " + fixed_text(m.fit_rms_z_median, 4) + " mm");
        methods().push_back(std::move(m));
    }
}

void Run::calibrate_paper_procedure() {
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
        so.decode.threads = options().threads;
        so.compare_corner_methods = true; // its report compares them
        so.stereo.procedure = StereoProcedure::joint;
        so.stereo.camera_grid = {};
        so.stereo.projector_grid = {};
        so.progress = indented();
        paper_calibration_ =
            calibrate_stereo(paper_board_session_, so, "stereo-report-paper", record_.paper_stereo);
    }
    const std::uint64_t hash = save(paper_calibration_, "calib-paper.yaml");
    record_.paper_turn = frame_turn(paper_calibration_, "calibration.paper.frame_turn_mrad");
    add_sv_method("sv-paper", "SV, the paper's calibration", Procedure::paper, paper_calibration_);
    say("the paper's hybrid tables from the flat boards, every model");
    add_tables(calibrate_hybrid(plane_session_, paper_calibration_, hash, hybrid_options(),
                                available_table_models()),
               Procedure::paper, "paper", "paper's procedure");
}

void Run::calibrate_our_procedures() {
    say("our stereo calibration from the checkerboard session (camera first, correction "
        "grids)");
    StereoSessionOptions so;
    so.decode.threads = options().threads;
    // Timed as a user's calibration (the reports apart): the corner
    // methods are compared in the paper's procedure's report only.
    so.progress = indented();
    // The tables' view of each board, kept as the stereo calibration reads
    // the session (as `fpp-calib calibrate` does): the tables read nothing.
    HybridOptions ho = hybrid_options();
    std::vector<BoardView> views;
    keep_board_views(board_session_, ho, so, views);
    our_calibration_ = calibrate_stereo(board_session_, so, "stereo-report", record_.our_stereo);
    const std::uint64_t hash = save(our_calibration_, "calib.yaml");
    record_.our_turn = frame_turn(our_calibration_, "calibration.boards.frame_turn_mrad");
    add_sv_method("sv", "SV, our calibration", Procedure::boards, our_calibration_);

    say("our hybrid tables from the same checkerboard session, every model");
    const auto hybrid_start = Clock::now();
    std::vector<HybridResult> boards = calibrate_hybrid(board_session_, our_calibration_, hash, ho,
                                                        available_table_models(), views);
    record_.seconds_boards_hybrid = seconds_since(hybrid_start);
    add("calibration.boards.seconds_stereo", record_.our_stereo.seconds, "s");
    add("calibration.boards.seconds_hybrid", record_.seconds_boards_hybrid, "s");
    add("calibration.boards.seconds", record_.our_stereo.seconds + record_.seconds_boards_hybrid,
        "s");
    const std::size_t first = count();
    add_tables(boards, Procedure::boards, "boards", "our procedure");
    for (std::size_t m = first; m < count(); ++m) {
        methods()[m].is_default = methods()[m].model == HybridOptions{}.model;
        // A model that keeps to the boards' depth range reaches fewer depths.
        methods()[m].in_common = ho.depth_margin_mm(methods()[m].model) > 0;
    }
    // The same session's tables fitted to the boards' samples alone,
    // and to the stereo model's alone, for comparison.
    for (const HybridSamples samples : {HybridSamples::boards, HybridSamples::model}) {
        ho.samples = samples;
        const std::string key = samples == HybridSamples::boards ? "boards-only" : "model-only";
        say("our tables fitted to " + std::string(to_string(samples)) + " samples only");
        add_tables(calibrate_hybrid(board_session_, our_calibration_, hash, ho,
                                    {HybridOptions{}.model}, views),
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

PaperExperimentResult Run::finish() {
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
    for (const auto& [key, s] :
         {std::pair{"paper", &record_.paper_stereo}, std::pair{"boards", &record_.our_stereo}}) {
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

} // namespace paper

constexpr EnumName<SvCalibrationSource> kSvCalibrationSourceNames[] = {
    {SvCalibrationSource::checkerboard, "checkerboard"},
    {SvCalibrationSource::rig_model, "rig-model"},
};

const char* to_string(SvCalibrationSource source) {
    return name_of(kSvCalibrationSourceNames, source, "checkerboard");
}

SvCalibrationSource parse_sv_calibration_source(const std::string& name) {
    return parse_name(kSvCalibrationSourceNames, "SV calibration source", name);
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
        paper::Run run(temp, options);
        result = run.run();
    });
    if (options.progress)
        options.progress("wrote " + out.string());
    return result;
}

} // namespace fpp::calib
