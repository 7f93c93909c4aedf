// Stereo calibration files: ours (OpenCV FileStorage YAML) and the foreign
// formats of SLStudio and SLMaster. See fpp/calib/stereo_calibration.hpp.

#include "fpp/calib/stereo_calibration.hpp"

#include "fpp/atomic_file.hpp"
#include "fpp/error.hpp"
#include "fpp/sim/rig.hpp"
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

StereoCalibration calibration_from_rig(const sim::Rig& rig) {
    StereoCalibration c;
    c.camera_size = rig.camera_size;
    c.projector_size = rig.projector_size;
    c.camera = rig.camera;
    c.projector = rig.projector;
    c.R = rig.R;
    c.T = rig.t;
    c.origin = "simulated rig '" + rig.name + "' (exact model)";
    return c;
}

CalibrationFormat parse_calibration_format(const std::string& name) {
    if (name == "auto")
        return CalibrationFormat::automatic;
    if (name == "fpp")
        return CalibrationFormat::fpp;
    if (name == "slstudio")
        return CalibrationFormat::slstudio;
    if (name == "slmaster")
        return CalibrationFormat::slmaster;
    throw std::invalid_argument("unknown calibration format '" + name +
                                "' (auto, fpp, slstudio, slmaster)");
}

const char* to_string(CalibrationFormat format) {
    switch (format) {
    case CalibrationFormat::automatic:
        return "auto";
    case CalibrationFormat::fpp:
        return "fpp";
    case CalibrationFormat::slstudio:
        return "slstudio";
    case CalibrationFormat::slmaster:
        return "slmaster";
    }
    return "?";
}

namespace {

// Key names of one format.
struct KeySet {
    const char* camera_matrix;
    const char* camera_distortion;
    const char* projector_matrix;
    const char* projector_distortion;
    const char* R;
    const char* T;
};

constexpr KeySet kFppKeys{
    "camera_matrix", "camera_distortion", "projector_matrix", "projector_distortion", "R", "T"};
constexpr KeySet kSlStudioKeys{"Kc", "kc", "Kp", "kp", "Rp", "Tp"};
constexpr KeySet kSlMasterKeys{"M1", "D1", "M4", "D4", "Rlp", "Tlp"};

// Reads keys of one parsed file, throwing InputError(origin, key, ...).
class Reader {
  public:
    Reader(const cv::FileNode& root, fs::path origin) : root_(root), origin_(std::move(origin)) {}

    [[noreturn]] void fail(const std::string& key, const std::string& what) const {
        throw InputError(origin_, key, what);
    }

    bool has(const char* key) const { return !root_[key].empty(); }

    cv::FileNode require(const std::string& key) const {
        cv::FileNode n = root_[key];
        if (n.empty())
            fail(key, "missing");
        return n;
    }

    // A !!opencv-matrix of finite numbers, as doubles.
    cv::Mat matrix(const std::string& key) const { return matrix_node(require(key), key); }

    cv::Mat matrix_node(const cv::FileNode& n, const std::string& key) const {
        cv::Mat m;
        if (n.isMap()) {
            try {
                n >> m;
            } catch (const cv::Exception& e) {
                fail(key, "malformed opencv-matrix: " + e.msg);
            }
        }
        if (m.empty())
            fail(key, "expected an opencv-matrix (a map with rows, cols, dt and data)");
        if (m.channels() != 1)
            fail(key, "expected a single-channel matrix");
        cv::Mat d;
        m.convertTo(d, CV_64F);
        for (int r = 0; r < d.rows; ++r)
            for (int c = 0; c < d.cols; ++c)
                if (!std::isfinite(d.at<double>(r, c)))
                    fail(key, "element (" + std::to_string(r) + ", " + std::to_string(c) +
                                  ") is not a finite number");
        return d;
    }

    cv::Mat matrix_shaped(const std::string& key, int rows, int cols) const {
        cv::Mat m = matrix(key);
        if (m.rows != rows || m.cols != cols)
            fail(key, "expected a " + std::to_string(rows) + "x" + std::to_string(cols) +
                          " matrix, got " + std::to_string(m.rows) + "x" + std::to_string(m.cols));
        return m;
    }

