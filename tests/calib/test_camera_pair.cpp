// Camera-camera calibrations (fpp/calib/camera_pair.hpp): OpenCV's stereo
// YAML (merged and as the sample's two files), SLMaster's binocular
// caliInfo.yml, Bouguet's stereo results and MATLAB's stereoParameters as
// text, each checked against a synthetic pair whose answer is known; and the
// recognition of such files by load_calibration.

#include "test_support.hpp"

#include "fpp/calib/camera_pair.hpp"
#include "fpp/calib/stereo_calibration.hpp"
#include "fpp/error.hpp"
#include "fpp/yaml_fields.hpp"

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>

namespace {

using fpp::calib::CameraPairCalibration;
using fpp::calib::CameraPairFormat;
using fpp::test::TempDir;
namespace fs = std::filesystem;

// The known pair: camera 2 is 120 mm to the right of camera 1, turned 8
// degrees towards it. X_2 = R X_1 + T.
struct Truth {
    cv::Mat K1 = (cv::Mat_<double>(3, 3) << 2400.5, 0.75, 1023.25, 0, 2401.5, 767.5, 0, 0, 1);
    cv::Mat D1 = (cv::Mat_<double>(1, 5) << -0.071, 0.185, 0.0023, -0.0005, -0.5);
    cv::Mat K2 = (cv::Mat_<double>(3, 3) << 2350.0, 0.0, 1001.0, 0, 2352.0, 770.25, 0, 0, 1);
    cv::Mat D2 = (cv::Mat_<double>(1, 5) << -0.065, 0.12, -0.001, 0.0007, 0.25);
    cv::Mat om = (cv::Mat_<double>(3, 1) << 0.01, -0.1396, 0.004);
    cv::Mat R;
    cv::Mat T = (cv::Mat_<double>(3, 1) << -119.0, 1.5, 15.5);
    Truth() { cv::Rodrigues(om, R); }
};

std::string matlab_row(const cv::Mat& m) { // mat2str(m, 17): "[a b c;d e f]"
    std::string s = "[";
    char buf[64];
    for (int r = 0; r < m.rows; ++r) {
        for (int c = 0; c < m.cols; ++c) {
            std::snprintf(buf, sizeof buf, "%.17g", m.at<double>(r, c));
            if (c > 0)
                s += ' ';
            s += buf;
        }
        if (r + 1 < m.rows)
            s += ";";
    }
    return s + "]";
}

void expect_lens(const fpp::LensModel& l, const cv::Mat& K, const cv::Mat& D, double tol) {
    EXPECT_NEAR(l.fu, K.at<double>(0, 0), tol);
    EXPECT_NEAR(l.skew, K.at<double>(0, 1), tol);
    EXPECT_NEAR(l.cu, K.at<double>(0, 2), tol);
    EXPECT_NEAR(l.fv, K.at<double>(1, 1), tol);
    EXPECT_NEAR(l.cv, K.at<double>(1, 2), tol);
    EXPECT_NEAR(l.k1, D.at<double>(0), 1e-12);
    EXPECT_NEAR(l.k2, D.at<double>(1), 1e-12);
    EXPECT_NEAR(l.p1, D.at<double>(2), 1e-12);
    EXPECT_NEAR(l.p2, D.at<double>(3), 1e-12);
    EXPECT_NEAR(l.k3, D.at<double>(4), 1e-12);
}

void expect_geometry(const CameraPairCalibration& c, const Truth& t) {
    expect_lens(c.first, t.K1, t.D1, 1e-9);
    expect_lens(c.second, t.K2, t.D2, 1e-9);
    for (int i = 0; i < 9; ++i)
        EXPECT_NEAR(c.R[std::size_t(i)], t.R.at<double>(i / 3, i % 3), 1e-12) << i;
    for (int i = 0; i < 3; ++i)
        EXPECT_NEAR(c.T[std::size_t(i)], t.T.at<double>(i), 1e-12) << i;
}

// The MATLAB text of the truth, as mat2str writes stereoParameters' fields:
// IntrinsicMatrix = K' with the principal point 1-based, RotationOfCamera2 =
// R', row-vector translation (x2 = x1 * R_m + t).
std::string matlab_text(const Truth& t) {
    auto intrinsic = [](cv::Mat K) {
        K = K.clone();
        K.at<double>(0, 2) += 1;
        K.at<double>(1, 2) += 1;
        return cv::Mat(K.t());
    };
    auto radial = [](const cv::Mat& D) {
        return cv::Mat(
            (cv::Mat_<double>(1, 3) << D.at<double>(0), D.at<double>(1), D.at<double>(4)));
    };
    auto tangential = [](const cv::Mat& D) {
        return cv::Mat((cv::Mat_<double>(1, 2) << D.at<double>(2), D.at<double>(3)));
    };
    std::string s = "% stereoParams exported with mat2str\n";
    s += "CameraParameters1.IntrinsicMatrix = " + matlab_row(intrinsic(t.K1)) + "\n";
    s += "CameraParameters1.RadialDistortion = " + matlab_row(radial(t.D1)) + "\n";
    s += "CameraParameters1.TangentialDistortion = " + matlab_row(tangential(t.D1)) + "\n";
    s += "CameraParameters1.ImageSize = [1536 2048]\n";
    s += "CameraParameters2.IntrinsicMatrix = " + matlab_row(intrinsic(t.K2)) + "\n";
    s += "CameraParameters2.RadialDistortion = " + matlab_row(radial(t.D2)) + "\n";
    s += "CameraParameters2.TangentialDistortion = " + matlab_row(tangential(t.D2)) + "\n";
    s += "CameraParameters2.ImageSize = [1536 2048]\n";
    s += "RotationOfCamera2 = " + matlab_row(t.R.t()) + "\n";
    s += "TranslationOfCamera2 = " + matlab_row(t.T.t()) + "\n";
    s += "MeanReprojectionError = 0.125\n";
    return s;
}

TEST(CameraPair, MatlabTextIsTransposedAndOneBased) {
    const Truth t;
    const CameraPairCalibration c = fpp::calib::parse_camera_pair(matlab_text(t), "stereo.txt");
    expect_geometry(c, t);
    EXPECT_EQ(c.first_size, (fpp::Size{2048, 1536}));
    EXPECT_EQ(c.second_size, (fpp::Size{2048, 1536}));
    EXPECT_DOUBLE_EQ(c.rms, 0.125);

    // A point seen by both cameras, computed as MATLAB would (row vectors,
    // 1-based pixels) without distortion, must land on our model's pixel + 1.
    CameraPairCalibration ideal = c;
    ideal.second.k1 = ideal.second.k2 = ideal.second.k3 = ideal.second.p1 = ideal.second.p2 = 0;
    const cv::Mat X1 = (cv::Mat_<double>(1, 3) << 60.0, -35.0, 640.0);
    const cv::Mat x2 = X1 * t.R.t() + t.T.t(); // x2 = x1 * RotationOfCamera2 + t
    cv::Mat K2m = t.K2.t();
    K2m.at<double>(2, 0) += 1;
    K2m.at<double>(2, 1) += 1;
    const cv::Mat h = (cv::Mat_<double>(1, 3) << x2.at<double>(0) / x2.at<double>(2),
                       x2.at<double>(1) / x2.at<double>(2), 1.0) *
                      K2m; // MATLAB: [u v 1] = [x y 1] * IntrinsicMatrix
    const fpp::Vec3 p1{60.0, -35.0, 640.0};
    const fpp::Vec3 rp = fpp::mul(ideal.R, p1);
    const fpp::Vec2 ours =
        ideal.second.project({rp[0] + ideal.T[0], rp[1] + ideal.T[1], rp[2] + ideal.T[2]});
    EXPECT_NEAR(ours[0] + 1, h.at<double>(0), 1e-9);
    EXPECT_NEAR(ours[1] + 1, h.at<double>(1), 1e-9);
    EXPECT_NEAR(c.baseline(), cv::norm(t.T), 1e-12);
}

TEST(CameraPair, MatlabErrorsNameTheField) {
    const Truth t;
    std::string text = matlab_text(t);
    const std::size_t at = text.find("RotationOfCamera2");
    std::string missing = text.substr(0, at) + text.substr(text.find('\n', at) + 1);
    try {
        fpp::calib::parse_camera_pair(missing, "stereo.txt", CameraPairFormat::matlab);
        FAIL() << "accepted a file without RotationOfCamera2";
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.field(), "RotationOfCamera2");
        EXPECT_EQ(e.file(), fs::path("stereo.txt"));
    }
    std::string ragged = text;
    ragged.replace(ragged.find("RotationOfCamera2 = [") + 21, 0, "7 ");
    try {
        fpp::calib::parse_camera_pair(ragged, "stereo.txt");
        FAIL() << "accepted a ragged matrix";
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.field(), "line 10");
        EXPECT_NE(std::string(e.what()).find("rows of different lengths"), std::string::npos);
    }
    std::string scaled = matlab_text(t);
    scaled.replace(scaled.find("RotationOfCamera2 = [") + 21, 0, "2*");
    EXPECT_THROW(fpp::calib::parse_camera_pair(scaled, "stereo.txt"), fpp::InputError);
}

