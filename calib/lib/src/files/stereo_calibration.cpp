// Stereo calibration files: ours (OpenCV FileStorage YAML) and the foreign
// formats of SLStudio and SLMaster. See fpp/calib/stereo_calibration.hpp.

#include "fpp/calib/stereo_calibration.hpp"

#include "calibration_reader.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/enum_names.hpp"
#include "fpp/error.hpp"
#include "fpp/yaml_fields.hpp"

#include <opencv2/core.hpp>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace fpp::calib {

namespace fs = std::filesystem;

Vec3 StereoCalibration::projector_centre() const {
    const Vec3 rt = mul(transpose(R), T);
    return {-rt[0], -rt[1], -rt[2]};
}

Vec2 StereoCalibration::camera_pixel(const Vec3& camera_point) const {
    return camera_correction.apply(camera.project(camera_point));
}

Vec2 StereoCalibration::projector_pixel(const Vec3& camera_point) const {
    const Vec3 p = mul(R, camera_point);
    return projector_correction.apply(projector.project({p[0] + T[0], p[1] + T[1], p[2] + T[2]}));
}

bool StereoCalibration::camera_ray(Vec2 pixel, Vec2& normalised) const {
    Vec2 model{};
    return camera_correction.remove(pixel, model) && camera.pixel_to_normalised(model, normalised);
}

bool StereoCalibration::sizes_known() const {
    return camera_size.width > 0 && camera_size.height > 0 && projector_size.width > 0 &&
           projector_size.height > 0;
}

CameraPairFileError::CameraPairFileError(const fs::path& file, CameraPairCalibration pair_)
    : InputError(file, "",
                 "a camera-camera calibration of " + pair_.summary() +
                     ", not a camera-projector calibration: it allows two-camera scanning "
                     "(fpp-calib reconstruct with two capture sets, one per camera, and this "
                     "file), not a camera-projector table (the projector is not calibrated)"),
      pair(std::move(pair_)) {}

constexpr EnumName<CalibrationFormat> kCalibrationFormatNames[] = {
    {CalibrationFormat::automatic, "auto"},
    {CalibrationFormat::fpp, "fpp"},
    {CalibrationFormat::slstudio, "slstudio"},
    {CalibrationFormat::slmaster, "slmaster"},
    {CalibrationFormat::opencv_stereo, "opencv-stereo"},
    {CalibrationFormat::bouguet, "bouguet"},
    {CalibrationFormat::matlab, "matlab"},
};

CalibrationFormat parse_calibration_format(const std::string& name) {
    return parse_name(kCalibrationFormatNames, "calibration format", name);
}

const char* to_string(CalibrationFormat format) {
    return name_of(kCalibrationFormatNames, format);
}

