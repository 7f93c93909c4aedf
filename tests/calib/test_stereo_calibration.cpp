// Stereo calibration files: our YAML (round trip, every key required, shapes,
// non-finite values, sizes), atomic saving, and the foreign formats of
// SLStudio (calibration.xml) and SLMaster (caliInfo.yml).

#include "lens_expect.hpp"
#include "test_support.hpp"

#include "fpp/calib/camera_pair.hpp"
#include "fpp/calib/simulated_rig.hpp"
#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/error.hpp"
#include "fpp/simulator/rig.hpp"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <cmath>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

namespace {

using fpp::calib::CalibrationFormat;
using fpp::calib::StereoCalibration;
using fpp::test::TempDir;
namespace fs = std::filesystem;

StereoCalibration sample() {
    StereoCalibration c = fpp::calib::calibration_from_rig(fpp::sim::Rig::paper());
    c.camera_rms = 0.1537;
    c.projector_rms = 0.0991;
    c.poses.push_back({"pose-01", 0.12, 0.08, 247, true, ""});
    c.poses.push_back({"pose-02", 0.95, 1.70, 180, false, "outlier: \"projector\" RMS 1.70 px"});
    c.origin = "fpp-calib stereo on 'session #3': 15 poses";
    c.trueness.length_mm = 150;
    c.trueness.at = {fpp::calib::LengthSigma{420, 0.015, 0.003},
                     fpp::calib::LengthSigma{478.5, 0.0191, 0.0034},
                     fpp::calib::LengthSigma{537, 0.024, 0.0039}};
    c.depth_correction =
        fpp::calib::DepthCorrection{0.999869, -131.2, 32.1, -8.3, 33.0, 4, "ball bar #17"};
    return c;
}

using fpp::test::expect_same_lens;

TEST(CalibrationFile, RoundTripIsExact) {
    TempDir dir;
    const StereoCalibration c = sample();
    const fs::path path = dir / "calib.yaml";
    fpp::calib::save_calibration(path, c);
    const StereoCalibration r = fpp::calib::load_calibration(path);
    EXPECT_EQ(r.format, CalibrationFormat::fpp);
    EXPECT_EQ(r.camera_size, c.camera_size);
    EXPECT_EQ(r.projector_size, c.projector_size);
    expect_same_lens(r.camera, c.camera);
    expect_same_lens(r.projector, c.projector);
    EXPECT_EQ(r.R, c.R);
    EXPECT_EQ(r.T, c.T);
    EXPECT_EQ(r.camera_rms, c.camera_rms);
    EXPECT_EQ(r.projector_rms, c.projector_rms);
    ASSERT_EQ(r.poses.size(), 2u);
    EXPECT_EQ(r.poses[1].name, "pose-02");
    EXPECT_EQ(r.poses[1].camera_rms, 0.95);
    EXPECT_EQ(r.poses[1].projector_rms, 1.70);
    EXPECT_EQ(r.poses[1].corners, 180);
    EXPECT_FALSE(r.poses[1].used);
    EXPECT_EQ(r.poses[1].note, "outlier: \"projector\" RMS 1.70 px");
    EXPECT_TRUE(r.poses[0].used);
    EXPECT_EQ(r.poses[0].note, "");
    EXPECT_EQ(r.origin, c.origin);
    EXPECT_EQ(r.trueness.length_mm, 150);
    for (std::size_t k = 0; k < 3; ++k) {
        EXPECT_EQ(r.trueness.at[k].depth_mm, c.trueness.at[k].depth_mm);
        EXPECT_EQ(r.trueness.at[k].along_depth_mm, c.trueness.at[k].along_depth_mm);
        EXPECT_EQ(r.trueness.at[k].across_mm, c.trueness.at[k].across_mm);
    }
    ASSERT_TRUE(r.depth_correction.has_value());
    EXPECT_EQ(r.depth_correction->focal_scale, 0.999869);
    EXPECT_EQ(r.depth_correction->before_ppm, -131.2);
    EXPECT_EQ(r.depth_correction->before_sigma_ppm, 32.1);
    EXPECT_EQ(r.depth_correction->after_ppm, -8.3);
    EXPECT_EQ(r.depth_correction->after_sigma_ppm, 33.0);
    EXPECT_EQ(r.depth_correction->positions, 4);
    EXPECT_EQ(r.depth_correction->artefact, "ball bar #17");
    // Nothing but the file itself in the folder (atomic write, no temporaries).
    int entries = 0;
    for (const auto& e : fs::directory_iterator(dir.path())) {
        (void)e;
        ++entries;
    }
    EXPECT_EQ(entries, 1);
}

TEST(CalibrationFile, OpenCvReadsTheKeysDirectly) {
    // Other tools read our file with plain FileStorage.
    const StereoCalibration c = sample();
    cv::FileStorage fs(fpp::calib::calibration_to_yaml(c),
                       cv::FileStorage::READ | cv::FileStorage::MEMORY);
    ASSERT_TRUE(fs.isOpened());
    cv::Mat K, D, R, T;
    fs["camera_matrix"] >> K;
    fs["projector_distortion"] >> D;
    fs["R"] >> R;
    fs["T"] >> T;
    ASSERT_EQ(K.rows, 3);
    ASSERT_EQ(K.cols, 3);
    EXPECT_EQ(K.at<double>(0, 1), c.camera.skew);
    EXPECT_EQ(K.at<double>(1, 2), c.camera.cv);
    ASSERT_EQ(D.total(), 5u);
    EXPECT_EQ(D.at<double>(4), c.projector.k3); // k1 k2 p1 p2 k3
    EXPECT_EQ(D.at<double>(2), c.projector.p1);
    EXPECT_EQ(R.at<double>(1, 2), c.R[5]);
    ASSERT_EQ(T.rows, 3);
    EXPECT_EQ(T.at<double>(2), c.T[2]);
    cv::FileNode size = fs["camera_size"];
    ASSERT_TRUE(size.isSeq());
    EXPECT_EQ(int(size[0]), 1600);
    EXPECT_EQ(int(size[1]), 1200);
    EXPECT_EQ(double(fs["camera_rms"]), c.camera_rms);
}

// Our file with `omit` left out and `replace` (key -> YAML text) substituted.
std::string edited_yaml(const std::string& omit, const std::string& key = "",
                        const std::string& replacement = "") {
    const std::string text = fpp::calib::calibration_to_yaml(sample());
    // Top-level keys start a line with "key:"; their block runs to the next one.
    std::string out;
    std::size_t pos = 0;
    bool skipping = false;
    while (pos < text.size()) {
        std::size_t end = text.find('\n', pos);
        if (end == std::string::npos)
            end = text.size();
        const std::string line = text.substr(pos, end - pos);
        pos = end + 1;
        const bool top = !line.empty() && line[0] != ' ' && line[0] != '-' &&
                         line.find(':') != std::string::npos && line[0] != '%' && line[0] != '#';
        if (top) {
            const std::string name = line.substr(0, line.find(':'));
            skipping = name == omit || name == key;
            if (name == key)
                out += key + ": " + replacement + "\n";
        }
        if (!skipping)
            out += line + "\n";
    }
    return out;
}

void expect_input_error(const std::string& text, const std::string& field,
                        const std::string& needle = "") {
    try {
        fpp::calib::parse_calibration(text, "calib.yaml");
        ADD_FAILURE() << "accepted a file with a bad " << field << ":\n" << text;
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.field(), field) << e.what();
        EXPECT_EQ(e.file(), fs::path("calib.yaml"));
        EXPECT_NE(std::string(e.what()).find("calib.yaml"), std::string::npos);
        if (!needle.empty()) {
            EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
        }
    }
}

