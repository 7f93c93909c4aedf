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

// One pixel's samples: phase, normalised phase t, point X, Y, Z and weights
// (scratch allocated once per chunk of rows, refilled per pixel).
struct PixelSamples {
    explicit PixelSamples(std::size_t capacity)
        : phase(capacity), t(capacity), X(capacity), Y(capacity), Z(capacity), w(capacity),
          wz(capacity) {}
    std::vector<double> phase, t, X, Y, Z, w, wz;
    std::size_t n = 0;       // samples in use
    std::size_t board_n = 0; // the first board_n are the boards', the rest the model's
    double lo = 0, hi = 0;   // phase range
    double centre = 0, half = 0;
};

// The number of model samples per pixel, after checking that the inputs fit
// the table and the options ask for something fittable.
int checked_model_count(const std::vector<PoseSamples>& poses, const Image<float>& rays,
                        const TableInfo& info, const PixelFitOptions& options) {
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
    return model_count;
}

PixelFit empty_fit(const TableInfo& info) {
    PixelFit result;
    result.table = CoefficientTable(info);
    result.rms_x = Image<float>(info.camera, 1, kNaN);
    result.rms_y = Image<float>(info.camera, 1, kNaN);
    result.rms_z = Image<float>(info.camera, 1, kNaN);
    result.sigma_z = Image<float>(info.camera, 1, kNaN);
    result.samples = Image<std::uint16_t>(info.camera);
    return result;
}

enum class PixelOutcome { modelled, too_few, ill_conditioned };

// The per-pixel stages, sharing the inputs and the result they write into.
struct PixelFitter {
    const std::vector<PoseSamples>& poses;
    const Image<float>& rays;
    const PixelFitOptions& options;
    TableModel model;
    bool along_ray;
    int model_count;
    int unknowns;
    PixelFit& result;

    // Board samples: where the pixel's line of sight meets each pose's board
    // plane, or (the paper's correction) the foot of the perpendicular from
    // its SV point.
    void gather_board_samples(std::size_t i, double xn, double yn, PixelSamples& s) const {
        std::size_t n = 0;
        double lo = std::numeric_limits<double>::infinity(), hi = -lo;
        for (const PoseSamples& pose : poses) {
            const double p = double(pose.phase.data()[i]);
            const double weight = pose.weight.empty() ? 1.0 : double(pose.weight.data()[i]);
            if (!std::isfinite(p) || !(weight > 0) || !std::isfinite(xn))
                continue;
            const Vec3& nrm = pose.plane.normal;
            if (along_ray) {
                s.Z[n] = pose.plane.d / (nrm[0] * xn + nrm[1] * yn + nrm[2]);
                s.X[n] = xn * s.Z[n];
                s.Y[n] = yn * s.Z[n];
            } else {
                const double z = double(pose.sv_depth.data()[i]);
                if (!std::isfinite(z))
                    continue;
                const double x = xn * z, y = yn * z;
                const double dist = nrm[0] * x + nrm[1] * y + nrm[2] * z - pose.plane.d;
                s.X[n] = x - dist * nrm[0];
                s.Y[n] = y - dist * nrm[1];
                s.Z[n] = z - dist * nrm[2];
            }
            if (!std::isfinite(s.Z[n]))
                continue;
            s.phase[n] = p;
            s.w[n] = weight * options.board_weight;
            lo = std::min(lo, p);
            hi = std::max(hi, p);
            ++n;
        }
        s.n = n;
        s.board_n = n;
        s.lo = lo;
        s.hi = hi;
    }

    // Samples of the stereo model along the ray, over the boards' depth range.
    void add_model_samples(int u, int v, double xn, double yn, PixelSamples& s) const {
        if (model_count <= 0)
            return;
        std::size_t n = s.n;
        double z_near = s.Z[0], z_far = s.Z[0];
        for (std::size_t k = 1; k < n; ++k) {
            z_near = std::min(z_near, s.Z[k]);
            z_far = std::max(z_far, s.Z[k]);
        }
        const int added =
            options.model_samples(u, v, z_near, z_far, &s.phase[n], &s.Z[n], model_count);
        for (int k = 0; k < added; ++k, ++n) {
            s.X[n] = xn * s.Z[n];
            s.Y[n] = yn * s.Z[n];
            s.w[n] = options.model_weight;
            s.lo = std::min(s.lo, s.phase[n]);
            s.hi = std::max(s.hi, s.phase[n]);
        }
        s.n = n;
    }