namespace {

using detail::KeySet;
using detail::Reader;

constexpr KeySet kFppKeys{
    "camera_matrix", "camera_distortion", "projector_matrix", "projector_distortion", "R", "T"};
constexpr KeySet kSlStudioKeys{"Kc", "kc", "Kp", "kp", "Rp", "Tp"};
constexpr KeySet kSlMasterKeys{"M1", "D1", "M4", "D4", "Rlp", "Tlp"};

// trueness: { length_mm: L, depth_mm: [near, middle, far],
//             along_depth_mm: [3], across_mm: [3] }
Trueness read_trueness(const Reader& in) {
    const cv::FileNode node = in.require("trueness");
    if (!node.isMap())
        in.fail("trueness", "expected a map");
    const auto field = [&](const char* name) {
        const cv::FileNode n = node[name];
        if (n.empty())
            in.fail(std::string("trueness.") + name, "missing");
        return n;
    };
    Trueness t;
    t.length_mm = in.number(field("length_mm"), "trueness.length_mm");
    if (!(t.length_mm > 0 && std::isfinite(t.length_mm)))
        in.fail("trueness.length_mm", "must be a positive length (mm)");
    const auto three = [&](const char* name, auto member, bool positive) {
        const cv::FileNode n = field(name);
        const std::string key = std::string("trueness.") + name;
        if (!n.isSeq() || n.size() != 3)
            in.fail(key, "expected a list of 3 numbers (near, middle, far)");
        for (int k = 0; k < 3; ++k) {
            const std::string element = key + "[" + std::to_string(k) + "]";
            const double v = in.number(n[k], element); // refuses a non-finite value
            if (v < 0 || (positive && v == 0))
                in.fail(element, positive ? "must be positive (mm)" : "must not be negative (mm)");
            t.at[std::size_t(k)].*member = v;
        }
    };
    three("depth_mm", &LengthSigma::depth_mm, true);
    three("along_depth_mm", &LengthSigma::along_depth_mm, false);
    three("across_mm", &LengthSigma::across_mm, false);
    return t;
}

// depth_correction: { focal_scale: s, before_ppm: b, before_sigma_ppm: bs,
//                     after_ppm: a, after_sigma_ppm: as, positions: n, artefact: name }
DepthCorrection read_depth_correction(const Reader& in) {
    const cv::FileNode node = in.require("depth_correction");
    if (!node.isMap())
        in.fail("depth_correction", "expected a map");
    const auto field = [&](const char* name) {
        const cv::FileNode n = node[name];
        if (n.empty())
            in.fail(std::string("depth_correction.") + name, "missing");
        return n;
    };
    const auto number = [&](const char* name) {
        return in.number(field(name), std::string("depth_correction.") + name);
    };
    DepthCorrection d;
    d.focal_scale = number("focal_scale");
    // A depth scale off by more than 1 % is no calibration's; correct refuses
    // anything beyond 5 sigma of the predicted trueness long before.
    if (!(std::abs(d.focal_scale - 1) < 0.01))
        in.fail("depth_correction.focal_scale", "must be within 1 % of 1");
    d.before_ppm = number("before_ppm");
    d.before_sigma_ppm = number("before_sigma_ppm");
    d.after_ppm = number("after_ppm");
    d.after_sigma_ppm = number("after_sigma_ppm");
    if (d.before_sigma_ppm < 0 || d.after_sigma_ppm < 0)
        in.fail(d.before_sigma_ppm < 0 ? "depth_correction.before_sigma_ppm"
                                       : "depth_correction.after_sigma_ppm",
                "must not be negative");
    d.positions = in.integer(field("positions"), "depth_correction.positions");
    if (d.positions < 2)
        in.fail("depth_correction.positions", "must be at least 2 (a fit needs two positions)");
    d.artefact = in.text(field("artefact"), "depth_correction.artefact");
    return d;
}

StereoCalibration read_fpp(const Reader& in) {
    StereoCalibration c;
    if (in.has("format")) {
        const std::string format = in.text(in.require("format"), "format");
        if (format != kStereoFormat)
            in.fail("format", "unknown format '" + format + "' (expected " + kStereoFormat + ")");
    }
    c.camera_size = in.size("camera_size");
    c.projector_size = in.size("projector_size");
    in.geometry(kFppKeys, c);
    c.camera_correction = in.correction("camera_correction", c.camera_size);
    c.projector_correction = in.correction("projector_correction", c.projector_size);
    if (in.has("board_square_size")) {
        c.board_square_size = in.number("board_square_size");
        if (!(c.board_square_size > 0))
            in.fail("board_square_size", "must be positive (mm)");
    }
    c.camera_rms = in.number("camera_rms");
    c.projector_rms = in.number("projector_rms");
    const cv::FileNode poses = in.require("poses");
    if (!poses.isSeq() && !(poses.isNone() || poses.empty()))
        in.fail("poses", "expected a list");
    for (std::size_t i = 0; i < poses.size(); ++i) {
        const std::string key = "poses[" + std::to_string(i) + "]";
        const cv::FileNode p = poses[static_cast<int>(i)];
        if (!p.isMap())
            in.fail(key, "expected a map");
        auto field = [&](const char* name) {
            const cv::FileNode n = p[name];
            if (n.empty())
                in.fail(key + "." + name, "missing");
            return n;
        };
        PoseResidual r;
        r.name = in.text(field("name"), key + ".name");
        r.camera_rms = in.number(field("camera_rms"), key + ".camera_rms");
        r.projector_rms = in.number(field("projector_rms"), key + ".projector_rms");
        r.corners = in.integer(field("corners"), key + ".corners");
        const int used = in.integer(field("used"), key + ".used");
        if (used != 0 && used != 1)
            in.fail(key + ".used", "expected 0 or 1");
        r.used = used == 1;
        if (!p["note"].empty())
            r.note = in.text(p["note"], key + ".note");
        c.poses.push_back(std::move(r));
    }
    if (in.has("trueness"))
        c.trueness = read_trueness(in);
    if (in.has("depth_correction"))
        c.depth_correction = read_depth_correction(in);
    if (in.has("origin"))
        c.origin = in.text(in.require("origin"), "origin");
    return c;
}

StereoCalibration read_slstudio(const Reader& in) {
    StereoCalibration c;
    in.geometry(kSlStudioKeys, c);
    c.camera_size = {in.dimension(in.require("frameWidth"), "frameWidth"),
                     in.dimension(in.require("frameHeight"), "frameHeight")};
    c.projector_size = {in.dimension(in.require("screenResX"), "screenResX"),
                        in.dimension(in.require("screenResY"), "screenResY")};
    if (in.has("cam_error"))
        c.camera_rms = in.number("cam_error");
    if (in.has("proj_error"))
        c.projector_rms = in.number("proj_error");
    return c;
}

StereoCalibration read_slmaster(const Reader& in) {
    StereoCalibration c;
    in.geometry(kSlMasterKeys, c);
    return c; // sizes unknown: supplied by the user
}

} // namespace

