// The sub-pixel corner model (corners.hpp, refine_corners_model): each
// corner fitted with a blurred checker corner under shading, edges bent as
// their rows and columns of corners bend.

#include "fpp/calib/corners.hpp"

#include <Eigen/Dense>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace fpp::calib {

namespace {

double dist(const Vec2& a, const Vec2& b) {
    return std::hypot(a[0] - b[0], a[1] - b[1]);
}

// Below this fitted blur (px, median over a board) the corners are fitted
// again on a copy of the texture blurred by kPreBlurPx.
constexpr double kMinModelBlurPx = 0.4;
constexpr double kPreBlurPx = 0.5;

// What a corner's fit is given, measured on its neighbours: the bends of its
// edges (ku, kv: an edge bends by k w^2 at a distance w along it, see
// edge_bends) and the relative gradient of the contrast (gx, gy per px:
// shading multiplies the pattern). Zero for a first pass.
struct CornerPrior {
    double ku = 0, kv = 0, gx = 0, gy = 0;
};

// Per sample of a corner's window: offset from the start (px), shading
// coordinates (per window radius), the contrast's tilt, and the value.
struct CornerSample {
    double dx, dy, sx, sy, tilt, value;
};

// The finite pixels within `radius` of the start; false when the window
// leaves the image.
bool window_samples(const Image<float>& image, const Vec2& start, double radius,
                    const CornerPrior& prior, std::vector<CornerSample>& samples) {
    const int x0 = static_cast<int>(std::ceil(start[0] - radius));
    const int x1 = static_cast<int>(std::floor(start[0] + radius));
    const int y0 = static_cast<int>(std::ceil(start[1] - radius));
    const int y1 = static_cast<int>(std::floor(start[1] + radius));
    if (x0 < 0 || y0 < 0 || x1 >= image.width() || y1 >= image.height())
        return false;
    const double inv_r = 1.0 / radius;
    for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
            const double dx = x - start[0], dy = y - start[1];
            const float v = image.at(x, y);
            if (dx * dx + dy * dy > radius * radius || !std::isfinite(v))
                continue;
            // Shading multiplies the pattern: its slope tilts the contrast too.
            samples.push_back({dx, dy, dx * inv_r, dy * inv_r, 1 + prior.gx * dx + prior.gy * dy,
                               static_cast<double>(v)});
        }
    return true;
}

constexpr int kCornerParams = 9;
constexpr int kCornerLinear = 4; // a0, ax, ay, b
using CornerVec = Eigen::Matrix<double, kCornerParams, 1>;
using CornerMat = Eigen::Matrix<double, kCornerParams, kCornerParams>;

// The blurred checker corner model over one window's samples, with the
// edges' given bends. `rows` holds the Jacobian and `res` the residuals,
// allocated once per corner.
struct CornerModel {
    CornerModel(const std::vector<CornerSample>& s, double ku_, double kv_)
        : samples(s), ku(ku_), kv(kv_), rows(static_cast<Eigen::Index>(s.size()), kCornerParams),
          res(static_cast<Eigen::Index>(s.size())) {}

    const std::vector<CornerSample>& samples;
    double ku, kv;
    Eigen::Matrix<double, Eigen::Dynamic, kCornerParams> rows;
    Eigen::VectorXd res;

