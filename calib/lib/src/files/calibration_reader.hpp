#pragma once
// Reading OpenCV FileStorage calibration files key by key: every problem
// throws InputError naming the file and the key. Shared by the stereo
// (camera-projector) and camera-pair loaders.

#include "file_storage_yaml.hpp"
#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/error.hpp"

#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace fpp::calib::detail {

namespace fs = std::filesystem;

// Key names of one format.
struct KeySet {
    const char* camera_matrix;
    const char* camera_distortion;
    const char* projector_matrix;
    const char* projector_distortion;
    const char* R;
    const char* T;
};

// OpenCV 4.6's XML parser dereferences a null pointer on a tag still open
// where its text ends (`<Kc type_id=`; found by tests/fuzz): such XML is
// refused before it sees it. (YAML and JSON never reach OpenCV as they were
// written: see file_storage_yaml.hpp.)
inline void refuse_xml_ending_inside_a_tag(std::string_view xml, const fs::path& origin) {
    bool in_tag = false;
    char quote = 0;
    for (const char ch : xml) {
        if (!in_tag)
            in_tag = ch == '<';
        else if (quote != 0)
            quote = ch == quote ? 0 : quote;
        else if (ch == '"' || ch == '\'')
            quote = ch;
        else if (ch == '>')
            in_tag = false;
    }
    if (in_tag)
        throw InputError(origin, "", "not an OpenCV FileStorage file: XML ends inside a tag");
}

// Opens FileStorage text, every failure an InputError naming `origin`. Some
// malformed text makes OpenCV throw std::length_error rather than
// cv::Exception (found by tests/fuzz).
inline cv::FileStorage open_file_storage(const std::string& text, const fs::path& origin) {
    const std::string_view seen(text.c_str()); // what OpenCV reads: up to a NUL
    const std::size_t first = seen.find_first_not_of(" \t\r\n");
    const bool xml = first != std::string_view::npos && seen[first] == '<';
    if (xml)
        refuse_xml_ending_inside_a_tag(seen, origin);
    const std::string opencv_text = xml ? text : rewrite_yaml_for_opencv(text, origin);
    cv::FileStorage storage;
    try {
        storage.open(opencv_text, cv::FileStorage::READ | cv::FileStorage::MEMORY);
    } catch (const cv::Exception& e) {
        throw InputError(origin, "",
                         "not an OpenCV FileStorage file (YAML, XML or JSON): " + e.msg);
    } catch (const std::exception& e) {
        throw InputError(origin, "",
                         std::string("not an OpenCV FileStorage file (YAML, XML or JSON): ") +
                             e.what());
    }
    if (!storage.isOpened())
        throw InputError(origin, "", "not an OpenCV FileStorage file (YAML, XML or JSON)");
    return storage;
}

// Reads keys of one parsed file, throwing InputError(origin, key, ...).
class Reader {
public:
    Reader(const cv::FileNode& root, fs::path origin) : root_(root), origin_(std::move(origin)) {}

    [[noreturn]] void fail(const std::string& key, const std::string& what) const {
        throw InputError(origin_, key, what);
    }

    // OpenCV asserts (cv::Exception) on a key lookup in anything but a map:
    // a file whose top level is a list or a scalar has no keys.
    bool has(const char* key) const { return root_.isMap() && !root_[key].empty(); }

    cv::FileNode require(const std::string& key) const {
        if (!root_.isMap())
            fail(key, "missing (the file's top level is not a map of keys)");
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
            check_matrix_header(n, key);
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

    // OpenCV allocates rows x cols x channels before it reads `data`: a
    // header claiming billions of elements would allocate gigabytes for a few
    // bytes of file. Sizes must be positive and `data` must hold them all.
    void check_matrix_header(const cv::FileNode& n, const std::string& key) const {
        const cv::FileNode rows = n["rows"], cols = n["cols"], dt = n["dt"], data = n["data"];
        if (rows.empty() || cols.empty() || dt.empty() || data.empty())
            fail(key, "expected an opencv-matrix (a map with rows, cols, dt and data)");
        if (!rows.isInt() || !cols.isInt() || !dt.isString() || !data.isSeq())
            fail(key, "malformed opencv-matrix: rows and cols must be integers, dt a string, "
                      "data a list");
        const std::int64_t r = static_cast<int>(rows), c = static_cast<int>(cols);
        const std::string type = static_cast<std::string>(dt);
        // "d" or "3d": the leading digits count channels.
        std::int64_t channels = 0;
        std::size_t i = 0;
        for (; i < type.size() && i < 2 && type[i] >= '0' && type[i] <= '9'; ++i)
            channels = channels * 10 + (type[i] - '0');
        if (i == 0)
            channels = 1;
        const auto elements = static_cast<std::int64_t>(data.size());
        if (r < 1 || c < 1 || channels < 1 || r * c * channels != elements)
            fail(key, "malformed opencv-matrix: rows " + std::to_string(r) + " x cols " +
                          std::to_string(c) + " x channels " + std::to_string(channels) +
                          " does not match the " + std::to_string(elements) + " numbers of data");
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
        const cv::Mat K = matrix_shaped(matrix_key, 3, 3); // the matrix's errors first
        return lens_from(K, matrix(distortion_key), matrix_key, distortion_key);
    }

    // A lens from a 3x3 camera matrix and its distortion (keys for errors).
    LensModel lens_from(const cv::Mat& K, const cv::Mat& D, const std::string& matrix_key,
                        const std::string& distortion_key) const {
        const double fu = K.at<double>(0, 0), skew = K.at<double>(0, 1), cu = K.at<double>(0, 2);
        const double fv = K.at<double>(1, 1), cv = K.at<double>(1, 2);
        if (K.at<double>(1, 0) != 0 || K.at<double>(2, 0) != 0 || K.at<double>(2, 1) != 0 ||
            std::fabs(K.at<double>(2, 2) - 1) > 1e-12)
            fail(matrix_key, "not a camera matrix (expected [fu s cu; 0 fv cv; 0 0 1])");
        if (!(fu > 0) || !(fv > 0))
            fail(matrix_key, "focal lengths must be positive");

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

    Mat3 rotation(const char* key) const { return rotation_from(matrix_shaped(key, 3, 3), key); }

    // A 3x3 matrix checked to be a rotation (key for errors).
    Mat3 rotation_from(const cv::Mat& m, const std::string& key) const {
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

} // namespace fpp::calib::detail