namespace {

// A two-device file named explicitly: its first camera is the camera, its
// second device the projector (sizes unknown, supplied by the user).
StereoCalibration from_pair(const CameraPairCalibration& pair) {
    StereoCalibration c;
    c.camera = pair.first;
    c.projector = pair.second;
    c.camera_size = pair.first_size;
    c.R = pair.R;
    c.T = pair.T;
    c.origin = pair.origin + ", second device read as the projector";
    return c;
}

CameraPairFormat pair_format(CalibrationFormat format) {
    if (format == CalibrationFormat::opencv_stereo)
        return CameraPairFormat::opencv_stereo;
    return format == CalibrationFormat::bouguet ? CameraPairFormat::bouguet
                                                : CameraPairFormat::matlab;
}

} // namespace

StereoCalibration parse_calibration(const std::string& text, const fs::path& origin,
                                    CalibrationFormat format) {
    if (text.find_first_not_of(" \t\r\n") == std::string::npos)
        throw InputError(origin, "", "empty calibration file");
    if (format == CalibrationFormat::opencv_stereo || format == CalibrationFormat::bouguet ||
        format == CalibrationFormat::matlab) {
        StereoCalibration c = from_pair(parse_camera_pair(text, origin, pair_format(format)));
        c.format = format;
        return c;
    }
    // Camera-camera files (OpenCV stereo YAML, SLMaster's binocular caliInfo.yml
    // without M4, Bouguet's or MATLAB's stereo text): say what they are.
    if (format == CalibrationFormat::automatic && looks_like_camera_pair(text))
        throw CameraPairFileError(origin, parse_camera_pair(text, origin));
    const cv::FileStorage storage = detail::open_file_storage(text, origin);
    const Reader in(storage.root(), origin);

    if (format == CalibrationFormat::automatic) {
        if (in.has("camera_matrix"))
            format = CalibrationFormat::fpp;
        else if (in.has("Kc") || in.has("Kp"))
            format = CalibrationFormat::slstudio;
        else if (in.has("M1") || in.has("M4"))
            format = CalibrationFormat::slmaster;
        else
            throw InputError(origin, "",
                             "not a recognised calibration: expected the keys of fpp-calib "
                             "(camera_matrix, projector_matrix, R, T, ...), SLStudio's "
                             "calibration.xml (Kc, Kp, Rp, Tp, ...) or SLMaster's caliInfo.yml "
                             "(M1, M4, Rlp, Tlp, ...); camera-camera files (OpenCV's M1 D1 M2 "
                             "D2 R T, Bouguet's or MATLAB's stereo text) are recognised too");
    }
    StereoCalibration c;
    try {
        switch (format) {
        case CalibrationFormat::fpp:
            c = read_fpp(in);
            break;
        case CalibrationFormat::slstudio:
            c = read_slstudio(in);
            break;
        case CalibrationFormat::slmaster:
            c = read_slmaster(in);
            break;
        case CalibrationFormat::automatic:
        case CalibrationFormat::opencv_stereo:
        case CalibrationFormat::bouguet:
        case CalibrationFormat::matlab:
            break;
        }
    } catch (const cv::Exception& e) { // a node of an unexpected kind deep inside
        throw InputError(origin, "", std::string("malformed calibration file: ") + e.msg);
    }
    c.format = format;
    if (c.origin.empty())
        c.origin = origin.string() + " (" + to_string(format) + " format)";
    return c;
}

StereoCalibration load_calibration(const fs::path& path, CalibrationFormat format) {
    return parse_calibration(yaml_fields::read_text_file(path), path, format);
}

namespace {

void require_finite(double v, const char* what) {
    if (!std::isfinite(v))
        throw std::invalid_argument(std::string("calibration: ") + what + " is not finite");
}

void check_representable(const LensModel& lens, const char* which) {
    for (double v : {lens.fu, lens.fv, lens.cu, lens.cv, lens.skew, lens.k1, lens.k2, lens.k3,
                     lens.p1, lens.p2})
        require_finite(v, which);
    if (lens.has_unmodelled_terms())
        throw std::invalid_argument(std::string("calibration: the ") + which +
                                    " lens has k4, thin-prism or trefoil terms, which the "
                                    "file's 5-coefficient model cannot hold");
}

cv::Mat camera_matrix(const LensModel& l) {
    return (cv::Mat_<double>(3, 3) << l.fu, l.skew, l.cu, 0.0, l.fv, l.cv, 0.0, 0.0, 1.0);
}

cv::Mat distortion(const LensModel& l) {
    return (cv::Mat_<double>(1, 5) << l.k1, l.k2, l.p1, l.p2, l.k3);
}

void write_correction(cv::FileStorage& out, const std::string& prefix, const CorrectionGrid& grid,
                      Size image) {
    if (grid.empty())
        return;
    if (!(grid.image() == image))
        throw std::invalid_argument("calibration: the " + prefix +
                                    " grid is not over the device's image");
    cv::Mat du(grid.rows(), grid.columns(), CV_64F), dv(grid.rows(), grid.columns(), CV_64F);
    for (int j = 0; j < grid.rows(); ++j)
        for (int i = 0; i < grid.columns(); ++i) {
            require_finite(grid.at(i, j)[0], "a correction control point");
            require_finite(grid.at(i, j)[1], "a correction control point");
            du.at<double>(j, i) = grid.at(i, j)[0];
            dv.at<double>(j, i) = grid.at(i, j)[1];
        }
    out << prefix + "_du" << du;
    out << prefix + "_dv" << dv;
}

} // namespace