TEST(CalibrationFile, EveryKeyIsRequired) {
    // Sanity: the editing helper leaves a valid file when nothing is removed.
    EXPECT_NO_THROW(fpp::calib::parse_calibration(edited_yaml(""), "calib.yaml"));
    for (const char* key :
         {"camera_size", "projector_size", "camera_distortion", "projector_matrix",
          "projector_distortion", "R", "T", "camera_rms", "projector_rms", "poses"})
        expect_input_error(edited_yaml(key), key, "missing");
    // Without camera_matrix the file is no longer recognisable as ours.
    try {
        fpp::calib::parse_calibration(edited_yaml("camera_matrix"), "calib.yaml");
        ADD_FAILURE() << "accepted a file without camera_matrix";
    } catch (const fpp::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("camera_matrix"), std::string::npos) << e.what();
    }
    // Asked for explicitly, it is named as missing.
    try {
        fpp::calib::parse_calibration(edited_yaml("camera_matrix"), "calib.yaml",
                                      CalibrationFormat::fpp);
        ADD_FAILURE();
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.field(), "camera_matrix");
    }
}

const char* matrix_yaml(int rows, int cols, const std::string& data) {
    static std::string s;
    s = "!!opencv-matrix\n   rows: " + std::to_string(rows) + "\n   cols: " + std::to_string(cols) +
        "\n   dt: d\n   data: [ " + data + " ]";
    return s.c_str();
}

