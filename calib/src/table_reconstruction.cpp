#include "table_reconstruction.hpp"

#include "cli_util.hpp"
#include "decode_outputs.hpp"

#include "fpp/decode_consistency.hpp"
#include "fpp/decode_diagnosis.hpp"
#include "fpp/error.hpp"
#include "fpp/parallel.hpp"

#include <algorithm>
#include <iostream>
#include <variant>

namespace fpp::calib {

namespace {

// True when a block of `sequence` gives the decoder a projector coordinate
// along `axis`: a phase or micro phase block (to a fraction of a pixel), or a
// code block (a code-only sequence: its code step's centre; with a phase
// block it only indexes the periods). A centerline is a cue, not a coordinate.
bool sequence_codes_axis(const Sequence& sequence, Axis axis) {
    return std::any_of(sequence.begin(), sequence.end(), [&](const PatternBlock& b) {
        if (const auto* phase = std::get_if<PhaseBlock>(&b))
            return phase->axis == axis;
        if (const auto* micro = std::get_if<MicroPhaseBlock>(&b))
            return micro->axis == axis;
        if (const auto* code = std::get_if<GrayBlock>(&b))
            return code->axis == axis;
        return false;
    });
}

} // namespace

void check_capture_axes(const CaptureSet& capture, ReconstructAxes requested) {
    const std::filesystem::path manifest_path = capture.folder / "capture.yaml";
    const bool has_x = sequence_codes_axis(capture.manifest.sequence, Axis::x);
    const bool has_y = sequence_codes_axis(capture.manifest.sequence, Axis::y);
    if (!has_x)
        throw InputError(manifest_path, "sequence",
                         "no phase, micro phase or code block along x: reconstruction needs the "
                         "projector column");
    if (requested == ReconstructAxes::xy && !has_y)
        throw InputError(manifest_path, "sequence",
                         "--axes xy needs the projector row, but the capture has no phase, micro "
                         "phase or code block along y (use --axes x)");
}

void check_table_fits_capture(const CoefficientTable& table,
                              const std::filesystem::path& table_path, const CaptureSet& capture) {
    if (table.info().camera != capture.manifest.camera)
        throw InputError(capture.folder / "capture.yaml", "camera",
                         "the capture's frames are " + size_text(capture.manifest.camera) +
                             ", but the table " + table_path.string() + " is for a " +
                             size_text(table.info().camera) +
                             " camera: a capture of another camera or binning");
    if (table.info().phase_axis != Axis::x)
        throw InputError(table_path, "phase_axis", "maps the projector row; expected x");
    if (!(table.info().projector == capture.manifest.projector))
        throw InputError(table_path, "projector_size",
                         "the table is for a " + size_text(table.info().projector) +
                             " projector, the capture's is " +
                             size_text(capture.manifest.projector));
}

CoefficientTable load_table_for_capture(const std::filesystem::path& table_path,
                                        const CaptureSet& capture) {
    CoefficientTable table = load_table(table_path, &capture.manifest.camera);
    check_table_fits_capture(table, table_path, capture);
    return table;
}

std::optional<DecodedScan> decode_and_smooth(const CaptureSet& capture,
                                             const DecodeOptions& decode_options,
                                             const CoordinateFilterOptions& smooth,
                                             bool accept_inconsistent) {
    Stopwatch decode_watch;
    DecodeResult decoded = decode(capture, decode_options); // InputError naming the field
    const double decode_seconds = decode_watch.seconds();
    // A failed decode gives no cloud: the likely cause instead (fpp/decode_diagnosis.hpp).
    const DecodeStatistics decode_stats = decode_statistics(decoded, frames_full_scale(capture));
    const DecodeDiagnosis diagnosis =
        diagnose_decode(capture, decoded, decode_stats, decode_options);
    if (diagnosis.failed) {
        std::cerr << "fpp-calib: error: " << capture.folder.string() << ": " << diagnosis.message
                  << "\nno point cloud written\n";
        return std::nullopt;
    }
    if (!diagnosis.message.empty())
        std::cerr << "fpp-calib: warning: " << diagnosis.message << "\n";
    const DecodeConsistency consistency =
        check_decode_consistency(decoded, capture.manifest.sequence);
    if (consistency.inconsistent) {
        const std::string why =
            capture.folder.string() + ": the decode is inconsistent: " + consistency.message;
        if (!accept_inconsistent)
            throw DecodeRefused(kExitInconsistent,
                                why + "\nno point cloud written (--accept-inconsistent to "
                                      "write it all the same)");
        std::cerr << "fpp-calib: warning: " << why << "\n";
    }
    Stopwatch smooth_watch;
    Image<float> scratch;
    const CoordinateFilterReport smoothing = smooth_coordinates(decoded, smooth, scratch);
    const double smooth_seconds = smooth_watch.seconds();
    return DecodedScan{std::move(decoded), decode_stats, smoothing, decode_seconds, smooth_seconds};
}

TableCloud apply_table_to_scan(const CoefficientTable& table, const DecodeResult& decoded,
                               int threads) {
    TableCloud made;
    ThreadPool pool(threads);
    Stopwatch watch;
    made.stats = apply_table(table, decoded.proj_x, made.cloud, &pool);
    made.seconds = watch.seconds();
    made.cloud.quality = decoded.modulation;
    made.cloud.intensity = decoded.mean;
    return made;
}

} // namespace fpp::calib