std::string bouguet_text(const Truth& t) {
    auto v = [](std::initializer_list<double> xs) {
        std::string s = "[ ";
        char buf[64];
        for (double x : xs) {
            std::snprintf(buf, sizeof buf, "%.17g ", x);
            s += buf;
        }
        return s + "]";
    };
    auto side = [&](const char* name, const cv::Mat& K, const cv::Mat& D) {
        const std::string n = name;
        return "Intrinsic parameters of " + n + " camera:\n\nFocal Length:          fc_" + n +
               " = " + v({K.at<double>(0, 0), K.at<double>(1, 1)}) +
               " ± [ 1.2 1.3 ]\nPrincipal point:       cc_" + n + " = " +
               v({K.at<double>(0, 2), K.at<double>(1, 2)}) + " ± [ 2.1 2.2 ]\n" +
               "Skew:             alpha_c_" + n + " = " +
               v({K.at<double>(0, 1) / K.at<double>(0, 0)}) +
               " ± [ 0.0 ]   => angle of pixel axes = 90.0 ± 0.0 degrees\n" +
               "Distortion:            kc_" + n + " = " +
               v({D.at<double>(0), D.at<double>(1), D.at<double>(2), D.at<double>(3),
                  D.at<double>(4)}) +
               " ± [ 0.01 0.02 0.001 0.001 0.0 ]\n\n";
    };
    return "Stereo calibration parameters after optimization:\n\n" + side("left", t.K1, t.D1) +
           side("right", t.K2, t.D2) +
           "Extrinsic parameters (position of right camera wrt left camera):\n\n" +
           "Rotation vector:             om = " +
           v({t.om.at<double>(0), t.om.at<double>(1), t.om.at<double>(2)}) +
           " ± [ 0.001 0.001 0.001 ]\nTranslation vector:           T = " +
           v({t.T.at<double>(0), t.T.at<double>(1), t.T.at<double>(2)}) + " ± [ 0.1 0.1 0.1 ]\n";
}