    // 3 elements as a row or a column.
    Vec3 vector3(const std::string& key) const {
        cv::Mat m = matrix(key);
        if (m.total() != 3 || (m.rows != 1 && m.cols != 1))
            fail(key, "expected a 3x1 vector, got " + std::to_string(m.rows) + "x" +
                          std::to_string(m.cols));
        return {m.at<double>(0), m.at<double>(1), m.at<double>(2)};
    }

    double number(const cv::FileNode& n, const std::string& key) const {
        if (!n.isReal() && !n.isInt())
            fail(key, "expected a number");
        const double v = n.real();
        if (!std::isfinite(v))
            fail(key, "not a finite number");
        return v;
    }
    double number(const std::string& key) const { return number(require(key), key); }

    int integer(const cv::FileNode& n, const std::string& key) const {
        const double v = number(n, key);
        if (v != std::floor(v) || std::fabs(v) > 2147483647.0)
            fail(key, "expected an integer");
        return static_cast<int>(v);
    }

    int dimension(const cv::FileNode& n, const std::string& key) const {
        const int v = integer(n, key);
        if (v < 1 || v > 65535)
            fail(key, "image dimension " + std::to_string(v) + " outside 1..65535");
        return v;
    }

    // [width, height] as a sequence or a 1x2 / 2x1 matrix.
    Size size(const std::string& key) const {
        const cv::FileNode n = require(key);
        double w = 0, h = 0;
        if (n.isSeq()) {
            if (n.size() != 2)
                fail(key, "expected [width, height]");
            return {dimension(n[0], key + "[0]"), dimension(n[1], key + "[1]")};
        }
        if (n.isMap()) {
            cv::Mat m = matrix_node(n, key);
            if (m.total() != 2 || (m.rows != 1 && m.cols != 1))
                fail(key, "expected [width, height]");
            w = m.at<double>(0);
            h = m.at<double>(1);
            if (w != std::floor(w) || h != std::floor(h) || w < 1 || h < 1 || w > 65535 ||
                h > 65535)
                fail(key, "expected integer image dimensions in 1..65535");
            return {static_cast<int>(w), static_cast<int>(h)};
        }
        fail(key, "expected [width, height]");
    }

    std::string text(const cv::FileNode& n, const std::string& key) const {
        if (!n.isString())
            fail(key, "expected a string");
        return n.string();
    }

    LensModel lens(const char* matrix_key, const char* distortion_key) const {
        const cv::Mat K = matrix_shaped(matrix_key, 3, 3);
        const double fu = K.at<double>(0, 0), skew = K.at<double>(0, 1), cu = K.at<double>(0, 2);
        const double fv = K.at<double>(1, 1), cv = K.at<double>(1, 2);
        if (K.at<double>(1, 0) != 0 || K.at<double>(2, 0) != 0 || K.at<double>(2, 1) != 0 ||
            std::fabs(K.at<double>(2, 2) - 1) > 1e-12)
            fail(matrix_key, "not a camera matrix (expected [fu s cu; 0 fv cv; 0 0 1])");
        if (!(fu > 0) || !(fv > 0))
            fail(matrix_key, "focal lengths must be positive");

        const cv::Mat D = matrix(distortion_key);
        const std::size_t n = D.total();
        if ((D.rows != 1 && D.cols != 1) || (n != 4 && n != 5 && n != 8 && n != 12 && n != 14))
            fail(distortion_key, "expected 5 coefficients k1 k2 p1 p2 k3 (1x5 or 5x1), got " +
                                     std::to_string(D.rows) + "x" + std::to_string(D.cols));
        for (std::size_t i = 5; i < n; ++i)
            if (D.at<double>(static_cast<int>(i)) != 0)
                fail(distortion_key, "coefficient " + std::to_string(i) +
                                         " (rational or prism term) is not zero: the model "
                                         "has k1 k2 p1 p2 k3 only");
        LensModel lens;
        lens.fu = fu;
        lens.fv = fv;
        lens.cu = cu;
        lens.cv = cv;
        lens.skew = skew;
        lens.k1 = D.at<double>(0);
        lens.k2 = D.at<double>(1);
        lens.p1 = D.at<double>(2);
        lens.p2 = D.at<double>(3);
        lens.k3 = n >= 5 ? D.at<double>(4) : 0.0;
        return lens;
    }

