// Two-camera scanning: rectification of the pair (fpp/calib/two_camera.hpp).
// OpenCV's stereoRectify gives the rotations; every pixel is mapped through
// fpp::LensModel's own distortion model.

#include "fpp/calib/two_camera.hpp"

#include "fpp/parallel.hpp"

#include <opencv2/calib3d.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace fpp::calib {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

cv::Mat lens_matrix(const LensModel& l) {
    return (cv::Mat_<double>(3, 3) << l.fu, l.skew, l.cu, 0.0, l.fv, l.cv, 0.0, 0.0, 1.0);
}

// OpenCV's five coefficients: only used by stereoRectify for its own
// projection matrices, which we do not use (the rotations do not depend on them).
cv::Mat lens_distortion(const LensModel& l) {
    return (cv::Mat_<double>(1, 5) << l.k1, l.k2, l.p1, l.p2, l.k3);
}

cv::Mat to_cv(const Mat3& m) {
    cv::Mat out(3, 3, CV_64F);
    for (int i = 0; i < 9; ++i)
        out.at<double>(i / 3, i % 3) = m[static_cast<std::size_t>(i)];
    return out;
}

Mat3 from_cv(const cv::Mat& m) {
    Mat3 out{};
    for (int i = 0; i < 9; ++i)
        out[static_cast<std::size_t>(i)] = m.at<double>(i / 3, i % 3);
    return out;
}

// Rectified normalised coordinates (X/Z, Y/Z) of a camera pixel; false if the
// lens cannot invert it or it lands behind the rectified camera.
bool rectified_normalised(const LensModel& lens, const Mat3& R, Vec2 pixel, Vec2& out) {
    Vec2 n{};
    if (!lens.pixel_to_normalised(pixel, n))
        return false;
    const Vec3 r = mul(R, Vec3{n[0], n[1], 1.0});
    if (!(r[2] > 1e-9))
        return false;
    out = {r[0] / r[2], r[1] / r[2]};
    return true;
}

} // namespace

void TwoCameraOptions::validate() const {
    auto positive = [](double v, const char* name) {
        if (!(v > 0) || !std::isfinite(v))
            throw std::invalid_argument(std::string("TwoCameraOptions::") + name + " must be > 0");
    };
    positive(max_step_px, "max_step_px");
    positive(max_v_px, "max_v_px");
    positive(cluster_px, "cluster_px");
    positive(max_row_step_px, "max_row_step_px");
    positive(occlusion_margin_px, "occlusion_margin_px");
    if (threads < 0)
        throw std::invalid_argument("TwoCameraOptions::threads must be >= 0");
}

