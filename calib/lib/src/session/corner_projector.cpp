// Projector coordinates of checkerboard corners from the decoded phase maps.

#include "fpp/calib/corner_projector.hpp"

#include "fpp/enum_names.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace fpp::calib {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// 3x3 homography (row-major) mapping src to dst in least squares (normalised
// DLT). Returns false if degenerate.
bool fit_homography(const std::vector<Vec2>& src, const std::vector<Vec2>& dst,
                    Eigen::Matrix3d& H) {
    const std::size_t n = src.size();
    if (n < 4)
        return false;
    auto normaliser = [](const std::vector<Vec2>& p) {
        double mx = 0, my = 0;
        for (const Vec2& q : p) {
            mx += q[0];
            my += q[1];
        }
        mx /= static_cast<double>(p.size());
        my /= static_cast<double>(p.size());
        double d = 0;
        for (const Vec2& q : p)
            d += std::hypot(q[0] - mx, q[1] - my);
        d /= static_cast<double>(p.size());
        const double s = d > 0 ? std::sqrt(2.0) / d : 1.0;
        Eigen::Matrix3d T;
        T << s, 0, -s * mx, 0, s, -s * my, 0, 0, 1;
        return T;
    };
    const Eigen::Matrix3d Ts = normaliser(src), Td = normaliser(dst);
    Eigen::Matrix<double, 9, 9> AtA = Eigen::Matrix<double, 9, 9>::Zero();
    for (std::size_t k = 0; k < n; ++k) {
        const Eigen::Vector3d s = Ts * Eigen::Vector3d(src[k][0], src[k][1], 1);
        const Eigen::Vector3d d = Td * Eigen::Vector3d(dst[k][0], dst[k][1], 1);
        const double rows[2][9] = {
            {s.x(), s.y(), 1, 0, 0, 0, -d.x() * s.x(), -d.x() * s.y(), -d.x()},
            {0, 0, 0, s.x(), s.y(), 1, -d.y() * s.x(), -d.y() * s.y(), -d.y()}};
        // The lower triangle (the upper one is the same sums).
        for (int i = 0; i < 9; ++i)
            for (int j = 0; j <= i; ++j)
                AtA(i, j) += rows[0][i] * rows[0][j] + rows[1][i] * rows[1][j];
    }
    AtA.triangularView<Eigen::StrictlyUpper>() = AtA.transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 9, 9>> eig(AtA);
    if (eig.info() != Eigen::Success)
        return false;
    const Eigen::Matrix<double, 9, 1> h = eig.eigenvectors().col(0);
    Eigen::Matrix3d Hn;
    Hn << h(0), h(1), h(2), h(3), h(4), h(5), h(6), h(7), h(8);
    H = Td.inverse() * Hn * Ts;
    if (!(std::fabs(H(2, 2)) > 1e-300))
        return false;
    H /= H(2, 2);
    return H.allFinite();
}

Vec2 apply(const Eigen::Matrix3d& H, double x, double y) {
    const Eigen::Vector3d q = H * Eigen::Vector3d(x, y, 1);
    return {q.x() / q.z(), q.y() / q.z()};
}

// Legendre polynomials P_0..P_order at t.
void legendre(double t, int order, double* out) {
    out[0] = 1;
    if (order >= 1)
        out[1] = t;
    for (int n = 1; n < order; ++n)
        out[n + 1] = ((2 * n + 1) * t * out[n] - n * out[n - 1]) / (n + 1);
}

struct Sample {
    double x, y;   // camera px relative to the corner, scaled
    double px, py; // projector coordinates
};