TEST(CalibrationFile, WrongShapesAndValuesAreRejected) {
    expect_input_error(edited_yaml("", "camera_matrix", matrix_yaml(2, 3, "1, 0, 0, 0, 1, 0")),
                       "camera_matrix", "3x3");
    expect_input_error(edited_yaml("", "T", matrix_yaml(2, 2, "1, 2, 3, 4")), "T", "3x1");
    expect_input_error(edited_yaml("", "T", matrix_yaml(3, 1, "1, .nan, 3")), "T", "finite");
    expect_input_error(edited_yaml("", "camera_distortion", matrix_yaml(1, 3, "0.1, 0.2, 0.3")),
                       "camera_distortion", "5 coefficients");
    expect_input_error(
        edited_yaml("", "projector_distortion", matrix_yaml(1, 8, "0.1, 0.2, 0, 0, 0, 0.5, 0, 0")),
        "projector_distortion", "not zero");
    expect_input_error(edited_yaml("", "R", matrix_yaml(3, 3, "1, 0, 0, 0, 1, 0, 0, 0, -1")), "R",
                       "rotation");
    expect_input_error(edited_yaml("", "R", matrix_yaml(3, 3, "2, 0, 0, 0, 1, 0, 0, 0, 1")), "R",
                       "rotation");
    expect_input_error(
        edited_yaml("", "camera_matrix", matrix_yaml(3, 3, "-100, 0, 5, 0, 100, 5, 0, 0, 1")),
        "camera_matrix", "positive");
    expect_input_error(
        edited_yaml("", "camera_matrix", matrix_yaml(3, 3, "100, 0, 5, 0, 100, 5, 0, 0, 2")),
        "camera_matrix", "camera matrix");
    expect_input_error(edited_yaml("", "camera_matrix", "42"), "camera_matrix", "opencv-matrix");
    expect_input_error(edited_yaml("", "camera_rms", "\"abc\""), "camera_rms", "number");
    expect_input_error(edited_yaml("", "poses", "[ { name: a, camera_rms: 0.1 } ]"),
                       "poses[0].projector_rms", "missing");
    expect_input_error(edited_yaml("", "format", "\"fpp-stereo/9\""), "format", "unknown format");
}

