// Camera-camera calibrations: OpenCV's stereo YAML (one file or the sample's
// two), SLMaster's binocular caliInfo.yml, Bouguet's stereo results and
// MATLAB's stereoParameters as text. See fpp/calib/camera_pair.hpp and
// firmware/core/formats/imports.md.

#include "fpp/calib/camera_pair.hpp"

#include "calibration_reader.hpp"
#include "calibration_text.hpp"

#include "fpp/enum_names.hpp"
#include "fpp/error.hpp"
#include "fpp/yaml_fields.hpp"

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace fpp::calib {

namespace fs = std::filesystem;
using detail::Reader;
using detail::TextFields;
using detail::TextMatrix;

double CameraPairCalibration::baseline() const {
    return std::sqrt(T[0] * T[0] + T[1] * T[1] + T[2] * T[2]);
}

std::string CameraPairCalibration::summary() const {
    auto size_text = [](Size s) {
        return s.width > 0 ? std::to_string(s.width) + " x " + std::to_string(s.height) + " px"
                           : std::string("unrecorded size");
    };
    char baseline_text[64];
    std::snprintf(baseline_text, sizeof baseline_text, "%.1f mm", baseline());
    return "two cameras (" + size_text(first_size) + " and " + size_text(second_size) +
           "), baseline " + baseline_text;
}

constexpr EnumName<CameraPairFormat> kCameraPairFormatNames[] = {
    {CameraPairFormat::automatic, "auto"},
    {CameraPairFormat::opencv_stereo, "opencv-stereo"},
    {CameraPairFormat::bouguet, "bouguet"},
    {CameraPairFormat::matlab, "matlab"},
};

CameraPairFormat parse_camera_pair_format(const std::string& name) {
    return parse_name(kCameraPairFormatNames, "camera-pair format", name);
}

const char* to_string(CameraPairFormat format) {
    return name_of(kCameraPairFormatNames, format);
}

namespace {

bool is_file_storage(const std::string& text) {
    const std::size_t first = text.find_first_not_of(" \t\r\n");
    if (first == std::string::npos)
        return false;
    return text.compare(first, 5, "%YAML") == 0 || text.compare(first, 5, "<?xml") == 0 ||
           text.compare(first, 16, "<opencv_storage>") == 0 || text[first] == '{';
}

// --- OpenCV FileStorage: M1 D1 M2 D2 R T ---

// An optional image size: S / image_size / imageSize as [w, h] (SLMaster's S
// is the camera size, the same for both cameras of its binocular head).
Size optional_size(const Reader& in) {
    for (const char* key : {"S", "image_size", "imageSize"})
        if (in.has(key))
            return in.size(key);
    return {0, 0};
}

// M1 D1 M2 D2 (OpenCV's stereo_calib sample, SLMaster), or the names of
// cv::stereoCalibrate's own arguments, as a program saving its outputs
// names them: cameraMatrix1 distCoeffs1 cameraMatrix2 distCoeffs2.
bool named_by_arguments(const Reader& in) {
    return !in.has("M1") && in.has("cameraMatrix1");
}

void read_opencv_intrinsics(const Reader& in, CameraPairCalibration& c) {
    const bool arguments = named_by_arguments(in);
    c.first = arguments ? in.lens("cameraMatrix1", "distCoeffs1") : in.lens("M1", "D1");
    c.second = arguments ? in.lens("cameraMatrix2", "distCoeffs2") : in.lens("M2", "D2");
    c.first_size = c.second_size = optional_size(in);
}

// OpenCV's stereoCalibrate names the pair's motion R and T; SLMaster's
// binocular caliInfo.yml holds the same output of it as Rlr and Tlr (left
// camera to right, X_2 = R X_1 + T), beside its rectification (R1 P1 R2 P2
// Q), E, F and epipolar lines, which are not needed here.
bool has_slmaster_motion(const Reader& in) {
    return !in.has("R") && in.has("Rlr");
}

void read_opencv_extrinsics(const Reader& in, CameraPairCalibration& c) {
    const bool slmaster = has_slmaster_motion(in);
    c.R = in.rotation(slmaster ? "Rlr" : "R");
    c.T = in.vector3(slmaster ? "Tlr" : "T");
    if (in.has("rms"))
        c.rms = in.number("rms");
}

cv::FileStorage open_storage(const std::string& text, const fs::path& origin) {
    return detail::open_file_storage(text, origin);
}

CameraPairCalibration read_opencv(const std::string& text, const fs::path& origin) {
    const cv::FileStorage storage = open_storage(text, origin);
    const Reader in(storage.root(), origin);
    CameraPairCalibration c;
    try {
        read_opencv_intrinsics(in, c);
        read_opencv_extrinsics(in, c);
    } catch (const cv::Exception& e) {
        throw InputError(origin, "", std::string("malformed calibration file: ") + e.msg);
    }
    return c;
}

// --- text formats ---

class TextReader {
public:
    TextReader(TextFields fields, fs::path origin)
        : fields_(std::move(fields)), origin_(std::move(origin)), reader_(cv::FileNode(), origin_) {
    }

    bool has(const std::string& name) const { return fields_.count(name) != 0; }

    const TextMatrix& get(const std::string& name) const {
        const auto it = fields_.find(name);
        if (it == fields_.end())
            throw InputError(origin_, name, "missing");
        return it->second;
    }

    // `count` numbers as a row or a column.
    std::vector<double> vector(const std::string& name, std::size_t min_count,
                               std::size_t max_count) const {
        const TextMatrix& m = get(name);
        if ((m.rows != 1 && m.cols != 1) || m.values.size() < min_count ||
            m.values.size() > max_count)
            fail(name, m,
                 "expected " + std::to_string(min_count) +
                     (min_count == max_count ? "" : " to " + std::to_string(max_count)) +
                     " numbers, got " + std::to_string(m.rows) + "x" + std::to_string(m.cols));
        return m.values;
    }

    cv::Mat matrix3(const std::string& name) const {
        const TextMatrix& m = get(name);
        if (m.rows != 3 || m.cols != 3)
            fail(name, m,
                 "expected a 3x3 matrix [a b c; d e f; g h i], got " + std::to_string(m.rows) +
                     "x" + std::to_string(m.cols));
        cv::Mat out(3, 3, CV_64F);
        for (int r = 0; r < 3; ++r)
            for (int k = 0; k < 3; ++k)
                out.at<double>(r, k) = m.at(r, k);
        return out;
    }

    [[noreturn]] void fail(const std::string& name, const TextMatrix& m,
                           const std::string& what) const {
        throw InputError(origin_, name + " (line " + std::to_string(m.line) + ")", what);
    }

    const Reader& reader() const { return reader_; }

private:
    TextFields fields_;
    fs::path origin_;
    Reader reader_;
};

Vec3 vec3(const std::vector<double>& v) {
    return {v[0], v[1], v[2]};
}

// Bouguet: KK = [fc(1) alpha_c*fc(1) cc(1); 0 fc(2) cc(2); 0 0 1], pixel
// (0, 0) the centre of the upper-left pixel (as OpenCV), kc = k1 k2 p1 p2 k3.
LensModel bouguet_lens(const TextReader& in, const std::string& side) {
    const auto fc = in.vector("fc_" + side, 2, 2);
    const auto cc = in.vector("cc_" + side, 2, 2);
    const double alpha = in.has("alpha_c_" + side) ? in.vector("alpha_c_" + side, 1, 1)[0] : 0.0;
    const auto kc = in.vector("kc_" + side, 4, 5);
    cv::Mat K =
        (cv::Mat_<double>(3, 3) << fc[0], alpha * fc[0], cc[0], 0.0, fc[1], cc[1], 0.0, 0.0, 1.0);
    cv::Mat D(1, static_cast<int>(kc.size()), CV_64F);
    for (std::size_t i = 0; i < kc.size(); ++i)
        D.at<double>(static_cast<int>(i)) = kc[i];
    return in.reader().lens_from(K, D, "fc_" + side + "/cc_" + side, "kc_" + side);
}

CameraPairCalibration read_bouguet(const TextReader& in) {
    CameraPairCalibration c;
    c.first = bouguet_lens(in, "left");
    c.second = bouguet_lens(in, "right");
    const auto om = in.vector("om", 3, 3);
    cv::Mat R;
    cv::Rodrigues(cv::Mat(om, true), R);
    c.R = in.reader().rotation_from(R, "om");
    c.T = vec3(in.vector("T", 3, 3));
    if (in.has("nx") && in.has("ny")) {
        const double nx = in.vector("nx", 1, 1)[0], ny = in.vector("ny", 1, 1)[0];
        if (nx >= 1 && ny >= 1 && nx <= 65535 && ny <= 65535 && nx == std::floor(nx) &&
            ny == std::floor(ny))
            c.first_size = c.second_size = {static_cast<int>(nx), static_cast<int>(ny)};
        else
            in.fail("nx", in.get("nx"), "expected image dimensions in 1..65535");
    }
    return c;
}

// MATLAB: IntrinsicMatrix is K transposed ([fx 0 0; s fy 0; cx cy 1]), K (R2022b
// on) is K itself; both put the centre of the upper-left pixel at (1, 1), so
// the principal point moves by -1 to OpenCV's convention.
LensModel matlab_lens(const TextReader& in, const std::string& camera, Size& size) {
    cv::Mat K;
    std::string key;
    if (in.has(camera + ".K")) {
        key = camera + ".K";
        K = in.matrix3(key);
    } else {
        key = camera + ".IntrinsicMatrix";
        K = in.matrix3(key).t();
    }
    K.at<double>(0, 2) -= 1.0;
    K.at<double>(1, 2) -= 1.0;
    const auto radial = in.vector(camera + ".RadialDistortion", 2, 3);
    std::vector<double> tangential{0.0, 0.0};
    if (in.has(camera + ".TangentialDistortion"))
        tangential = in.vector(camera + ".TangentialDistortion", 2, 2);
    cv::Mat D = (cv::Mat_<double>(1, 5) << radial[0], radial[1], tangential[0], tangential[1],
                 radial.size() == 3 ? radial[2] : 0.0);
    if (in.has(camera + ".ImageSize")) {
        const auto rows_cols = in.vector(camera + ".ImageSize", 2, 2);
        if (rows_cols[0] < 1 || rows_cols[1] < 1 || rows_cols[0] > 65535 || rows_cols[1] > 65535 ||
            rows_cols[0] != std::floor(rows_cols[0]) || rows_cols[1] != std::floor(rows_cols[1]))
            in.fail(camera + ".ImageSize", in.get(camera + ".ImageSize"),
                    "expected [rows columns] in 1..65535");
        size = {static_cast<int>(rows_cols[1]), static_cast<int>(rows_cols[0])};
    }
    return in.reader().lens_from(K, D, key, camera + ".RadialDistortion");
}

CameraPairCalibration read_matlab(const TextReader& in) {
    CameraPairCalibration c;
    c.first = matlab_lens(in, "CameraParameters1", c.first_size);
    c.second = matlab_lens(in, "CameraParameters2", c.second_size);
    // Row vectors: x2 = x1 R_m + t, so in column form X2 = R_m^T X1 + t^T.
    c.R = in.reader().rotation_from(in.matrix3("RotationOfCamera2").t(), "RotationOfCamera2");
    c.T = vec3(in.vector("TranslationOfCamera2", 3, 3));
    if (in.has("MeanReprojectionError"))
        c.rms = in.vector("MeanReprojectionError", 1, 1)[0];
    return c;
}

CameraPairFormat text_format(const TextFields& fields) {
    if (fields.count("fc_left") != 0 || fields.count("om") != 0)
        return CameraPairFormat::bouguet;
    if (fields.count("RotationOfCamera2") != 0 ||
        fields.count("CameraParameters1.IntrinsicMatrix") != 0 ||
        fields.count("CameraParameters1.K") != 0)
        return CameraPairFormat::matlab;
    return CameraPairFormat::automatic;
}

} // namespace

bool looks_like_camera_pair(const std::string& text) {
    if (is_file_storage(text)) {
        try {
            const cv::FileStorage storage = detail::open_file_storage(text, "");
            const cv::FileNode root = storage.root();
            const bool motion = (!root["R"].empty() && !root["T"].empty()) ||
                                (!root["Rlr"].empty() && !root["Tlr"].empty());
            const bool cameras = (!root["M1"].empty() && !root["M2"].empty()) ||
                                 (!root["cameraMatrix1"].empty() && !root["cameraMatrix2"].empty());
            return root.isMap() && cameras && motion && root["M4"].empty();
        } catch (const cv::Exception&) {
            return false;
        } catch (const InputError&) {
            return false;
        }
    }
    try {
        return text_format(detail::parse_text_fields(text, "")) != CameraPairFormat::automatic;
    } catch (const InputError&) {
        return false;
    }
}

CameraPairCalibration parse_camera_pair(const std::string& text, const fs::path& origin,
                                        CameraPairFormat format) {
    if (text.find_first_not_of(" \t\r\n") == std::string::npos)
        throw InputError(origin, "", "empty calibration file");
    if (format == CameraPairFormat::automatic && is_file_storage(text))
        format = CameraPairFormat::opencv_stereo;
    CameraPairCalibration c;
    if (format == CameraPairFormat::opencv_stereo) {
        c = read_opencv(text, origin);
    } else {
        TextFields fields = detail::parse_text_fields(text, origin);
        if (format == CameraPairFormat::automatic)
            format = text_format(fields);
        if (format == CameraPairFormat::automatic)
            throw InputError(origin, "",
                             "not a recognised camera-camera calibration: expected OpenCV's "
                             "stereo YAML (M1 D1 M2 D2 R T), Bouguet's stereo results (fc_left "
                             "cc_left kc_left ... om T) or MATLAB's stereoParameters as text "
                             "(CameraParameters1.IntrinsicMatrix ... RotationOfCamera2 "
                             "TranslationOfCamera2)");
        const TextReader in(std::move(fields), origin);
        c = format == CameraPairFormat::bouguet ? read_bouguet(in) : read_matlab(in);
    }
    c.origin = origin.string() + " (" + to_string(format) + " format)";
    return c;
}

CameraPairCalibration load_camera_pair(const fs::path& path, CameraPairFormat format) {
    return parse_camera_pair(yaml_fields::read_text_file(path), path, format);
}

CameraPairCalibration load_camera_pair(const fs::path& intrinsics, const fs::path& extrinsics) {
    CameraPairCalibration c;
    {
        const cv::FileStorage s = open_storage(yaml_fields::read_text_file(intrinsics), intrinsics);
        read_opencv_intrinsics(Reader(s.root(), intrinsics), c);
    }
    {
        const cv::FileStorage s = open_storage(yaml_fields::read_text_file(extrinsics), extrinsics);
        read_opencv_extrinsics(Reader(s.root(), extrinsics), c);
    }
    c.origin = intrinsics.string() + " + " + extrinsics.string() + " (opencv-stereo format)";
    return c;
}

} // namespace fpp::calib