// Least-squares fit of a 2D polynomial of total degree `order` (Legendre
// basis in scaled coordinates, well conditioned) to both projector
// coordinates, with one pass rejecting gross outliers (pixels decoded to
// the wrong fringe); returns the value at (0, 0).
bool fit_polynomial_at_origin(const std::vector<Sample>& samples, int order,
                              int min_per_coefficient, Vec2& value) {
    const int terms = (order + 1) * (order + 2) / 2;
    std::vector<char> keep(samples.size(), 1);
    std::vector<double> lx(static_cast<std::size_t>(order + 1)),
        ly(static_cast<std::size_t>(order + 1));
    Eigen::MatrixXd coef;
    for (int pass = 0; pass < 2; ++pass) {
        std::size_t n = 0;
        for (char k : keep)
            n += k ? 1 : 0;
        if (n < static_cast<std::size_t>(terms * min_per_coefficient))
            return false;
        Eigen::MatrixXd A(static_cast<Eigen::Index>(n), terms);
        Eigen::MatrixXd b(static_cast<Eigen::Index>(n), 2);
        Eigen::Index r = 0;
        for (std::size_t s = 0; s < samples.size(); ++s) {
            if (!keep[s])
                continue;
            legendre(samples[s].x, order, lx.data());
            legendre(samples[s].y, order, ly.data());
            int c = 0;
            for (int dx = 0; dx <= order; ++dx)
                for (int dy = 0; dx + dy <= order; ++dy)
                    A(r, c++) = lx[static_cast<std::size_t>(dx)] * ly[static_cast<std::size_t>(dy)];
            b(r, 0) = samples[s].px;
            b(r, 1) = samples[s].py;
            ++r;
        }
        // The lower triangle only (a symmetric rank update: half a product's
        // work), which is all LDLT reads.
        Eigen::MatrixXd AtA = Eigen::MatrixXd::Zero(terms, terms);
        AtA.selfadjointView<Eigen::Lower>().rankUpdate(A.transpose());
        const Eigen::MatrixXd Atb = A.transpose() * b;
        const Eigen::LDLT<Eigen::MatrixXd, Eigen::Lower> ldlt(AtA);
        if (ldlt.info() != Eigen::Success)
            return false;
        coef = ldlt.solve(Atb);
        if (!coef.allFinite())
            return false;
        if (pass == 1)
            break;
        // Residuals; reject beyond max(6 robust sigmas, 0.5 projector px).
        const Eigen::MatrixXd res = A * coef - b;
        std::vector<double> mag(static_cast<std::size_t>(res.rows()));
        for (Eigen::Index k = 0; k < res.rows(); ++k)
            mag[static_cast<std::size_t>(k)] = std::hypot(res(k, 0), res(k, 1));
        std::vector<double> sorted = mag;
        std::nth_element(sorted.begin(),
                         sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2),
                         sorted.end());
        const double limit = std::max(6.0 * 1.4826 * sorted[sorted.size() / 2] / 1.1774, 0.5);
        bool any = false;
        r = 0;
        for (std::size_t s = 0; s < samples.size(); ++s) {
            if (!keep[s])
                continue;
            if (mag[static_cast<std::size_t>(r)] > limit) {
                keep[s] = 0;
                any = true;
            }
            ++r;
        }
        if (!any)
            break;
    }
    legendre(0.0, order, lx.data());
    value = {0, 0};
    int c = 0;
    for (int dx = 0; dx <= order; ++dx)
        for (int dy = 0; dx + dy <= order; ++dy) {
            const double basis =
                lx[static_cast<std::size_t>(dx)] * lx[static_cast<std::size_t>(dy)];
            value[0] += coef(c, 0) * basis;
            value[1] += coef(c, 1) * basis;
            ++c;
        }
    return true;
}

struct LocalFrame {
    Eigen::Matrix3d board_to_image; // board coordinates relative to the corner, in squares
    Eigen::Matrix3d image_to_board;
    double square_a_px = 0; // length of one square along a (i) and b (j) at the corner
    double square_b_px = 0;
};

bool local_frame(const std::vector<Vec2>& corners, int columns, int rows, int i, int j,
                 LocalFrame& f) {
    std::vector<Vec2> board, image;
    for (int jj = std::max(j - 1, 0); jj <= std::min(j + 1, rows - 1); ++jj)
        for (int ii = std::max(i - 1, 0); ii <= std::min(i + 1, columns - 1); ++ii) {
            board.push_back({static_cast<double>(ii - i), static_cast<double>(jj - j)});
            image.push_back(corners[static_cast<std::size_t>(jj * columns + ii)]);
        }
    if (!fit_homography(board, image, f.board_to_image))
        return false;
    f.image_to_board = f.board_to_image.inverse();
    const Vec2 a = apply(f.board_to_image, 1, 0), am = apply(f.board_to_image, -1, 0);
    const Vec2 b = apply(f.board_to_image, 0, 1), bm = apply(f.board_to_image, 0, -1);
    f.square_a_px = 0.5 * std::hypot(a[0] - am[0], a[1] - am[1]);
    f.square_b_px = 0.5 * std::hypot(b[0] - bm[0], b[1] - bm[1]);
    return f.image_to_board.allFinite() && f.square_a_px > 2 && f.square_b_px > 2;
}