// The trueness is optional (files made elsewhere, or before it existed);
// when present, every field is checked.
TEST(CalibrationFile, TruenessIsOptionalAndChecked) {
    const StereoCalibration without =
        fpp::calib::parse_calibration(edited_yaml("trueness"), "calib.yaml");
    EXPECT_FALSE(without.trueness.known());
    const std::string ok = "{ length_mm: 150, depth_mm: [ 400, 480, 560 ], along_depth_mm: [ "
                           "0.01, 0.02, 0.03 ], across_mm: [ 0.001, 0.002, 0.003 ] }";
    EXPECT_EQ(fpp::calib::parse_calibration(edited_yaml("", "trueness", ok), "calib.yaml")
                  .trueness.at[1]
                  .along_depth_mm,
              0.02);
    expect_input_error(edited_yaml("", "trueness", "[ 1, 2 ]"), "trueness", "map");
    expect_input_error(edited_yaml("", "trueness", "{ depth_mm: [ 1, 2, 3 ] }"),
                       "trueness.length_mm", "missing");
    const auto with = [](const std::string& from, const std::string& to) {
        std::string t = "{ length_mm: 150, depth_mm: [ 400, 480, 560 ], along_depth_mm: [ "
                        "0.01, 0.02, 0.03 ], across_mm: [ 0.001, 0.002, 0.003 ] }";
        t.replace(t.find(from), from.size(), to);
        return edited_yaml("", "trueness", t);
    };
    expect_input_error(with("length_mm: 150", "length_mm: 0"), "trueness.length_mm", "positive");
    expect_input_error(with("[ 400, 480, 560 ]", "[ 400, 480 ]"), "trueness.depth_mm", "3 numbers");
    expect_input_error(with("[ 400, 480, 560 ]", "[ 400, 0, 560 ]"), "trueness.depth_mm[1]",
                       "positive");
    expect_input_error(with("0.01, 0.02", "0.01, -0.02"), "trueness.along_depth_mm[1]", "negative");
    expect_input_error(with("0.001, 0.002", "0.001, .nan"), "trueness.across_mm[1]", "finite");
    expect_input_error(with("along_depth_mm", "along_mm"), "trueness.along_depth_mm", "missing");
}

// The record of an in-field correction is optional (a calibration never
// corrected has none); when present, every field is checked.
TEST(CalibrationFile, DepthCorrectionIsOptionalAndChecked) {
    EXPECT_FALSE(fpp::calib::parse_calibration(edited_yaml("depth_correction"), "calib.yaml")
                     .depth_correction.has_value());
    const auto with = [](const std::string& from, const std::string& to) {
        std::string t = "{ focal_scale: 0.99987, before_ppm: -131, before_sigma_ppm: 32, "
                        "after_ppm: -8, after_sigma_ppm: 33, positions: 4, artefact: bar }";
        t.replace(t.find(from), from.size(), to);
        return edited_yaml("", "depth_correction", t);
    };
    EXPECT_EQ(
        fpp::calib::parse_calibration(with("-8", "-9"), "calib.yaml").depth_correction->after_ppm,
        -9);
    expect_input_error(edited_yaml("", "depth_correction", "0.9999"), "depth_correction", "map");
    expect_input_error(with("0.99987", "1.2"), "depth_correction.focal_scale", "1 %");
    expect_input_error(with("0.99987", ".nan"), "depth_correction.focal_scale", "");
    expect_input_error(with("before_sigma_ppm: 32", "before_sigma_ppm: -1"),
                       "depth_correction.before_sigma_ppm", "negative");
    expect_input_error(with("positions: 4", "positions: 1"), "depth_correction.positions",
                       "at least 2");
    expect_input_error(with(", artefact: bar", ""), "depth_correction.artefact", "missing");
    expect_input_error(with("after_ppm: -8", "after_ppm: x"), "depth_correction.after_ppm",
                       "number");
}

TEST(CalibrationFile, WrongSizesAreRejected) {
    expect_input_error(edited_yaml("", "camera_size", "[ 1600 ]"), "camera_size", "width, height");
    expect_input_error(edited_yaml("", "camera_size", "[ 1600, 1200, 3 ]"), "camera_size");
    expect_input_error(edited_yaml("", "projector_size", "[ 0, 800 ]"), "projector_size[0]",
                       "1..65535");
    expect_input_error(edited_yaml("", "projector_size", "[ 1280, 800.5 ]"), "projector_size[1]",
                       "integer");
    expect_input_error(edited_yaml("", "camera_size", "1600"), "camera_size", "width, height");
}