TwoCameraReconstructor::TwoCameraReconstructor(const CameraPairCalibration& pair,
                                               const TwoCameraOptions& options)
    : pair_(pair), options_(options) {
    options_.validate();
    const Size s1 = pair.first_size, s2 = pair.second_size;
    if (s1.width < 2 || s1.height < 2 || s2.width < 2 || s2.height < 2)
        throw std::invalid_argument("the camera pair calibration gives no image sizes");

    cv::Mat R1, R2, P1, P2, Q;
    const cv::Mat T = (cv::Mat_<double>(3, 1) << pair.T[0], pair.T[1], pair.T[2]);
    cv::stereoRectify(lens_matrix(pair.first), lens_distortion(pair.first),
                      lens_matrix(pair.second), lens_distortion(pair.second),
                      cv::Size(s1.width, s1.height), to_cv(pair.R), T, R1, R2, P1, P2, Q,
                      cv::CALIB_ZERO_DISPARITY, -1);
    rect_.R1 = from_cv(R1);
    // R2 = R1 R^T exactly, so that X_r2 = X_r1 - R1 C_2 with C_2 = -R^T T.
    rect_.R2 = mul(rect_.R1, transpose(pair.R));
    const Vec3 c2 = mul(transpose(pair.R), Vec3{-pair.T[0], -pair.T[1], -pair.T[2]});
    const Vec3 b = mul(rect_.R1, c2);
    const double length = std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
    if (!(length > 0))
        throw std::invalid_argument("the camera pair has no baseline (T = 0)");
    if (std::abs(b[1]) > 1e-6 * length || std::abs(b[2]) > 1e-6 * length)
        throw std::invalid_argument(
            "the cameras are above one another, not side by side: two-camera scanning matches "
            "along rows and needs the baseline mostly along x");
    rect_.baseline = b[0];
    rect_.f = 0.25 * (pair.first.fu + pair.first.fv + pair.second.fu + pair.second.fv);

    // Camera 2's border in rectified normalised coordinates gives the grid.
    double a_min = 1e300, a_max = -1e300, b_min = 1e300, b_max = -1e300;
    auto extend = [&](int x, int y) {
        Vec2 r{};
        if (!rectified_normalised(pair.second, rect_.R2, {double(x), double(y)}, r))
            return;
        a_min = std::min(a_min, r[0]);
        a_max = std::max(a_max, r[0]);
        b_min = std::min(b_min, r[1]);
        b_max = std::max(b_max, r[1]);
    };
    for (int x = 0; x < s2.width; ++x) {
        extend(x, 0);
        extend(x, s2.height - 1);
    }
    for (int y = 0; y < s2.height; ++y) {
        extend(0, y);
        extend(s2.width - 1, y);
    }
    if (!(a_max > a_min) || !(b_max > b_min))
        throw std::invalid_argument("the second camera's lens cannot be inverted at its border");
    const double f = rect_.f;
    rect_.cx = -std::floor(f * a_min);
    rect_.cy = -std::floor(f * b_min);
    const double width = std::ceil(f * a_max + rect_.cx) + 1,
                 height = std::ceil(f * b_max + rect_.cy) + 1;
    if (width > 4.0 * s2.width || height > 4.0 * s2.height)
        throw std::invalid_argument("the second camera's field is too wide to rectify "
                                    "(more than 4 times its image)");
    rect_.grid = {int(width), int(height)};

    ThreadPool& pool = ThreadPool::shared(options_.threads);
    // Camera 2: the source pixel of every rectified cell (round trip checked,
    // so that no ray outside the lens's valid field folds back into the image).
    second_source_ = Image<float>(rect_.grid, 2, kNaN);
    const Mat3 R2t = transpose(rect_.R2);
    pool.parallel_for(rect_.grid.height, 8, [&](int begin, int end, int) {
        for (int j = begin; j < end; ++j) {
            float* out = second_source_.row(j);
            for (int i = 0; i < rect_.grid.width; ++i, out += 2) {
                const Vec3 ray = mul(R2t, Vec3{(i - rect_.cx) / f, (j - rect_.cy) / f, 1.0});
                if (!(ray[2] > 1e-9))
                    continue;
                const Vec2 n{ray[0] / ray[2], ray[1] / ray[2]};
                const Vec2 p = pair_.second.distorted_to_pixel(pair_.second.distort(n));
                if (!(p[0] >= 0 && p[1] >= 0 && p[0] <= s2.width - 1 && p[1] <= s2.height - 1))
                    continue;
                Vec2 back{};
                if (!pair_.second.pixel_to_normalised(p, back) ||
                    std::abs(back[0] - n[0]) + std::abs(back[1] - n[1]) > 1e-7)
                    continue;
                out[0] = static_cast<float>(p[0]);
                out[1] = static_cast<float>(p[1]);
            }
        }
    });
    // Camera 1: every pixel's exact rectified position.
    first_rectified_ = Image<float>(s1, 2, kNaN);
    pool.parallel_for(s1.height, 8, [&](int begin, int end, int) {
        for (int y = begin; y < end; ++y) {
            float* out = first_rectified_.row(y);
            for (int x = 0; x < s1.width; ++x, out += 2) {
                Vec2 r{};
                if (!rectified_normalised(pair_.first, rect_.R1, {double(x), double(y)}, r))
                    continue;
                out[0] = static_cast<float>(f * r[0] + rect_.cx);
                out[1] = static_cast<float>(f * r[1] + rect_.cy);
            }
        }
    });
}

} // namespace fpp::calib