// Integer bounding box of the image of the board rectangle [-h, h]^2 around the corner.
void window_box(const LocalFrame& f, double h, Size size, int& x0, int& y0, int& x1, int& y1) {
    double minx = 1e300, miny = 1e300, maxx = -1e300, maxy = -1e300;
    for (int k = 0; k < 4; ++k) {
        // Outline sampled (perspective keeps edges straight).
        const double t = -h + 2 * h * k / 3.0;
        const Vec2 pts[4] = {apply(f.board_to_image, t, -h), apply(f.board_to_image, t, h),
                             apply(f.board_to_image, -h, t), apply(f.board_to_image, h, t)};
        for (const Vec2& p : pts) {
            minx = std::min(minx, p[0]);
            maxx = std::max(maxx, p[0]);
            miny = std::min(miny, p[1]);
            maxy = std::max(maxy, p[1]);
        }
    }
    x0 = std::max(0, static_cast<int>(std::floor(minx)));
    y0 = std::max(0, static_cast<int>(std::floor(miny)));
    x1 = std::min(size.width - 1, static_cast<int>(std::ceil(maxx)));
    y1 = std::min(size.height - 1, static_cast<int>(std::ceil(maxy)));
}

bool corner_poly(const DecodeResult& d, const Vec2& corner, const LocalFrame& f,
                 bool top_left_black, const ProjectorCornerOptions& o, Vec2& out) {
    const double square = std::max(f.square_a_px, f.square_b_px);
    const double erosion = o.erosion_px > 0
                               ? o.erosion_px
                               : std::max(3.0, 0.12 * std::min(f.square_a_px, f.square_b_px));
    int x0, y0, x1, y1;
    window_box(f, 1.0, d.camera, x0, y0, x1, y1);
    std::vector<Sample> samples;
    samples.reserve(static_cast<std::size_t>((x1 - x0 + 1) * (y1 - y0 + 1) / 2));
    const double inv_scale = 1.0 / square;
    const Eigen::Matrix3d& G = f.image_to_board;
    int side_a = 0, side_b = 0;
    for (int y = y0; y <= y1; ++y) {
        const float* px = d.proj_x.row(y);
        const float* py = d.proj_y.row(y);
        const std::uint8_t* m = d.mask.row(y);
        for (int x = x0; x <= x1; ++x) {
            if (!(m[x] & kDecodeValid) || !std::isfinite(px[x]) || !std::isfinite(py[x]))
                continue;
            const double w = G(2, 0) * x + G(2, 1) * y + G(2, 2);
            const double a = (G(0, 0) * x + G(0, 1) * y + G(0, 2)) / w;
            const double b = (G(1, 0) * x + G(1, 1) * y + G(1, 2)) / w;
            if (!(std::fabs(a) < 1 && std::fabs(b) < 1))
                continue;
            // White squares only: a*b < 0 are the top-right and bottom-left
            // squares, white when the top-left one is black.
            const bool white = top_left_black ? (a * b < 0) : (a * b > 0);
            if (!white)
                continue;
            const double edge =
                std::min({std::fabs(a) * f.square_a_px, std::fabs(b) * f.square_b_px,
                          (1 - std::fabs(a)) * f.square_a_px, (1 - std::fabs(b)) * f.square_b_px});
            if (edge < erosion)
                continue;
            samples.push_back({(x - corner[0]) * inv_scale, (y - corner[1]) * inv_scale,
                               static_cast<double>(px[x]), static_cast<double>(py[x])});
            (a > 0 ? side_a : side_b)++;
        }
    }
    // Both white squares must contribute, or the fit extrapolates.
    if (side_a < 4 || side_b < 4)
        return false;
    return fit_polynomial_at_origin(samples, o.poly_order, o.min_pixels_per_coefficient, out);
}