    // Cost (sum of squared residuals, model - value) at q and, when A is
    // given, the normal equations J^T J (A) and J^T r (g).
    double evaluate(const CornerVec& q, CornerMat* A, CornerVec* g) {
        const double k = 1.0 / std::sqrt(2.0);
        const double two_over_sqrt_pi = 2.0 / std::sqrt(3.14159265358979323846);
        const Eigen::Index n = static_cast<Eigen::Index>(samples.size());
        const double su = std::sin(q(2)), cu = std::cos(q(2)), sv = std::sin(q(3)),
                     cv = std::cos(q(3));
        const double s = q(4);
        double cost = 0;
        for (Eigen::Index i = 0; i < n; ++i) {
            const CornerSample& o = samples[static_cast<std::size_t>(i)];
            const double ex = o.dx - q(0), ey = o.dy - q(1);
            // Signed distances across the edges along u and v; lens distortion
            // bends the edges (a straight-edge model moves corners far from the
            // image centre by a few thousandths of a pixel, radially).
            const double l1 = -su * ex + cu * ey, w1 = cu * ex + su * ey;
            const double l2 = -sv * ex + cv * ey, w2 = cv * ex + sv * ey;
            const double d1 = l1 + ku * w1 * w1, d2 = l2 + kv * w2 * w2;
            const double z1 = k * d1 / s, z2 = k * d2 / s;
            // Beyond |z| = 6, erf is +-1 and its slope below 1e-15 in
            // double: most of a wide window lies there on one edge or both.
            const bool flat1 = std::fabs(z1) > 6, flat2 = std::fabs(z2) > 6;
            const double e1 = flat1 ? std::copysign(1.0, z1) : std::erf(z1);
            const double e2 = flat2 ? std::copysign(1.0, z2) : std::erf(z2);
            const double contrast = q(8) * o.tilt;
            const double model = q(5) + q(6) * o.sx + q(7) * o.sy + contrast * e1 * e2;
            const double r = model - o.value;
            cost += r * r;
            if (!A)
                continue;
            const double g1 =
                flat1 ? 0 : two_over_sqrt_pi * std::exp(-z1 * z1) * k / s; // d e1 / d d1
            const double g2 = flat2 ? 0 : two_over_sqrt_pi * std::exp(-z2 * z2) * k / s;
            const double m1 = contrast * g1 * e2, m2 = contrast * e1 * g2; // dM/dd1, dM/dd2
            res(i) = r;
            rows(i, 0) = m1 * (su - 2 * ku * w1 * cu) + m2 * (sv - 2 * kv * w2 * cv);
            rows(i, 1) = m1 * (-cu - 2 * ku * w1 * su) + m2 * (-cv - 2 * kv * w2 * sv);
            rows(i, 2) = m1 * (-w1 + 2 * ku * w1 * l1);
            rows(i, 3) = m2 * (-w2 + 2 * kv * w2 * l2);
            rows(i, 4) = -(m1 * d1 + m2 * d2) / s;
            rows(i, 5) = 1;
            rows(i, 6) = o.sx;
            rows(i, 7) = o.sy;
            rows(i, 8) = o.tilt * e1 * e2;
        }
        if (A) {
            A->noalias() = rows.transpose() * rows;
            g->noalias() = rows.transpose() * res;
        }
        return cost;
    }
};

// Shading and contrast first, linear for the starting geometry. NB: this
// start is their best fit with its sign turned (g = J^T r and r = -value
// at zero), which LM's first step undoes; the corner model's accuracy
// was measured from this start. From the unturned fit the corners at
// full size agree to 1e-5 px, but a joint calibration at 400 x 300 moves
// by 0.008 mm of depth (HybridCalibrate tests), not yet understood.
bool start_shading_and_contrast(CornerModel& model, CornerVec& p) {
    CornerMat A;
    CornerVec g;
    model.evaluate(p, &A, &g);
    const Eigen::Matrix<double, kCornerLinear, 1> lin =
        A.bottomRightCorner<kCornerLinear, kCornerLinear>().ldlt().solve(g.tail<kCornerLinear>());
    if (!lin.allFinite())
        return false;
    p.tail<kCornerLinear>() += lin;
    return true;
}

// Levenberg-Marquardt from p, keeping the blur in (0.05, radius].
void refine_levenberg_marquardt(CornerModel& model, double radius, CornerVec& p) {
    CornerMat A;
    CornerVec g;
    double cost = model.evaluate(p, &A, &g);
    double lambda = 1e-3;
    CornerMat trial_A;
    CornerVec trial_g;
    for (int it = 0; it < 40; ++it) {
        bool accepted = false;
        for (int attempt = 0; attempt < 10 && !accepted; ++attempt) {
            CornerMat M = A;
            M.diagonal() += lambda * A.diagonal();
            const CornerVec step = -M.ldlt().solve(g);
            const CornerVec trial = p + step;
            if (!trial.allFinite() || !(trial(4) > 0.05) || trial(4) > radius) {
                lambda *= 10;
                continue;
            }
            // With its normal equations: most trials are accepted.
            const double c = model.evaluate(trial, &trial_A, &trial_g);
            if (c < cost) {
                const double decrease = (cost - c) / cost;
                p = trial;
                cost = c;
                A = trial_A;
                g = trial_g;
                lambda = std::max(lambda * 0.3, 1e-9);
                accepted = true;
                if (decrease < 1e-10 || step.head(2).norm() < 1e-6)
                    it = 1000;
            } else {
                lambda *= 10;
            }
        }
        if (!accepted)
            break;
    }
}

// One corner: Levenberg-Marquardt on the blurred checker corner model.
// Parameters: cx, cy (relative to the start), edge angles tu, tv, blur s,
// shading a0, ax, ay (per window radius) and contrast b; the contrast's
// slope is given (a fitted one trades with the corner's position in a small
// window: at 400 x 300 it tripled the spread of the focal lengths).
bool fit_corner_model(const Image<float>& image, const Vec2& start, double tu, double tv,
                      const CornerPrior& prior, double radius, Vec2& out, double& sigma,
                      double& contrast_out) {
    std::vector<CornerSample> samples;
    if (!window_samples(image, start, radius, prior, samples) || samples.size() < 30)
        return false;
    CornerModel model(samples, prior.ku, prior.kv);
    CornerVec p;
    p << 0, 0, tu, tv, 1.0, 0, 0, 0, 0;
    if (!start_shading_and_contrast(model, p))
        return false;
    refine_levenberg_marquardt(model, radius, p);
    out = {start[0] + p(0), start[1] + p(1)};
    sigma = p(4);
    contrast_out = p(8);
    return std::isfinite(out[0]) && std::isfinite(out[1]) && std::fabs(p(8)) > 0;
}