    // Maps the phase range onto t in [-1, 1]; false when it is empty.
    static bool normalise_phase(PixelSamples& s) {
        s.centre = 0.5 * (s.lo + s.hi);
        s.half = 0.5 * (s.hi - s.lo);
        if (!(s.half > 0))
            return false;
        for (std::size_t k = 0; k < s.n; ++k)
            s.t[k] = (s.phase[k] - s.centre) / s.half;
        return true;
    }

    // Coefficients of X, Y, Z (polynomial) or of Z alone (coeffs[0]); false
    // when ill-conditioned or (rational) the pole falls inside the range.
    bool fit_coefficients(PixelSamples& s, double coeffs[3][5]) const {
        const auto cubic_row = [&](std::size_t k, double* r) {
            r[0] = 1;
            r[1] = s.t[k];
            r[2] = s.t[k] * s.t[k];
            r[3] = r[2] * s.t[k];
        };
        const auto rational_row = [&](std::size_t k, double* r) {
            cubic_row(k, r);
            r[4] = -s.t[k] * s.Z[k];
        };
        if (model == TableModel::polynomial) {
            const double* values[3] = {s.X.data(), s.Y.data(), s.Z.data()};
            return least_squares(4, s.n, cubic_row, 3, values, s.w.data(), options.max_condition,
                                 coeffs);
        }
        const double* values[1] = {s.Z.data()};
        if (model == TableModel::ray)
            return least_squares(4, s.n, cubic_row, 1, values, s.w.data(), options.max_condition,
                                 coeffs);
        // Z (1 + d t) = cubic(t) is linear in the unknowns; a second solve
        // weighted by 1 / (1 + d t)^2 turns its residuals into depth
        // residuals (Sanathanan-Koerner).
        const double* cz = coeffs[0];
        bool ok = least_squares(5, s.n, rational_row, 1, values, s.w.data(), options.max_condition,
                                coeffs);
        if (ok) {
            for (std::size_t k = 0; k < s.n; ++k) {
                const double den = 1 + cz[4] * s.t[k];
                s.wz[k] = s.w[k] / (den * den);
            }
            ok = least_squares(5, s.n, rational_row, 1, values, s.wz.data(), options.max_condition,
                               coeffs);
        }
        // The pole must stay outside the calibrated range.
        return ok && std::fabs(cz[4]) < 0.9;
    }

    // Fit RMS over the board samples (the measurement the table is judged
    // by); the depth sigma from the fitted samples' residuals (unbiased)
    // times the mean leverage p / n.
    void record_residuals(std::size_t i, double xn, double yn, const PixelSamples& s,
                          const double coeffs[3][5]) const {
        const double* cx = coeffs[0];
        const double* cy = coeffs[1];
        const double* cz = coeffs[model == TableModel::polynomial ? 2 : 0];
        const auto z_model = [&](double tk) {
            const double num = cubic(cz, tk);
            return model == TableModel::rational ? num / (1 + cz[4] * tk) : num;
        };
        double board2[3] = {0, 0, 0}, fit2 = 0, wsum = 0;
        std::size_t fitted = 0;
        for (std::size_t k = 0; k < s.n; ++k) {
            const double dz = z_model(s.t[k]) - s.Z[k];
            if (k < s.board_n) {
                if (along_ray) {
                    board2[0] += dz * dz * xn * xn;
                    board2[1] += dz * dz * yn * yn;
                } else {
                    const double dx = cubic(cx, s.t[k]) - s.X[k], dy = cubic(cy, s.t[k]) - s.Y[k];
                    board2[0] += dx * dx;
                    board2[1] += dy * dy;
                }
                board2[2] += dz * dz;
            }
            if (s.w[k] > 0) {
                fit2 += s.w[k] * dz * dz;
                wsum += s.w[k];
                ++fitted;
            }
        }
        const auto nb = double(s.board_n);
        result.rms_x.data()[i] = static_cast<float>(std::sqrt(board2[0] / nb));
        result.rms_y.data()[i] = static_cast<float>(std::sqrt(board2[1] / nb));
        result.rms_z.data()[i] = static_cast<float>(std::sqrt(board2[2] / nb));
        const double dof = double(fitted) - double(unknowns);
        result.sigma_z.data()[i] =
            dof > 0 ? static_cast<float>(std::sqrt(fit2 / wsum / dof * double(unknowns))) : kNaN;
    }

