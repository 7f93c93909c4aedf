// Per-pixel fits of the hybrid table (see fpp/calib/pixel_fit.hpp).

#include "fpp/calib/pixel_fit.hpp"

#include "fpp/parallel.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace fpp::calib {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// Solves the symmetric positive definite system a x = b_j (n <= 5) for
// `count` right-hand sides by one LDL^T factorisation, in place. Returns
// false when a pivot is below 1/max_condition of the largest (samples
// bunched at one phase).
bool solve_normal_equations(int n, double a[5][5], int count, double b[3][5],
                            double max_condition) {
    double dmax = 0;
    for (int j = 0; j < n; ++j) {
        double d = a[j][j];
        for (int k = 0; k < j; ++k)
            d -= a[j][k] * a[j][k] * a[k][k];
        a[j][j] = d;
        dmax = std::max(dmax, d);
        if (!(d > dmax / max_condition))
            return false;
        for (int i = j + 1; i < n; ++i) {
            double v = a[i][j];
            for (int k = 0; k < j; ++k)
                v -= a[i][k] * a[j][k] * a[k][k];
            a[i][j] = v / d;
        }
    }
    for (int c = 0; c < count; ++c) {
        double* x = b[c];
        for (int i = 0; i < n; ++i)
            for (int k = 0; k < i; ++k)
                x[i] -= a[i][k] * x[k];
        for (int i = 0; i < n; ++i)
            x[i] /= a[i][i];
        for (int i = n - 1; i >= 0; --i)
            for (int k = i + 1; k < n; ++k)
                x[i] -= a[k][i] * x[k];
    }
    return true;
}

// Weighted least squares of value_c[k] = sum_i coeffs[c][i] basis_i(k) over
// the samples k, for `count` (<= 3) value arrays sharing one design: basis
// rows from `row(k, out)`, weights w_k. n unknowns (n <= 5).
template <class Row>
bool least_squares(int n, std::size_t samples, const Row& row, int count,
                   const double* const* value, const double* weight, double max_condition,
                   double coeffs[3][5]) {
    double a[5][5] = {};
    double r[5];
    for (int c = 0; c < count; ++c)
        for (int i = 0; i < n; ++i)
            coeffs[c][i] = 0;
    for (std::size_t k = 0; k < samples; ++k) {
        row(k, r);
        const double w = weight[k];
        for (int i = 0; i < n; ++i) {
            for (int c = 0; c < count; ++c)
                coeffs[c][i] += w * r[i] * value[c][k];
            for (int j = 0; j <= i; ++j)
                a[i][j] += w * r[i] * r[j];
        }
    }
    for (int i = 0; i < n; ++i)
        for (int j = i + 1; j < n; ++j)
            a[i][j] = a[j][i];
    return solve_normal_equations(n, a, count, coeffs, max_condition);
}

double cubic(const double c[4], double t) {
    return c[0] + t * (c[1] + t * (c[2] + t * c[3]));
}

} // namespace

int model_coefficients(TableModel model) {
    return model == TableModel::rational ? 5 : 4;
}