// Bends of the edges through a line of corners (a row or a column of the
// board): the image of a straight board line is straight up to the lens's
// distortion, so a cubic through all of its corners, in the frame of the
// chord from the first to the last, measures how the edge bends at each
// (bend[k] = -l''(w_k) / 2, the model's ku or kv), with the noise of a dozen
// corners rather than of one corner's few pixels.
void edge_bends(const std::vector<Vec2>& line, std::vector<double>& bend) {
    bend.assign(line.size(), 0.0);
    if (line.size() < 5) // a cubic needs a fifth corner to be checked by the others
        return;
    const Vec2 first = line.front(), last = line.back();
    const double length = dist(first, last);
    if (!(length > 0))
        return;
    const Vec2 e{(last[0] - first[0]) / length, (last[1] - first[1]) / length};
    // Along the chord normalised to 0..1 (conditioning); across it in pixels.
    Eigen::MatrixXd A(static_cast<Eigen::Index>(line.size()), 4);
    Eigen::VectorXd l(static_cast<Eigen::Index>(line.size()));
    std::vector<double> w(line.size());
    for (std::size_t k = 0; k < line.size(); ++k) {
        const double dx = line[k][0] - first[0], dy = line[k][1] - first[1];
        w[k] = (e[0] * dx + e[1] * dy) / length;
        const auto row = static_cast<Eigen::Index>(k);
        A(row, 0) = 1;
        A(row, 1) = w[k];
        A(row, 2) = w[k] * w[k];
        A(row, 3) = w[k] * w[k] * w[k];
        l(row) = -e[1] * dx + e[0] * dy;
    }
    const Eigen::Vector4d c = A.colPivHouseholderQr().solve(l);
    if (!c.allFinite())
        return;
    // l'' per pixel squared along the edge: the normalised one over length^2.
    for (std::size_t k = 0; k < line.size(); ++k)
        bend[k] = -(2 * c(2) + 6 * c(3) * w[k]) / (2 * length * length);
}

// Per corner (row-major): the bends of its edges along the rows (ku) and the
// columns (kv) from the whole lines of corners, and its contrast's relative
// gradient from its neighbours' contrasts (neighbouring corners' contrasts
// have opposite signs: their magnitudes are compared; NaN where a corner was
// not refined).
std::vector<CornerPrior> measure_priors(const std::vector<Vec2>& points,
                                        const std::vector<double>& contrasts, int columns,
                                        int rows) {
    std::vector<CornerPrior> out(points.size());
    std::vector<Vec2> line;
    std::vector<double> bend;
    auto index = [&](int i, int j) { return static_cast<std::size_t>(j * columns + i); };
    for (int j = 0; j < rows; ++j) {
        line.clear();
        for (int i = 0; i < columns; ++i)
            line.push_back(points[index(i, j)]);
        edge_bends(line, bend);
        for (int i = 0; i < columns; ++i)
            out[index(i, j)].ku = bend[static_cast<std::size_t>(i)];
    }
    for (int i = 0; i < columns; ++i) {
        line.clear();
        for (int j = 0; j < rows; ++j)
            line.push_back(points[index(i, j)]);
        edge_bends(line, bend);
        for (int j = 0; j < rows; ++j)
            out[index(i, j)].kv = bend[static_cast<std::size_t>(j)];
    }
    for (int j = 0; j < rows; ++j)
        for (int i = 0; i < columns; ++i) {
            const double c0 = std::fabs(contrasts[index(i, j)]);
            if (!(c0 > 0))
                continue;
            // Least squares over the (up to four) neighbours: |b_n| - |b_0| = g . (p_n - p_0).
            double a11 = 0, a12 = 0, a22 = 0, r1 = 0, r2 = 0;
            const int di[4] = {1, -1, 0, 0}, dj[4] = {0, 0, 1, -1};
            for (int k = 0; k < 4; ++k) {
                const int ni = i + di[k], nj = j + dj[k];
                if (ni < 0 || nj < 0 || ni >= columns || nj >= rows)
                    continue;
                const double cn = std::fabs(contrasts[index(ni, nj)]);
                if (!(cn > 0))
                    continue;
                const double dx = points[index(ni, nj)][0] - points[index(i, j)][0];
                const double dy = points[index(ni, nj)][1] - points[index(i, j)][1];
                a11 += dx * dx;
                a12 += dx * dy;
                a22 += dy * dy;
                r1 += dx * (cn - c0);
                r2 += dy * (cn - c0);
            }
            const double det = a11 * a22 - a12 * a12;
            if (!(det > 1e-6 * (a11 + a22) * (a11 + a22)))
                continue; // fewer than two independent directions
            out[index(i, j)].gx = (a22 * r1 - a12 * r2) / det / c0;
            out[index(i, j)].gy = (a11 * r2 - a12 * r1) / det / c0;
        }
    return out;
}