TEST(CalibrationFile, UnreadableFilesNameTheFile) {
    TempDir dir;
    EXPECT_THROW(fpp::calib::load_calibration(dir / "missing.yaml"), fpp::InputError);
    std::ofstream(dir / "garbage.yaml") << "%YAML:1.0\n---\nkey: [ unclosed\n";
    try {
        fpp::calib::load_calibration(dir / "garbage.yaml");
        ADD_FAILURE();
    } catch (const fpp::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("garbage.yaml"), std::string::npos) << e.what();
    }
    std::ofstream(dir / "other.yaml") << "%YAML:1.0\n---\nfoo: 1\n";
    try {
        fpp::calib::load_calibration(dir / "other.yaml");
        ADD_FAILURE();
    } catch (const fpp::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("not a recognised calibration"), std::string::npos)
            << e.what();
    }
    std::ofstream(dir / "empty.yaml") << "";
    EXPECT_THROW(fpp::calib::load_calibration(dir / "empty.yaml"), fpp::InputError);
}

TEST(CalibrationFile, SavingRefusesWhatTheFileCannotHold) {
    TempDir dir;
    StereoCalibration c = sample();
    c.camera.k4 = 0.01; // outside the 5-coefficient model
    EXPECT_THROW(fpp::calib::save_calibration(dir / "c.yaml", c), std::invalid_argument);
    c = sample();
    c.projector_size = {0, 0};
    EXPECT_THROW(fpp::calib::save_calibration(dir / "c.yaml", c), std::invalid_argument);
    c = sample();
    c.T[1] = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(fpp::calib::save_calibration(dir / "c.yaml", c), std::invalid_argument);
    EXPECT_FALSE(fs::exists(dir / "c.yaml"));
    EXPECT_TRUE(fs::is_empty(dir.path()));
}

TEST(CalibrationFile, FormatNames) {
    EXPECT_EQ(fpp::calib::parse_calibration_format("auto"), CalibrationFormat::automatic);
    EXPECT_EQ(fpp::calib::parse_calibration_format("slmaster"), CalibrationFormat::slmaster);
    EXPECT_EQ(fpp::calib::parse_calibration_format("matlab"), CalibrationFormat::matlab);
    EXPECT_EQ(fpp::calib::parse_calibration_format("opencv-stereo"),
              CalibrationFormat::opencv_stereo);
    EXPECT_THROW(fpp::calib::parse_calibration_format("excel"), std::invalid_argument);
    EXPECT_STREQ(fpp::calib::to_string(CalibrationFormat::slstudio), "slstudio");
}

double norm(const fpp::Vec3& v) {
    return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

TEST(CalibrationFile, ReadsSlStudioCalibrationXml) {
    const fs::path path = fpp::test::dataset("slstudio/calibration/calibration.xml");
    FPP_REQUIRE_DATASET(path);
    const StereoCalibration c = fpp::calib::load_calibration(path);
    EXPECT_EQ(c.format, CalibrationFormat::slstudio);
    EXPECT_EQ(c.camera_size, (fpp::Size{1688, 1352}));
    EXPECT_EQ(c.projector_size, (fpp::Size{1824, 1140}));
    EXPECT_NEAR(c.camera.fu, 2195.12036, 1e-3);
    EXPECT_NEAR(c.camera.cu, 843.5, 1e-9);
    EXPECT_NEAR(c.camera.k1, -0.0580352657, 1e-9);
    EXPECT_NEAR(c.projector.cv, 1109.11121, 1e-3);
    EXPECT_NEAR(c.projector.k1, -0.0314900056, 1e-9);
    EXPECT_NEAR(c.R[1], -0.120346159, 1e-8); // Rp(0, 1)
    EXPECT_NEAR(c.T[0], -145.282562, 1e-5);
    EXPECT_NEAR(c.camera_rms, 0.282, 1e-3);
    EXPECT_NEAR(c.projector_rms, 0.463, 1e-3);
    // X_p = Rp X_c + Tp: the projector sits beside the camera, a few hundred
    // mm at most, slightly behind it.
    const fpp::Vec3 centre = c.projector_centre();
    EXPECT_GT(norm(centre), 100.0);
    EXPECT_LT(norm(centre), 300.0);
    EXPECT_LT(std::fabs(centre[2]), 100.0);
    // Explicit format gives the same; the wrong one names the missing key.
    EXPECT_EQ(fpp::calib::load_calibration(path, CalibrationFormat::slstudio).T, c.T);
    try {
        fpp::calib::load_calibration(path, CalibrationFormat::slmaster);
        ADD_FAILURE();
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.field(), "M1");
    }
}