TEST(CameraPair, BouguetPrintoutWithUncertainties) {
    const Truth t;
    const CameraPairCalibration c = fpp::calib::parse_camera_pair(bouguet_text(t), "stereo.txt");
    expect_geometry(c, t);
    EXPECT_EQ(c.first_size, (fpp::Size{0, 0})); // the printout has no image size
    EXPECT_NE(c.origin.find("bouguet"), std::string::npos);
}

void write_opencv_files(const Truth& t, const fs::path& intrinsics, const fs::path& extrinsics) {
    // As OpenCV's stereo_calib sample writes them.
    cv::FileStorage in(intrinsics.string(), cv::FileStorage::WRITE);
    in << "M1" << t.K1 << "D1" << t.D1 << "M2" << t.K2 << "D2" << t.D2;
    in.release();
    cv::FileStorage ex(extrinsics.string(), cv::FileStorage::WRITE);
    const cv::Mat eye = cv::Mat::eye(3, 3, CV_64F);
    ex << "R" << t.R << "T" << t.T << "R1" << eye << "R2" << eye << "P1"
       << cv::Mat::zeros(3, 4, CV_64F) << "P2" << cv::Mat::zeros(3, 4, CV_64F) << "Q"
       << cv::Mat::zeros(4, 4, CV_64F);
    ex.release();
}

TEST(CameraPair, OpenCvStereoSampleFilesAndMerged) {
    TempDir dir;
    const Truth t;
    write_opencv_files(t, dir / "intrinsics.yml", dir / "extrinsics.yml");
    expect_geometry(fpp::calib::load_camera_pair(dir / "intrinsics.yml", dir / "extrinsics.yml"),
                    t);
    cv::FileStorage merged((dir / "stereo.yml").string(), cv::FileStorage::WRITE);
    merged << "M1" << t.K1 << "D1" << t.D1 << "M2" << t.K2 << "D2" << t.D2 << "R" << t.R << "T"
           << t.T;
    merged.release();
    const CameraPairCalibration c = fpp::calib::load_camera_pair(dir / "stereo.yml");
    expect_geometry(c, t);
    // cv::stereoCalibrate's own argument names, with its E and F beside.
    cv::FileStorage named((dir / "arguments.yml").string(), cv::FileStorage::WRITE);
    named << "cameraMatrix1" << t.K1 << "distCoeffs1" << t.D1 << "cameraMatrix2" << t.K2
          << "distCoeffs2" << t.D2 << "R" << t.R << "T" << t.T << "E" << cv::Mat::eye(3, 3, CV_64F)
          << "F" << cv::Mat::eye(3, 3, CV_64F);
    named.release();
    expect_geometry(fpp::calib::load_camera_pair(dir / "arguments.yml"), t);
    EXPECT_TRUE(fpp::calib::looks_like_camera_pair(
        fpp::yaml_fields::read_text_file(dir / "arguments.yml")));
    // The intrinsics file alone is not a pair: named error.
    try {
        fpp::calib::load_camera_pair(dir / "intrinsics.yml");
        FAIL();
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.field(), "R");
    }
}