    void store_coefficients(int u, int v, double xn, double yn, const PixelSamples& s,
                            const double coeffs[3][5]) const {
        CoefficientTable& table = result.table;
        const auto put = [&](int plane, double value) {
            table.set(plane, u, v, static_cast<float>(value));
        };
        put(table_plane::centre, s.centre);
        put(table_plane::inv_half_range, 1.0 / s.half);
        if (model == TableModel::polynomial) {
            for (int k = 0; k < 4; ++k) {
                put(table_plane::poly_x + k, coeffs[0][k]);
                put(table_plane::poly_y + k, coeffs[1][k]);
                put(table_plane::poly_z + k, coeffs[2][k]);
            }
        } else if (model == TableModel::ray) {
            for (int k = 0; k < 4; ++k)
                put(table_plane::ray_z + k, coeffs[0][k]);
            put(table_plane::ray_xn, xn);
            put(table_plane::ray_yn, yn);
        } else {
            for (int k = 0; k < 4; ++k)
                put(table_plane::rational_z + k, coeffs[0][k]);
            put(table_plane::rational_d, coeffs[0][4]);
            put(table_plane::rational_xn, xn);
            put(table_plane::rational_yn, yn);
        }
    }

    // The pixel's samples, fit, residuals and table entry, in that order.
    PixelOutcome fit(int u, int v, PixelSamples& s) const {
        const std::size_t i = std::size_t(v) * std::size_t(rays.size().width) + std::size_t(u);
        const double xn = double(rays.data()[2 * i]), yn = double(rays.data()[2 * i + 1]);
        gather_board_samples(i, xn, yn, s);
        result.samples.data()[i] = static_cast<std::uint16_t>(std::min<std::size_t>(s.n, 65535));
        if (s.n < static_cast<std::size_t>(options.min_samples))
            return PixelOutcome::too_few;
        add_model_samples(u, v, xn, yn, s);
        double coeffs[3][5] = {};
        if (!normalise_phase(s) || !fit_coefficients(s, coeffs))
            return PixelOutcome::ill_conditioned;
        record_residuals(i, xn, yn, s, coeffs);
        store_coefficients(u, v, xn, yn, s, coeffs);
        return PixelOutcome::modelled;
    }
};

} // namespace

int model_coefficients(TableModel model) {
    return model == TableModel::rational ? 5 : 4;
}

PixelFit fit_pixel_models(const std::vector<PoseSamples>& poses, const Image<float>& rays,
                          const TableInfo& info, const PixelFitOptions& options) {
    const auto t_start = std::chrono::steady_clock::now();
    const int model_count = checked_model_count(poses, rays, info, options);
    PixelFit result = empty_fit(info);
    const PixelFitter fitter{poses,
                             rays,
                             options,
                             info.model,
                             options.correction != PlaneCorrection::perpendicular_foot,
                             model_count,
                             model_coefficients(info.model),
                             result};

    ThreadPool& pool = ThreadPool::shared(options.threads);
    const auto workers = static_cast<std::size_t>(pool.size());
    std::vector<std::size_t> too_few(workers, 0), ill(workers, 0), modelled(workers, 0);
    pool.parallel_for(info.camera.height, 4, [&](int row_begin, int row_end, int worker) {
        PixelSamples samples(poses.size() + std::size_t(model_count));
        const auto wk = static_cast<std::size_t>(worker);
        for (int v = row_begin; v < row_end; ++v)
            for (int u = 0; u < info.camera.width; ++u) {
                switch (fitter.fit(u, v, samples)) {
                case PixelOutcome::too_few:
                    ++too_few[wk];
                    break;
                case PixelOutcome::ill_conditioned:
                    ++ill[wk];
                    break;
                case PixelOutcome::modelled:
                    ++modelled[wk];
                    break;
                }
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