TEST(CalibrationFile, ReadsSlMasterCaliInfo) {
    const fs::path path = fpp::test::dataset("slmaster/monocular/caliInfo.yml");
    FPP_REQUIRE_DATASET(path);
    const StereoCalibration c = fpp::calib::load_calibration(path);
    EXPECT_EQ(c.format, CalibrationFormat::slmaster);
    EXPECT_FALSE(c.sizes_known()); // supplied by the user or the capture
    EXPECT_NEAR(c.camera.fu, 1754.1123627841946, 1e-9);
    EXPECT_NEAR(c.camera.k3, 1.8431788041215542, 1e-12);
    EXPECT_NEAR(c.projector.fu, 2496.6331464214777, 1e-9);
    EXPECT_NEAR(c.projector.k3, 3.4566274542907882, 1e-12);
    EXPECT_NEAR(c.projector.p2, 1.0583521629718045e-03, 1e-15);
    EXPECT_NEAR(c.R[2], 8.9680113989308669e-02, 1e-15); // Rlp(0, 2)
    EXPECT_NEAR(c.T[0], -108.18012009065924, 1e-12);
    EXPECT_LT(c.camera_rms, 0.0); // unknown
    const fpp::Vec3 centre = c.projector_centre();
    EXPECT_GT(norm(centre), 50.0);
    EXPECT_LT(norm(centre), 300.0);

    // Saved in our format once the sizes are known, it reads back the same.
    TempDir dir;
    StereoCalibration sized = c;
    sized.camera_size = {1280, 1024};
    sized.projector_size = {1920, 1080};
    fpp::calib::save_calibration(dir / "ours.yaml", sized);
    const StereoCalibration back = fpp::calib::load_calibration(dir / "ours.yaml");
    expect_same_lens(back.camera, c.camera);
    EXPECT_EQ(back.R, c.R);
    EXPECT_EQ(back.projector_size, (fpp::Size{1920, 1080}));
}

TEST(CalibrationFile, ForeignFilesWithMissingKeysNameTheKey) {
    const std::string slstudio =
        "<?xml version=\"1.0\"?>\n<opencv_storage>\n"
        "<Kc type_id=\"opencv-matrix\"><rows>3</rows><cols>3</cols><dt>f</dt>"
        "<data>1000 0 500 0 1000 400 0 0 1</data></Kc>\n"
        "<kc type_id=\"opencv-matrix\"><rows>5</rows><cols>1</cols><dt>f</dt>"
        "<data>0 0 0 0 0</data></kc>\n"
        "<Kp type_id=\"opencv-matrix\"><rows>3</rows><cols>3</cols><dt>f</dt>"
        "<data>1000 0 500 0 1000 400 0 0 1</data></Kp>\n"
        "<kp type_id=\"opencv-matrix\"><rows>5</rows><cols>1</cols><dt>f</dt>"
        "<data>0 0 0 0 0</data></kp>\n"
        "<Rp type_id=\"opencv-matrix\"><rows>3</rows><cols>3</cols><dt>f</dt>"
        "<data>1 0 0 0 1 0 0 0 1</data></Rp>\n"
        "<Tp type_id=\"opencv-matrix\"><rows>3</rows><cols>1</cols><dt>f</dt>"
        "<data>-100 0 0</data></Tp>\n"
        "<frameWidth>1000</frameWidth><frameHeight>800</frameHeight>\n"
        "<screenResX>912</screenResX>\n"
        "</opencv_storage>\n";
    try {
        fpp::calib::parse_calibration(slstudio, "calibration.xml");
        ADD_FAILURE();
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.field(), "screenResY") << e.what();
        EXPECT_NE(std::string(e.what()).find("calibration.xml"), std::string::npos);
    }
    const std::string slmaster = "%YAML:1.0\n---\nM1: !!opencv-matrix\n   rows: 3\n   cols: 3\n"
                                 "   dt: d\n   data: [ 1000., 0., 500., 0., 1000., 400., 0., 0., "
                                 "1. ]\n";
    try {
        fpp::calib::parse_calibration(slmaster, "caliInfo.yml");
        ADD_FAILURE();
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.field(), "D1") << e.what();
    }
}

} // namespace