// One pass over every corner on `texture`, each fit given its prior (none:
// straight edges, flat contrast); the fitted blur and contrast of each corner
// go to `sigmas` and `contrasts` (NaN where not refined).
int refine_pass(const Image<float>& texture, const std::vector<Vec2>& start,
                const std::vector<CornerPrior>* priors, std::vector<Vec2>& points, int columns,
                int rows, double max_shift_px, std::vector<double>& sigmas,
                std::vector<double>& contrasts) {
    int refined = 0;
    contrasts.assign(start.size(), std::numeric_limits<double>::quiet_NaN());
    auto at = [&](int i, int j) { return start[static_cast<std::size_t>(j * columns + i)]; };
    for (int j = 0; j < rows; ++j)
        for (int i = 0; i < columns; ++i) {
            const std::size_t index = static_cast<std::size_t>(j * columns + i);
            const Vec2 c = at(i, j);
            // Edge directions from the neighbouring corners; the disc stays
            // inside the four squares at the corner (40 % of the nearest spacing).
            const Vec2 a = at(std::min(i + 1, columns - 1), j), am = at(std::max(i - 1, 0), j);
            const Vec2 b = at(i, std::min(j + 1, rows - 1)), bm = at(i, std::max(j - 1, 0));
            double nearest = 1e300;
            for (const Vec2& q : {a, am, b, bm})
                if (q[0] != c[0] || q[1] != c[1])
                    nearest = std::min(nearest, dist(q, c));
            const double radius = 0.4 * nearest;
            if (!(radius >= 3))
                continue;
            const double tu = std::atan2(a[1] - am[1], a[0] - am[0]);
            const double tv = std::atan2(b[1] - bm[1], b[0] - bm[0]);
            const CornerPrior prior = priors ? (*priors)[index] : CornerPrior{};
            Vec2 out{};
            double sigma = 0, contrast = 0;
            if (!fit_corner_model(texture, c, tu, tv, prior, radius, out, sigma, contrast))
                continue;
            if (dist(out, c) > max_shift_px)
                continue;
            points[index] = out;
            sigmas.push_back(sigma);
            contrasts[index] = contrast;
            ++refined;
        }
    return refined;
}

} // namespace

int refine_corners_model(const Image<float>& texture, std::vector<Vec2>& points, int columns,
                         int rows, double max_shift_px) {
    const std::vector<Vec2> start = points;
    std::vector<double> sigmas, contrasts;
    int refined = refine_pass(texture, start, nullptr, points, columns, rows, max_shift_px, sigmas,
                              contrasts);
    if (sigmas.empty())
        return refined;
    std::nth_element(sigmas.begin(),
                     sigmas.begin() + static_cast<std::ptrdiff_t>(sigmas.size() / 2), sigmas.end());
    const double blur = sigmas[sigmas.size() / 2];
    const Image<float>* image = &texture;
    Image<float> blurred;
    if (blur < kMinModelBlurPx) {
        // A sharp image: edges are box-sampled ramps, not erf profiles, and
        // nearly axis-aligned edges make the fit jump with the sub-pixel phase
        // (up to 0.3 px measured at 0.25 px of optical blur). A symmetric
        // Gaussian pre-blur makes the profile erf-like again without moving the
        // corner (the pattern is point-symmetric about it).
        blurred = texture;
        cv::Mat m(blurred.height(), blurred.width(), CV_32F, blurred.data());
        cv::patchNaNs(m, 0.0);
        cv::GaussianBlur(m, m, cv::Size(0, 0), kPreBlurPx);
        image = &blurred;
        points = start;
        sigmas.clear();
        refine_pass(blurred, start, nullptr, points, columns, rows, max_shift_px, sigmas,
                    contrasts);
    }
    // Again with the edges bent as the refined corners' rows and columns
    // bend, and the contrast tilted as the neighbours' contrasts say: straight
    // edges move corners far from the image centre by a few thousandths of a
    // pixel towards it under barrel distortion (a focal length 30 ppm long),
    // and a shading gradient moves every corner a little the same way
    // (measured in simulation).
    const std::vector<CornerPrior> priors = measure_priors(points, contrasts, columns, rows);
    const std::vector<Vec2> first = points;
    sigmas.clear();
    return refine_pass(*image, first, &priors, points, columns, rows, max_shift_px, sigmas,
                       contrasts);
}

} // namespace fpp::calib