bool corner_homography(const DecodeResult& d, const Vec2& corner, const LocalFrame& f,
                       const ProjectorCornerOptions& o, Vec2& out) {
    const double half = o.homography_half_window * 0.5 * (f.square_a_px + f.square_b_px);
    const int x0 = std::max(0, static_cast<int>(std::ceil(corner[0] - half)));
    const int x1 = std::min(d.camera.width - 1, static_cast<int>(std::floor(corner[0] + half)));
    const int y0 = std::max(0, static_cast<int>(std::ceil(corner[1] - half)));
    const int y1 = std::min(d.camera.height - 1, static_cast<int>(std::floor(corner[1] + half)));
    std::vector<Vec2> cam, proj;
    for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
            if (!(d.mask.at(x, y) & kDecodeValid))
                continue;
            const float px = d.proj_x.at(x, y), py = d.proj_y.at(x, y);
            if (!std::isfinite(px) || !std::isfinite(py))
                continue;
            cam.push_back({x - corner[0], y - corner[1]});
            proj.push_back({static_cast<double>(px), static_cast<double>(py)});
        }
    if (cam.size() < static_cast<std::size_t>(9 * o.min_pixels_per_coefficient))
        return false;
    Eigen::Matrix3d H;
    if (!fit_homography(cam, proj, H))
        return false;
    // One pass rejecting pixels decoded to the wrong fringe.
    std::vector<double> err(cam.size());
    for (std::size_t k = 0; k < cam.size(); ++k) {
        const Vec2 q = apply(H, cam[k][0], cam[k][1]);
        err[k] = std::hypot(q[0] - proj[k][0], q[1] - proj[k][1]);
    }
    std::vector<double> sorted = err;
    std::nth_element(sorted.begin(),
                     sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
    const double limit = std::max(6.0 * 1.4826 * sorted[sorted.size() / 2] / 1.1774, 0.5);
    std::vector<Vec2> cam2, proj2;
    for (std::size_t k = 0; k < cam.size(); ++k)
        if (err[k] <= limit) {
            cam2.push_back(cam[k]);
            proj2.push_back(proj[k]);
        }
    if (cam2.size() != cam.size() && !fit_homography(cam2, proj2, H))
        return false;
    out = apply(H, 0, 0);
    return std::isfinite(out[0]) && std::isfinite(out[1]);
}

} // namespace

constexpr EnumName<CornerMethod> kCornerMethodNames[] = {
    {CornerMethod::poly, "poly"},
    {CornerMethod::bilinear, "bilinear"},
    {CornerMethod::homography, "homography"},
};

const char* to_string(CornerMethod method) {
    return name_of(kCornerMethodNames, method);
}

CornerMethod corner_method_from_string(const std::string& name) {
    return parse_name(kCornerMethodNames, "corner method", name);
}

double sample_bilinear(const Image<float>& image, double x, double y, int channel) {
    if (!(x >= 0 && y >= 0))
        return kNaN;
    const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
    if (x0 + 1 >= image.width() || y0 + 1 >= image.height()) {
        // Exactly on the last row/column is still inside.
        if (x0 < image.width() && y0 < image.height() && x == x0 && y == y0)
            return image.at(x0, y0, channel);
        return kNaN;
    }
    const double fx = x - x0, fy = y - y0;
    const double v00 = image.at(x0, y0, channel), v10 = image.at(x0 + 1, y0, channel);
    const double v01 = image.at(x0, y0 + 1, channel), v11 = image.at(x0 + 1, y0 + 1, channel);
    return (1 - fy) * ((1 - fx) * v00 + fx * v10) + fy * ((1 - fx) * v01 + fx * v11);
}

ProjectorCorners projector_corners(const DecodeResult& decoded, const std::vector<Vec2>& corners,
                                   int columns, int rows, bool origin_square_black,
                                   const ProjectorCornerOptions& options) {
    if (decoded.proj_x.empty() || decoded.proj_y.empty())
        throw std::invalid_argument("projector_corners: the capture codes only one projector axis");
    if (corners.size() != static_cast<std::size_t>(columns * rows))
        throw std::invalid_argument("projector_corners: corner count does not match the board");
    if (options.poly_order < 1 || options.poly_order > 9)
        throw std::invalid_argument("projector_corners: poly_order must be in 1..9");
    ProjectorCorners result;
    result.points.assign(corners.size(), Vec2{kNaN, kNaN});
    result.valid.assign(corners.size(), false);
    for (int j = 0; j < rows; ++j)
        for (int i = 0; i < columns; ++i) {
            const std::size_t k = static_cast<std::size_t>(j * columns + i);
            const Vec2& c = corners[k];
            Vec2 out{kNaN, kNaN};
            bool ok = false;
            if (options.method == CornerMethod::bilinear) {
                out = {sample_bilinear(decoded.proj_x, c[0], c[1]),
                       sample_bilinear(decoded.proj_y, c[0], c[1])};
                ok = std::isfinite(out[0]) && std::isfinite(out[1]);
            } else {
                LocalFrame frame;
                if (local_frame(corners, columns, rows, i, j, frame)) {
                    // The square up-left of corner (i, j) is square (i, j):
                    // black when i + j is even on a board whose origin square is black.
                    const bool top_left_black = ((i + j) % 2 == 0) == origin_square_black;
                    ok = options.method == CornerMethod::poly
                             ? corner_poly(decoded, c, frame, top_left_black, options, out)
                             : corner_homography(decoded, c, frame, options, out);
                }
            }
            if (ok) {
                result.points[k] = out;
                result.valid[k] = true;
            } else {
                ++result.failed;
            }
        }
    return result;
}

} // namespace fpp::calib