// Found by tests/fuzz/fuzz_calibration: a FileStorage file whose top level is
// a list (or a scalar) made the format detection look a key up in it, and
// OpenCV's cv::Exception escaped instead of the reader's InputError.
TEST(CalibrationFile, TopLevelListIsRefusedNamingTheFile) {
    for (const CalibrationFormat format :
         {CalibrationFormat::automatic, CalibrationFormat::fpp, CalibrationFormat::slstudio,
          CalibrationFormat::slmaster}) {
        try {
            fpp::calib::parse_calibration("%YAML:1.0\n---\n- camera_matrix\n- 2\n", "list.yml",
                                          format);
            ADD_FAILURE() << "accepted a list as " << fpp::calib::to_string(format);
        } catch (const fpp::InputError& e) {
            EXPECT_EQ(e.file(), fs::path("list.yml")) << e.what();
            EXPECT_EQ(std::string(e.what()).find("OpenCV("), std::string::npos) << e.what();
        }
    }
}

// Found by tests/fuzz/fuzz_calibration: OpenCV 4.6's XML parser dereferences
// a null pointer when the text ends inside a tag (the fuzzer's input had NUL
// bytes after `type_id=`; OpenCV reads up to the first). The reader refuses
// such XML itself, naming the file.
TEST(CalibrationFile, XmlEndingInsideATagIsRefusedBeforeOpenCvParsesIt) {
    const std::string truncated = "<?xml version=\"1.0\"?>\n<opencv_storage>\n<Kc type_id=";
    for (const std::string& text : {truncated, truncated + std::string(3, '\0') + "\"x\">"}) {
        try {
            fpp::calib::parse_calibration(text, "calibration.xml");
            ADD_FAILURE() << "accepted a truncated XML file";
        } catch (const fpp::InputError& e) {
            EXPECT_EQ(e.file(), fs::path("calibration.xml")) << e.what();
            EXPECT_NE(std::string(e.what()).find("ends inside a tag"), std::string::npos)
                << e.what();
        }
    }
}

// OpenCV 4.6's YAML parser never returns from some malformed text; the
// fuzzers found three kinds (run-long.sh: a line of dashes and text after the
// `%YAML` line; the test command's fuzz runs: text after `---   `, an indented
// first key under a shallower line with ", -", several `%YAML` documents with
// XML among them), and yaml-cpp's LoadAll hangs on a first line that starts
// with ','. YAML is parsed by yaml-cpp and written again in OpenCV's
// own grammar before OpenCV reads it, so each is refused, naming the file and
// the reason, by every reader that opens FileStorage text.
TEST(CalibrationFile, YamlThatHangsOpenCvIsRefusedBeforeOpenCvReadsIt) {
    const std::string with_nul("%YAML:1.0\n   us: 3\n 72e-0, -1.\n--\x01\0\0\0: x\n", 37);
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"%YAML:1.\n-----x\nC\nS", "its top level is a single value"},
        {"%YAML:1.0\n---\nM1: 1\n---x 2\n", "line 4: a second YAML document begins"},
        {"%YAML:1.0\n---   cc_right = 1.0\nM1: 1\n", "line 3: not YAML, XML or JSON"},
        {"%YAML:1.0\n  us: 3\n 7, -1\nM: 3\n", "line 4: not YAML, XML or JSON"},
        {with_nul, "M"}, // a map {us: "3 72e-0, -1. --"} to yaml-cpp: no known keys
        {"%YAML:1.0\n---\nM1: 1\n%YAML:1.0\n---\n<opencv_storage>\n",
         "line 4: a second YAML document begins"},
        // yaml-cpp's LoadAll never returns from these (its Load does).
        {",", "no document where it starts"},
        {",YAML:1.0\n---\nM1: 1\n", "line 2: a second YAML document begins"},
    };
    for (const auto& [text, reason] : cases) {
        for (const bool pair : {false, true}) {
            try {
                if (pair)
                    (void)fpp::calib::parse_camera_pair(
                        text, "pair.yml", fpp::calib::CameraPairFormat::opencv_stereo);
                else
                    (void)fpp::calib::parse_calibration(text, "pair.yml");
                ADD_FAILURE() << "accepted: " << text;
            } catch (const fpp::InputError& e) {
                EXPECT_EQ(e.file(), fs::path("pair.yml")) << e.what();
                EXPECT_NE(std::string(e.what()).find(reason), std::string::npos)
                    << e.what() << " (for: " << text << ")";
            }
        }
        EXPECT_FALSE(fpp::calib::looks_like_camera_pair(text));
    }
}