PixelFit fit_pixel_models(const std::vector<PoseSamples>& poses, const Image<float>& rays,
                          const TableInfo& info, const PixelFitOptions& options) {
    const auto t_start = std::chrono::steady_clock::now();
    const Size camera = info.camera;
    if (rays.size() != camera || rays.channels() != 2)
        throw std::invalid_argument("pixel fit: the camera rays are not of the table's size");
    const bool perpendicular = options.correction == PlaneCorrection::perpendicular_foot;
    for (const PoseSamples& s : poses) {
        if (s.phase.size() != camera || (!s.weight.empty() && s.weight.size() != camera))
            throw std::invalid_argument("pixel fit: a pose's samples are not of the camera's size");
        if (perpendicular && s.sv_depth.size() != camera)
            throw std::invalid_argument("pixel fit: the perpendicular correction needs SV depth");
    }
    const int model_count = options.model_samples ? std::max(0, options.model_sample_count) : 0;
    if (perpendicular && model_count > 0)
        throw std::invalid_argument("pixel fit: model samples lie along the ray");
    if (!(options.board_weight > 0) && model_count == 0)
        throw std::invalid_argument("pixel fit: no samples are fitted (board weight 0, no model)");
    const TableModel model = info.model;
    const bool along_ray = !perpendicular;
    PixelFit result;
    result.table = CoefficientTable(info);
    result.rms_x = Image<float>(camera, 1, kNaN);
    result.rms_y = Image<float>(camera, 1, kNaN);
    result.rms_z = Image<float>(camera, 1, kNaN);
    result.sigma_z = Image<float>(camera, 1, kNaN);
    result.samples = Image<std::uint16_t>(camera);

    const std::size_t pose_count = poses.size();
    const int unknowns = model_coefficients(model);
    ThreadPool& pool = ThreadPool::shared(options.threads);
    const auto workers = static_cast<std::size_t>(pool.size());
    std::vector<std::size_t> too_few(workers, 0), ill(workers, 0), modelled(workers, 0);
    CoefficientTable& table = result.table;
    pool.parallel_for(camera.height, 4, [&](int row_begin, int row_end, int worker) {
        // Per pixel and pose: normalised phase t, the point X, Y, Z and the
        // weight (scratch allocated once per chunk of rows).
        const std::size_t capacity = pose_count + std::size_t(model_count);
        std::vector<double> phase(capacity), t(capacity), X(capacity), Y(capacity), Z(capacity),
            w(capacity), wz(capacity);
        const auto wk = static_cast<std::size_t>(worker);
        const auto cubic_row = [&](std::size_t k, double* r) {
            r[0] = 1;
            r[1] = t[k];
            r[2] = t[k] * t[k];
            r[3] = r[2] * t[k];
        };
        const auto rational_row = [&](std::size_t k, double* r) {
            cubic_row(k, r);
            r[4] = -t[k] * Z[k];
        };
        for (int v = row_begin; v < row_end; ++v)
            for (int u = 0; u < camera.width; ++u) {
                const std::size_t i = std::size_t(v) * std::size_t(camera.width) + std::size_t(u);
                const double xn = double(rays.data()[2 * i]), yn = double(rays.data()[2 * i + 1]);
                std::size_t n = 0;
                double lo = std::numeric_limits<double>::infinity(), hi = -lo;
                for (const PoseSamples& s : poses) {
                    const double p = double(s.phase.data()[i]);
                    const double weight = s.weight.empty() ? 1.0 : double(s.weight.data()[i]);
                    if (!std::isfinite(p) || !(weight > 0) || !std::isfinite(xn))
                        continue;
                    const Vec3& nrm = s.plane.normal;
                    if (along_ray) {
                        // The pixel's line of sight meets the plane.
                        Z[n] = s.plane.d / (nrm[0] * xn + nrm[1] * yn + nrm[2]);
                        X[n] = xn * Z[n];
                        Y[n] = yn * Z[n];
                    } else {
                        // The paper's correction: foot of the perpendicular.
                        const double z = double(s.sv_depth.data()[i]);
                        if (!std::isfinite(z))
                            continue;
                        const double x = xn * z, y = yn * z;
                        const double dist = nrm[0] * x + nrm[1] * y + nrm[2] * z - s.plane.d;
                        X[n] = x - dist * nrm[0];
                        Y[n] = y - dist * nrm[1];
                        Z[n] = z - dist * nrm[2];
                    }
                    if (!std::isfinite(Z[n]))
                        continue;
                    phase[n] = p;
                    w[n] = weight * options.board_weight;
                    lo = std::min(lo, p);
                    hi = std::max(hi, p);
                    ++n;
                }
                result.samples.data()[i] =
                    static_cast<std::uint16_t>(std::min<std::size_t>(n, 65535));
                if (n < static_cast<std::size_t>(options.min_samples)) {
                    ++too_few[wk];
                    continue;
                }
                const std::size_t board_n = n;
                if (model_count > 0) {
                    double z_near = Z[0], z_far = Z[0];
                    for (std::size_t k = 1; k < n; ++k) {
                        z_near = std::min(z_near, Z[k]);
                        z_far = std::max(z_far, Z[k]);
                    }
                    const int added =
                        options.model_samples(u, v, z_near, z_far, &phase[n], &Z[n], model_count);
                    for (int k = 0; k < added; ++k, ++n) {
                        X[n] = xn * Z[n];
                        Y[n] = yn * Z[n];
                        w[n] = options.model_weight;
                        lo = std::min(lo, phase[n]);
                        hi = std::max(hi, phase[n]);
                    }
                }
                const double centre = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
                if (!(half > 0)) {
                    ++ill[wk];
                    continue;
                }
                for (std::size_t k = 0; k < n; ++k)
                    t[k] = (phase[k] - centre) / half;
                // Coefficients of X, Y, Z (polynomial) or of Z alone (in cz).
                double coeffs[3][5] = {};
                double* cx = coeffs[0];
                double* cy = coeffs[1];
                double* cz = coeffs[model == TableModel::polynomial ? 2 : 0];
                bool ok = true;
                if (model == TableModel::polynomial) {
                    const double* values[3] = {X.data(), Y.data(), Z.data()};
                    ok = least_squares(4, n, cubic_row, 3, values, w.data(), options.max_condition,
                                       coeffs);
                } else if (model == TableModel::ray) {
                    const double* values[1] = {Z.data()};
                    ok = least_squares(4, n, cubic_row, 1, values, w.data(), options.max_condition,
                                       coeffs);
                } else {
                    // Z (1 + d t) = cubic(t) is linear in the unknowns; a second
                    // solve weighted by 1 / (1 + d t)^2 turns its residuals
                    // into depth residuals (Sanathanan-Koerner).
                    const double* values[1] = {Z.data()};
                    ok = least_squares(5, n, rational_row, 1, values, w.data(),
                                       options.max_condition, coeffs);
                    if (ok) {
                        for (std::size_t k = 0; k < n; ++k) {
                            const double den = 1 + cz[4] * t[k];
                            wz[k] = w[k] / (den * den);
                        }
                        ok = least_squares(5, n, rational_row, 1, values, wz.data(),
                                           options.max_condition, coeffs);
                    }
                    // The pole must stay outside the calibrated range.
                    ok = ok && std::fabs(cz[4]) < 0.9;
                }
                if (!ok) {
                    ++ill[wk];
                    continue;
                }
                const auto z_model = [&](double tk) {
                    const double num = cubic(cz, tk);
                    return model == TableModel::rational ? num / (1 + cz[4] * tk) : num;
                };
                // Fit RMS over the board samples (the measurement the table is
                // judged by); the depth sigma from the fitted samples' residuals
                // (unbiased) times the mean leverage p / n.
                double board2[3] = {0, 0, 0}, fit2 = 0, wsum = 0;
                std::size_t fitted = 0;
                for (std::size_t k = 0; k < n; ++k) {
                    const double dz = z_model(t[k]) - Z[k];
                    if (k < board_n) {
                        if (along_ray) {
                            board2[0] += dz * dz * xn * xn;
                            board2[1] += dz * dz * yn * yn;
                        } else {
                            const double dx = cubic(cx, t[k]) - X[k], dy = cubic(cy, t[k]) - Y[k];
                            board2[0] += dx * dx;
                            board2[1] += dy * dy;
                        }
                        board2[2] += dz * dz;
                    }
                    if (w[k] > 0) {
                        fit2 += w[k] * dz * dz;
                        wsum += w[k];
                        ++fitted;
                    }
                }
                const auto nb = double(board_n);
                result.rms_x.data()[i] = static_cast<float>(std::sqrt(board2[0] / nb));
                result.rms_y.data()[i] = static_cast<float>(std::sqrt(board2[1] / nb));
                result.rms_z.data()[i] = static_cast<float>(std::sqrt(board2[2] / nb));
                const double dof = double(fitted) - double(unknowns);
                result.sigma_z.data()[i] =
                    dof > 0 ? static_cast<float>(std::sqrt(fit2 / wsum / dof * double(unknowns)))
                            : kNaN;
                const auto put = [&](int plane, double value) {
                    table.set(plane, u, v, static_cast<float>(value));
                };
                put(table_plane::centre, centre);
                put(table_plane::inv_half_range, 1.0 / half);
                if (model == TableModel::polynomial) {
                    for (int k = 0; k < 4; ++k) {
                        put(table_plane::poly_x + k, cx[k]);
                        put(table_plane::poly_y + k, cy[k]);
                        put(table_plane::poly_z + k, cz[k]);
                    }
                } else if (model == TableModel::ray) {
                    for (int k = 0; k < 4; ++k)
                        put(table_plane::ray_z + k, cz[k]);
                    put(table_plane::ray_xn, xn);
                    put(table_plane::ray_yn, yn);
                } else {
                    for (int k = 0; k < 4; ++k)
                        put(table_plane::rational_z + k, cz[k]);
                    put(table_plane::rational_d, cz[4]);
                    put(table_plane::rational_xn, xn);
                    put(table_plane::rational_yn, yn);
                }
                ++modelled[wk];
            }
    });
    for (std::size_t k = 0; k < workers; ++k) {
        result.too_few += too_few[k];
        result.ill_conditioned += ill[k];
        result.modelled += modelled[k];
    }
    result.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
    return result;
}

} // namespace fpp::calib