// SLMaster's binocular caliInfo.yml as the tool writes it
// (src/calibration/caliPacker.cpp, calibration type 1: OpenCV FileStorage,
// these keys in this order): M1 D1 S, then M2 D2, stereoRectify's R1 P1 R2
// P2 Q, stereoCalibrate's R and T as Rlr and Tlr, E, F and the epipolar
// lines, empty unless exported.
void write_slmaster_binocular(const fs::path& file, const Truth& t) {
    const cv::Size size(1280, 1024);
    cv::Mat R1, R2, P1, P2, Q;
    cv::stereoRectify(t.K1, t.D1, t.K2, t.D2, size, t.R, t.T, R1, R2, P1, P2, Q);
    const cv::Mat tx =
        (cv::Mat_<double>(3, 3) << 0, -t.T.at<double>(2), t.T.at<double>(1), t.T.at<double>(2), 0,
         -t.T.at<double>(0), -t.T.at<double>(1), t.T.at<double>(0), 0);
    const cv::Mat E = tx * t.R;
    const cv::Mat F = t.K2.inv().t() * E * t.K1.inv();
    cv::FileStorage f(file.string(), cv::FileStorage::WRITE);
    f << "M1" << t.K1 << "D1" << t.D1 << "S" << (cv::Mat_<double>(2, 1) << 1280, 1024);
    f << "M2" << t.K2 << "D2" << t.D2 << "R1" << R1 << "P1" << P1 << "R2" << R2 << "P2" << P2 << "Q"
      << Q << "Rlr" << t.R << "Tlr" << t.T << "E" << E << "F" << F;
    f << "epilines31" << cv::Mat() << "epilines32" << cv::Mat() << "epilines12" << cv::Mat();
}

// load_calibration meets camera-camera files: it says what they are and
// what they allow instead of "M4: missing".
TEST(CameraPair, LoadCalibrationRecognisesCameraCameraFiles) {
    TempDir dir;
    const Truth t;
    write_slmaster_binocular(dir / "caliInfo.yml", t);
    std::ofstream(dir / "bouguet.txt") << bouguet_text(t);
    std::ofstream(dir / "matlab.txt") << matlab_text(t);
    for (const char* name : {"caliInfo.yml", "bouguet.txt", "matlab.txt"}) {
        SCOPED_TRACE(name);
        try {
            fpp::calib::load_calibration(dir / name);
            FAIL() << "read a camera-camera file as camera-projector";
        } catch (const fpp::calib::CameraPairFileError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find("camera-camera calibration of two cameras"), std::string::npos)
                << what;
            EXPECT_NE(what.find("baseline 120.0 mm"), std::string::npos) << what;
            EXPECT_NE(what.find("two-camera scanning"), std::string::npos) << what;
            EXPECT_EQ(what.find("M4"), std::string::npos) << what;
            EXPECT_EQ(e.file(), dir / name);
            expect_geometry(e.pair, t);
        }
    }
    try {
        fpp::calib::load_calibration(dir / "caliInfo.yml");
    } catch (const fpp::calib::CameraPairFileError& e) {
        EXPECT_NE(std::string(e.what()).find("1280 x 1024 px and 1280 x 1024 px"),
                  std::string::npos)
            << e.what();
    }
    // Named explicitly, the second device is read as the projector.
    const auto as_projector = fpp::calib::load_calibration(
        dir / "caliInfo.yml", fpp::calib::CalibrationFormat::opencv_stereo);
    expect_lens(as_projector.projector, t.K2, t.D2, 1e-9);
    EXPECT_FALSE(as_projector.sizes_known());
}