// The rewrite's own limits: what OpenCV never writes is refused with its
// reason, and a few bytes of aliases cannot make megabytes.
TEST(CalibrationFile, YamlRewriteRefusesWhatOpenCvNeverWrites) {
    std::string deep = "M1: ";
    for (int i = 0; i < 20; ++i)
        deep += "[ ";
    deep += "1";
    for (int i = 0; i < 20; ++i)
        deep += " ]";
    std::string bomb = "a0: &a0 [ 1, 2, 3, 4, 5, 6, 7, 8, 9, 10 ]\n";
    for (int level = 1; level < 8; ++level) {
        const std::string below = "*a" + std::to_string(level - 1);
        bomb += "a" + std::to_string(level) + ": &a" + std::to_string(level) + " [ ";
        for (int i = 0; i < 10; ++i)
            bomb += below + (i < 9 ? ", " : " ]\n");
    }
    const std::vector<std::pair<std::string, std::string>> cases = {
        {deep + "\n", "nested more than 16 levels deep"},
        {bomb, "its aliases repeat too much"},
        {"%YAML:1.0\n---\nM1: 1\ncam era: 2\n", "line 4: key 'cam era' is not a name"},
        {"%YAML:1.0\n---\nM1: \"a\\tb\"\n", "line 3: a control character in a string"},
        {"%YAML:1.0\n---\n", "the file is empty"},
        {"- 1\n- 2\n", "its top level is a list"},
    };
    for (const auto& [text, reason] : cases) {
        try {
            (void)fpp::calib::parse_calibration(text, "c.yml");
            ADD_FAILURE() << "accepted: " << text.substr(0, 80);
        } catch (const fpp::InputError& e) {
            EXPECT_EQ(e.file(), fs::path("c.yml")) << e.what();
            EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << e.what();
        }
    }
}

// JSON reaches OpenCV through the rewrite too: SLMaster's real caliInfo.yml,
// written again as JSON by OpenCV itself, reads to the same calibration.
TEST(CalibrationFile, JsonThatOpenCvWroteReadsAsItsYaml) {
    const fs::path path = fpp::test::dataset("slmaster/monocular/caliInfo.yml");
    FPP_REQUIRE_DATASET(path);
    const StereoCalibration yaml = fpp::calib::load_calibration(path);
    cv::FileStorage in(path.string(), cv::FileStorage::READ);
    cv::FileStorage out(".json", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
    for (const char* key : {"M1", "D1", "S", "M4", "D4", "Rlp", "Tlp"}) {
        cv::Mat m;
        in[key] >> m;
        out << key << m;
    }
    const std::string json = out.releaseAndGetString();
    ASSERT_EQ(json.front(), '{');
    const StereoCalibration back = fpp::calib::parse_calibration(json, "caliInfo.json");
    EXPECT_EQ(back.format, CalibrationFormat::slmaster);
    EXPECT_EQ(back.camera_size, yaml.camera_size);
    expect_same_lens(back.camera, yaml.camera);
    expect_same_lens(back.projector, yaml.projector);
    EXPECT_EQ(back.R, yaml.R);
    EXPECT_EQ(back.T, yaml.T);
}