    Mat3 rotation(const char* key) const {
        const cv::Mat m = matrix_shaped(key, 3, 3);
        Mat3 R{};
        for (int i = 0; i < 9; ++i)
            R[std::size_t(i)] = m.at<double>(i / 3, i % 3);
        // Orthonormal to the precision of a float-stored file.
        const Mat3 P = mul(R, transpose(R));
        double worst = 0;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                worst =
                    std::max(worst, std::fabs(P[std::size_t(i * 3 + j)] - (i == j ? 1.0 : 0.0)));
        const double det = R[0] * (R[4] * R[8] - R[5] * R[7]) - R[1] * (R[3] * R[8] - R[5] * R[6]) +
                           R[2] * (R[3] * R[7] - R[4] * R[6]);
        if (worst > 1e-5 || !(det > 0))
            fail(key, "not a rotation matrix (R R^T differs from I by " + std::to_string(worst) +
                          ", det " + std::to_string(det) + ")");
        return R;
    }

    void geometry(const KeySet& keys, StereoCalibration& c) const {
        c.camera = lens(keys.camera_matrix, keys.camera_distortion);
        c.projector = lens(keys.projector_matrix, keys.projector_distortion);
        c.R = rotation(keys.R);
        c.T = vector3(keys.T);
    }

    // An optional correction grid over an image of `image` pixels, from the
    // matrices <prefix>_du and <prefix>_dv.
    CorrectionGrid correction(const std::string& prefix, Size image) const {
        const std::string du = prefix + "_du", dv = prefix + "_dv";
        if (!has(du.c_str()) && !has(dv.c_str()))
            return {};
        const cv::Mat mu = matrix(du), mv = matrix(dv);
        if (mu.rows < 4 || mu.cols < 4)
            fail(du, "a correction grid needs at least 4 x 4 control points");
        if (mv.rows != mu.rows || mv.cols != mu.cols)
            fail(dv, "expected the shape of " + du + " (" + std::to_string(mu.rows) + "x" +
                         std::to_string(mu.cols) + ")");
        CorrectionGrid grid(image, mu.cols, mu.rows);
        for (int j = 0; j < mu.rows; ++j)
            for (int i = 0; i < mu.cols; ++i) {
                const double a = mu.at<double>(j, i), b = mv.at<double>(j, i);
                if (std::fabs(a) > 1000 || std::fabs(b) > 1000)
                    fail(std::fabs(a) > 1000 ? du : dv,
                         "a control point moves the image by more than 1000 px");
                grid.at(i, j) = {a, b};
            }
        return grid;
    }

    const cv::FileNode& root() const { return root_; }

  private:
    cv::FileNode root_;
    fs::path origin_;
};

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

StereoCalibration parse_calibration(const std::string& text, const fs::path& origin,
                                    CalibrationFormat format) {
    if (text.find_first_not_of(" \t\r\n") == std::string::npos)
        throw InputError(origin, "", "empty calibration file");
    cv::FileStorage storage;
    try {
        storage.open(text, cv::FileStorage::READ | cv::FileStorage::MEMORY);
    } catch (const cv::Exception& e) {
        throw InputError(origin, "",
                         "not an OpenCV FileStorage file (YAML, XML or JSON): " + e.msg);
    }
    if (!storage.isOpened())
        throw InputError(origin, "", "not an OpenCV FileStorage file (YAML, XML or JSON)");
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
                             "(M1, M4, Rlp, Tlp, ...)");
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
    if (!c.origin.empty())
        out << "origin" << c.origin;
    return out.releaseAndGetString();
}

void save_calibration(const fs::path& path, const StereoCalibration& calibration) {
    write_file_atomically(path, calibration_to_yaml(calibration));
}

} // namespace fpp::calib