// The same file as a --pair-calibration: the pair's motion from Rlr and Tlr
// (it used to be refused with "R: missing").
TEST(CameraPair, SlMasterBinocularFileAsTheToolWritesIt) {
    TempDir dir;
    const Truth t;
    write_slmaster_binocular(dir / "caliInfo.yml", t);
    const CameraPairCalibration c = fpp::calib::load_camera_pair(dir / "caliInfo.yml");
    expect_geometry(c, t);
    EXPECT_EQ(c.first_size, (fpp::Size{1280, 1024}));
    // Without its motion it names the key it looked for.
    {
        cv::FileStorage f((dir / "no-motion.yml").string(), cv::FileStorage::WRITE);
        f << "M1" << t.K1 << "D1" << t.D1 << "M2" << t.K2 << "D2" << t.D2 << "Rlr" << t.R;
    }
    try {
        fpp::calib::load_camera_pair(dir / "no-motion.yml");
        FAIL() << "read a pair without Tlr";
    } catch (const fpp::InputError& e) {
        EXPECT_EQ(e.field(), "Tlr") << e.what();
    }
}

TEST(CameraPair, RealSlMasterMonocularFileIsStillCameraProjector) {
    const fs::path file = fpp::test::dataset("slmaster/monocular/caliInfo.yml");
    FPP_REQUIRE_DATASET(file);
    const auto c = fpp::calib::load_calibration(file);
    EXPECT_EQ(c.format, fpp::calib::CalibrationFormat::slmaster);
    EXPECT_NEAR(c.projector.fu, 2496.633, 1e-3);
}

// Each format's name reads back; an unknown name is refused naming them all.
TEST(CameraPair, FormatNamesReadBack) {
    using fpp::calib::parse_camera_pair_format, fpp::calib::to_string;
    for (const CameraPairFormat f : {CameraPairFormat::automatic, CameraPairFormat::opencv_stereo,
                                     CameraPairFormat::bouguet, CameraPairFormat::matlab})
        EXPECT_EQ(parse_camera_pair_format(to_string(f)), f) << to_string(f);
    EXPECT_STREQ(to_string(CameraPairFormat::opencv_stereo), "opencv-stereo");
    try {
        parse_camera_pair_format("opencv");
        FAIL() << "no exception";
    } catch (const std::invalid_argument& e) {
        EXPECT_STREQ(e.what(),
                     "unknown camera-pair format 'opencv' (auto, opencv-stereo, bouguet, matlab)");
    }
}

} // namespace

// Found by tests/fuzz/fuzz_camera_pair: OpenCV allocates an opencv-matrix's
// rows x cols before it reads `data`, so a header claiming 30 million rows
// over five numbers allocated 1.2 GB (80 GB for 2e9 rows, and a matrix
// without `data` the same). The reader now checks the header against the data
// first and names the key (valid files: the tests above).
TEST(CameraPair, MatrixHeaderLargerThanItsDataIsRefusedBeforeAllocating) {
    const std::string head = "%YAML:1.0\n---\nM1: !!opencv-matrix\n   rows: 30000000\n"
                             "   cols: 5\n   dt: d\n";
    for (const std::string& text : {head + "   data: [ 1, 2, 3, 4, 5 ]\n", head}) {
        try {
            fpp::calib::parse_camera_pair(text, "pair.yml", CameraPairFormat::opencv_stereo);
            ADD_FAILURE() << "accepted " << text;
        } catch (const fpp::InputError& e) {
            EXPECT_EQ(e.file(), fs::path("pair.yml")) << e.what();
            EXPECT_EQ(e.field(), "M1") << e.what();
            EXPECT_EQ(std::string(e.what()).find("OpenCV("), std::string::npos) << e.what();
        }
    }
}

// Found by tests/fuzz/fuzz_camera_pair: OpenCV's YAML parser throws
// std::length_error (not cv::Exception) for this text, which escaped from
// looks_like_camera_pair and the readers. It is an InputError naming the file.
TEST(CameraPair, OpenCvParserThrowingAStandardExceptionIsAnInputError) {
    const std::string text = "%YAML:1.0\n"
                             "---\n"
                             "M1: !!opencv-matrix\n"
                             "   rows: 3\n"
                             "   cols: 3\n"
                             "   :td d\n"
                             "   daa\xc1:t [ 2400..5, 075, 1023.25, 0(0, 2401.5, 767.5, 0.0, 0"
                             ".0Ster";
    EXPECT_FALSE(fpp::calib::looks_like_camera_pair(text));
    for (const CameraPairFormat format :
         {CameraPairFormat::automatic, CameraPairFormat::opencv_stereo}) {
        try {
            fpp::calib::parse_camera_pair(text, "pair.yml", format);
            ADD_FAILURE() << "accepted " << text;
        } catch (const fpp::InputError& e) {
            EXPECT_EQ(e.file(), fs::path("pair.yml")) << e.what();
        }
    }
}
