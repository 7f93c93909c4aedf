// fpp-calib reconstruct CAPTURE_1 --second-capture CAPTURE_2
//                       (--pair-calibration FILE | --calib FILE) --out cloud.ply [--xyz xyz.tiff]
//
// Two-camera scanning: both cameras recorded the same fringe sequence; each
// capture is decoded to the projector coordinate, the two are matched along
// rectified rows and triangulated camera to camera with a camera-camera
// calibration (OpenCV stereo YAML, Bouguet or MATLAB text; load_camera_pair),
// so the projector needs no calibration. Cloud: camera 1's frame, mm,
// organised on camera 1's pixels. Outputs are written only when everything
// succeeded and at least one point was made.

#include "cmd_reconstruct_pair.hpp"

#include "cli_util.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/calib/camera_pair.hpp"
#include "fpp/calib/two_camera.hpp"
#include "fpp/capture_set.hpp"
#include "fpp/error.hpp"
#include "fpp/image_io.hpp"
#include "fpp/point_cloud.hpp"

#include <cmath>
#include <iostream>
#include <sstream>
#include <stdexcept>

namespace fpp::calib {

namespace {

namespace fs = std::filesystem;

// Sizes the calibration records must be the captures'; missing ones are taken
// from the captures (with a note).
void settle_sizes(CameraPairCalibration& pair, const fs::path& file, const CaptureSet& first,
                  const CaptureSet& second) {
    struct Item {
        Size& size;
        Size capture;
        const char* which;
        const fs::path& folder;
    };
    for (Item item : {Item{pair.first_size, first.manifest.camera, "first", first.folder},
                      Item{pair.second_size, second.manifest.camera, "second", second.folder}}) {
        const std::string field = std::string("image size of the ") + item.which + " camera";
        if (item.size.width <= 0 || item.size.height <= 0) {
            std::cerr << "note: " << file.string() << " records no " << field
                      << "; using the capture's " << size_text(item.capture) << "\n";
            item.size = item.capture;
        } else if (item.size != item.capture) {
            throw InputError(file, field,
                             "the calibration is for " + size_text(item.size) + ", but " +
                                 (item.folder / "capture.yaml").string() + " has " +
                                 size_text(item.capture) + " frames");
        }
    }
}

DecodeResult decode_capture(const CaptureSet& capture, const DecodeOptions& options) {
    const fs::path manifest = capture.folder / "capture.yaml";
    const DecodeResult decoded = decode(capture, options); // InputError naming the field
    if (decoded.proj_x.empty())
        throw InputError(manifest, "sequence",
                         "codes no projector column (x): two-camera matching needs it");
    return decoded;
}

// The arguments, checked before anything is read.
void check_pair_arguments(const ReconstructPairArgs& args) {
    args.decode.validate();
    if (!args.table.empty())
        throw InputError("command line", "--table",
                         "a coefficient table models one camera and the projector; two-camera "
                         "scanning needs a camera-camera calibration (--pair-calibration)");
    if (args.calibration.empty())
        throw InputError("command line", "--pair-calibration",
                         "--second-capture needs the camera-camera calibration of the two "
                         "cameras (--pair-calibration or --calib)");
    if (args.second_capture.empty())
        throw InputError("command line", "--second-capture",
                         "a camera-camera calibration needs the second camera's capture set");
    const fs::path out = args.out, xyz_out = args.xyz;
    check_output_path(out, "--out");
    if (!xyz_out.empty()) {
        check_output_path(xyz_out, "--xyz");
        if (fs::weakly_canonical(xyz_out) == fs::weakly_canonical(out))
            throw InputError(xyz_out, "--xyz", "same path as --out");
    }
}

} // namespace

int run_reconstruct_pair(const ReconstructPairArgs& args) {
    check_pair_arguments(args);
    const fs::path out = args.out, xyz_out = args.xyz;

    const fs::path calibration_path = args.calibration;
    CameraPairCalibration pair = load_camera_pair(calibration_path);
    std::cerr << "camera pair: " << pair.origin << "\n";
    std::cerr << "reading " << args.first_capture << " and " << args.second_capture << "\n";
    const CaptureSet first = read_capture_set(args.first_capture);
    const CaptureSet second = read_capture_set(args.second_capture);
    const fs::path second_manifest = second.folder / "capture.yaml";
    if (!(second.manifest.sequence == first.manifest.sequence))
        throw InputError(second_manifest, "sequence",
                         "differs from " + (first.folder / "capture.yaml").string() +
                             "'s: both cameras must record the same pattern sequence");
    if (second.manifest.projector != first.manifest.projector)
        throw InputError(second_manifest, "projector",
                         size_text(second.manifest.projector) + ", but " +
                             (first.folder / "capture.yaml").string() + " says " +
                             size_text(first.manifest.projector));
    settle_sizes(pair, calibration_path, first, second);

    std::unique_ptr<TwoCameraReconstructor> reconstructor;
    try {
        reconstructor = std::make_unique<TwoCameraReconstructor>(pair);
    } catch (const std::invalid_argument& e) {
        throw InputError(calibration_path, "R, T", e.what());
    }

    Stopwatch decode_watch;
    DecodeResult decoded_first = decode_capture(first, args.decode);
    DecodeResult decoded_second = decode_capture(second, args.decode);
    const double decode_seconds = decode_watch.seconds();
    const bool both_y = !decoded_first.proj_y.empty() && !decoded_second.proj_y.empty();
    if (args.axes == "xy" && !both_y)
        throw InputError(first.folder / "capture.yaml", "sequence",
                         "--axes xy needs the projector row in both captures (use --axes x)");
    if (args.axes == "x") {
        decoded_first.proj_y = {};
        decoded_second.proj_y = {};
    }

    Stopwatch match_watch;
    PointCloud cloud;
    const TwoCameraStats stats = reconstructor->reconstruct(decoded_first, decoded_second, cloud);
    const double match_seconds = match_watch.seconds();
    std::ostringstream counts;
    counts << "camera 1 decoded " << stats.first_valid << " pixels, camera 2 " << stats.second_valid
           << "; no point: outside camera 2's rows " << stats.outside << ", no match "
           << stats.no_match << ", ambiguous " << stats.ambiguous << ", projector row disagrees "
           << stats.v_disagree << ", rows disagree " << stats.row_mismatch
           << ", behind the cameras " << stats.behind << ", hidden from camera 2 "
           << stats.occluded;
    if (stats.points == 0)
        throw InputError(second_manifest, "frames",
                         "no pixel of the two captures matched (" + counts.str() +
                             "): do the captures and " + calibration_path.string() +
                             " belong to the same two cameras, first and second in this order?");

    const std::vector<std::string> comments = {
        "fpp-calib reconstruct: two cameras (camera-camera triangulation), camera 1 frame, mm",
        "captures " + fs::path(args.first_capture).filename().string() + " and " +
            fs::path(args.second_capture).filename().string() + ", calibration " +
            calibration_path.filename().string() + ", axes " +
            (both_y && args.axes != "x" ? "xy" : "x"),
        "quality: fringe modulation (DN); intensity: mean intensity (DN); pixel: row * "
        "organised_width + column"};
    Stopwatch write_watch;
    write_atomically(out, [&](const fs::path& temp) {
        write_ply_synced(temp, cloud, comments);
        if (!xyz_out.empty())
            write_tiff(xyz_out, cloud.xyz);
    });
    const double write_seconds = write_watch.seconds();

    std::ostringstream report;
    report << "two cameras: " << pair.summary() << "\n"
           << "matched along rectified rows"
           << (both_y && args.axes != "x" ? ", projector row checked" : "") << "\n"
           << "points: " << stats.points << " of " << stats.first_valid
           << " decoded camera-1 pixels (" << 100.0 * stats.coverage() << " %); " << counts.str()
           << "\n"
           << truth_comparison(cloud, first) << "time: decode " << decode_seconds
           << " s, matching and triangulation " << match_seconds << " s, writing " << write_seconds
           << " s\n"
           << "wrote " << out.string() << (xyz_out.empty() ? "" : " and " + xyz_out.string())
           << "\n";
    std::cout << report.str();
    return 0;
}

} // namespace fpp::calib