std::string calibration_to_yaml(const StereoCalibration& c) {
    if (!c.sizes_known())
        throw std::invalid_argument("calibration: camera and projector sizes must be known");
    check_representable(c.camera, "camera");
    check_representable(c.projector, "projector");
    for (double v : c.R)
        require_finite(v, "R");
    for (double v : c.T)
        require_finite(v, "T");
    require_finite(c.camera_rms, "camera_rms");
    require_finite(c.projector_rms, "projector_rms");

    cv::FileStorage out(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY |
                                     cv::FileStorage::FORMAT_YAML);
    out.writeComment(" Stereo calibration of a camera-projector pair (fpp-calib). Camera frame, "
                     "mm; X_p = R X_c + T; pixel centres on integers; distortion k1 k2 p1 p2 k3.");
    out << "format" << kStereoFormat;
    out << "camera_size"
        << "[:" << c.camera_size.width << c.camera_size.height << "]";
    out << "projector_size"
        << "[:" << c.projector_size.width << c.projector_size.height << "]";
    out << "camera_matrix" << camera_matrix(c.camera);
    out << "camera_distortion" << distortion(c.camera);
    out << "projector_matrix" << camera_matrix(c.projector);
    out << "projector_distortion" << distortion(c.projector);
    out << "R" << cv::Mat(3, 3, CV_64F, const_cast<double*>(c.R.data())).clone();
    out << "T" << cv::Mat(3, 1, CV_64F, const_cast<double*>(c.T.data())).clone();
    write_correction(out, "camera_correction", c.camera_correction, c.camera_size);
    write_correction(out, "projector_correction", c.projector_correction, c.projector_size);
    if (c.board_square_size > 0)
        out << "board_square_size" << c.board_square_size;
    out << "camera_rms" << c.camera_rms;
    out << "projector_rms" << c.projector_rms;
    out << "poses"
        << "[";
    for (const auto& p : c.poses) {
        require_finite(p.camera_rms, "a pose's camera_rms");
        require_finite(p.projector_rms, "a pose's projector_rms");
        out << "{"
            << "name" << p.name << "camera_rms" << p.camera_rms << "projector_rms"
            << p.projector_rms << "corners" << p.corners << "used" << (p.used ? 1 : 0);
        if (!p.note.empty())
            out << "note" << p.note;
        out << "}";
    }
    out << "]";
    if (c.trueness.known()) {
        require_finite(c.trueness.length_mm, "trueness.length_mm");
        out << "trueness"
            << "{"
            << "length_mm" << c.trueness.length_mm;
        const auto three = [&](const char* name, auto member) {
            out << name << "[:";
            for (const LengthSigma& at : c.trueness.at) {
                require_finite(at.*member, (std::string("trueness.") + name).c_str());
                out << at.*member;
            }
            out << "]";
        };
        three("depth_mm", &LengthSigma::depth_mm);
        three("along_depth_mm", &LengthSigma::along_depth_mm);
        three("across_mm", &LengthSigma::across_mm);
        out << "}";
    }
    if (const std::optional<DepthCorrection>& d = c.depth_correction) {
        for (const double v :
             {d->focal_scale, d->before_ppm, d->before_sigma_ppm, d->after_ppm, d->after_sigma_ppm})
            require_finite(v, "depth_correction");
        out << "depth_correction"
            << "{"
            << "focal_scale" << d->focal_scale << "before_ppm" << d->before_ppm
            << "before_sigma_ppm" << d->before_sigma_ppm << "after_ppm" << d->after_ppm
            << "after_sigma_ppm" << d->after_sigma_ppm << "positions" << d->positions << "artefact"
            << d->artefact << "}";
    }
    if (!c.origin.empty())
        out << "origin" << c.origin;
    return out.releaseAndGetString();
}

void save_calibration(const fs::path& path, const StereoCalibration& calibration) {
    write_file_atomically(path, calibration_to_yaml(calibration));
}

} // namespace fpp::calib
