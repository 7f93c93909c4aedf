// The stereo bundle adjustment (see bundle_adjustment.hpp).

#include "bundle_adjustment.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace fpp::calib::detail {

namespace {

using vec::add;
using vec::cross;

// Adds an increment in the order of kLensParameters.
void add_lens_parameters(LensModel& l, const double* delta) {
    l.fu += delta[0];
    l.fv += delta[1];
    l.cu += delta[2];
    l.cv += delta[3];
    l.skew += delta[4];
    l.k1 += delta[5];
    l.k2 += delta[6];
    l.p1 += delta[7];
    l.p2 += delta[8];
    l.k3 += delta[9];
}

// Where each block of parameters sits in the full parameter vector, and
// which of them are free (column in the normal equations, or -1).
class Layout {
public:
    Layout(const RigState& s, const FreeParameters& free, const std::vector<bool>& pose_used)
        : camera_grid_points_(s.camera_grid.control_points()),
          projector_grid_points_(s.projector_grid.control_points()),
          poses_(static_cast<int>(s.poses.size())) {
        camera_lens_ = 0;
        projector_lens_ = camera_lens_ + kLensParameters;
        stereo_ = projector_lens_ + kLensParameters;
        camera_grid_ = stereo_ + 6;
        projector_grid_ = camera_grid_ + 2 * camera_grid_points_;
        poses_offset_ = projector_grid_ + 2 * projector_grid_points_;
        size_ = poses_offset_ + 6 * poses_;
        column_.assign(std::size_t(size_), -1);
        auto open = [&](int first, int count) {
            for (int k = first; k < first + count; ++k)
                column_[std::size_t(k)] = columns_++;
        };
        auto open_lens = [&](int first) {
            for (int k = 0; k < kLensParameters; ++k)
                if (free.skew || k != 4)
                    column_[std::size_t(first + k)] = columns_++;
        };
        if (free.camera_lens)
            open_lens(camera_lens_);
        if (free.projector_lens)
            open_lens(projector_lens_);
        if (free.stereo)
            open(stereo_, 6);
        if (free.camera_grid)
            open(camera_grid_, 2 * camera_grid_points_);
        if (free.projector_grid)
            open(projector_grid_, 2 * projector_grid_points_);
        if (free.poses)
            for (int i = 0; i < poses_; ++i)
                if (pose_used[std::size_t(i)])
                    open(poses_offset_ + 6 * i, 6);
    }

    int size() const { return size_; }
    int columns() const { return columns_; }
    int column(int full) const { return column_[std::size_t(full)]; }
    int camera_lens() const { return camera_lens_; }
    int projector_lens() const { return projector_lens_; }
    int stereo() const { return stereo_; }
    int camera_grid() const { return camera_grid_; }
    int projector_grid() const { return projector_grid_; }
    int pose(int i) const { return poses_offset_ + 6 * i; }

    // Applies a full-size increment to a state.
    void apply(RigState& s, const std::vector<double>& d) const {
        add_lens_parameters(s.camera, d.data() + camera_lens_);
        add_lens_parameters(s.projector, d.data() + projector_lens_);
        const double* st = d.data() + stereo_;
        s.R = mul(rotation_from_vector({st[0], st[1], st[2]}), s.R);
        s.T = add(s.T, {st[3], st[4], st[5]});
        for (int k = 0; k < camera_grid_points_; ++k) {
            s.camera_grid.values()[std::size_t(k)][0] += d[std::size_t(camera_grid_ + 2 * k)];
            s.camera_grid.values()[std::size_t(k)][1] += d[std::size_t(camera_grid_ + 2 * k + 1)];
        }
        for (int k = 0; k < projector_grid_points_; ++k) {
            s.projector_grid.values()[std::size_t(k)][0] += d[std::size_t(projector_grid_ + 2 * k)];
            s.projector_grid.values()[std::size_t(k)][1] +=
                d[std::size_t(projector_grid_ + 2 * k + 1)];
        }
        for (int i = 0; i < poses_; ++i) {
            const double* p = d.data() + pose(i);
            RigidPose& q = s.poses[std::size_t(i)];
            q.R = mul(rotation_from_vector({p[0], p[1], p[2]}), q.R);
            q.t = add(q.t, {p[3], p[4], p[5]});
        }
    }

private:
    int camera_grid_points_, projector_grid_points_, poses_;
    int camera_lens_ = 0, projector_lens_ = 0, stereo_ = 0, camera_grid_ = 0, projector_grid_ = 0,
        poses_offset_ = 0, size_ = 0, columns_ = 0;
    std::vector<int> column_;
};

// The Jacobian of one observation's two residuals: (column, d r_u, d r_v)
// for each free lens and rigid-transform parameter it touches, and the
// correction grid's control points that move it: a control point's u
// displacement moves only the pixel's u, its v only the v, both by the
// point's B-spline weight.
struct JacobianRow {
    static constexpr int kMax = kLensParameters + 6 + 6;
    int count = 0;
    int column[kMax];
    double du[kMax], dv[kMax];
    int grid_count = 0;
    int grid_u[CorrectionGrid::kSupport], grid_v[CorrectionGrid::kSupport];
    double grid_weight[CorrectionGrid::kSupport];
    void clear() { count = grid_count = 0; }
    void add(int col, double a, double b) {
        if (col < 0)
            return;
        column[count] = col;
        du[count] = a;
        dv[count] = b;
        ++count;
    }
    // A grid's columns are free together or not at all.
    void add_grid(int col_u, int col_v, double weight) {
        if (col_u < 0)
            return;
        grid_u[grid_count] = col_u;
        grid_v[grid_count] = col_v;
        grid_weight[grid_count] = weight;
        ++grid_count;
    }
};

// Neighbouring observations fall in one cell of a correction grid, so
// their grid products go to the same elements of the normal matrix: a run
// of such rows is summed here, in small contiguous arrays, and added to the
// matrix once (adds scattered over a matrix of a few hundred columns were
// most of an observation's time).
struct GridRun {
    static constexpr int kGrid = CorrectionGrid::kSupport;
    bool active = false;
    int shared_count = 0;
    int shared_column[JacobianRow::kMax];
    int grid_u[kGrid], grid_v[kGrid];
    double grid_grid[kGrid][kGrid];                 // sum of w w_k w_l, l <= k
    double grid_u_shared[kGrid][JacobianRow::kMax]; // sum of w w_k du_a
    double grid_v_shared[kGrid][JacobianRow::kMax]; // sum of w w_k dv_a

    // Whether a row moves the same grid cell and lens and rigid parameters.
    bool matches(const JacobianRow& j) const {
        if (!active || j.grid_u[0] != grid_u[0] || j.count != shared_count)
            return false;
        for (int a = 0; a < j.count; ++a)
            if (j.column[a] != shared_column[a])
                return false;
        return true;
    }
    void start(const JacobianRow& j) {
        active = true;
        shared_count = j.count;
        std::copy(j.column, j.column + j.count, shared_column);
        std::copy(j.grid_u, j.grid_u + kGrid, grid_u);
        std::copy(j.grid_v, j.grid_v + kGrid, grid_v);
        std::fill(&grid_grid[0][0], &grid_grid[0][0] + kGrid * kGrid, 0.0);
        std::fill(&grid_u_shared[0][0], &grid_u_shared[0][0] + kGrid * JacobianRow::kMax, 0.0);
        std::fill(&grid_v_shared[0][0], &grid_v_shared[0][0] + kGrid * JacobianRow::kMax, 0.0);
    }
    void add(const JacobianRow& j, double w) {
        for (int k = 0; k < kGrid; ++k) {
            const double wk = w * j.grid_weight[k];
            for (int l = 0; l <= k; ++l)
                grid_grid[k][l] += wk * j.grid_weight[l];
            for (int a = 0; a < shared_count; ++a) {
                grid_u_shared[k][a] += wk * j.du[a];
                grid_v_shared[k][a] += wk * j.dv[a];
            }
        }
    }
};

// Normal equations A x = -g of the free parameters (lower triangle of A)
// and the cost.
struct Normal {
    Eigen::MatrixXd A;
    Eigen::VectorXd g;
    double cost = 0;
    void reset(int n) {
        A.setZero(n, n);
        g.setZero(n);
        cost = 0;
        run_.active = false;
    }
    void add(int a, int b, double value) {
        if (a >= b)
            A(a, b) += value;
        else
            A(b, a) += value;
    }
    // The products of a grid's u column with a v residual, or of its v
    // column with a u residual, are zero and skipped. A row's grid products
    // join the current run (flush() before A is read).
    void accumulate(const JacobianRow& j, double ru, double rv, double w) {
        for (int a = 0; a < j.count; ++a) {
            const int ca = j.column[a];
            g(ca) += w * (j.du[a] * ru + j.dv[a] * rv);
            for (int b = 0; b <= a; ++b)
                add(ca, j.column[b], w * (j.du[a] * j.du[b] + j.dv[a] * j.dv[b]));
        }
        if (j.grid_count == 0)
            return;
        for (int k = 0; k < j.grid_count; ++k) {
            const double wk = j.grid_weight[k];
            g(j.grid_u[k]) += w * (wk * ru);
            g(j.grid_v[k]) += w * (wk * rv);
        }
        if (!run_.matches(j)) {
            flush();
            run_.start(j);
        }
        run_.add(j, w);
    }
    // Adds the current run's sums to A.
    void flush() {
        if (!run_.active)
            return;
        for (int k = 0; k < GridRun::kGrid; ++k) {
            for (int l = 0; l <= k; ++l) {
                add(run_.grid_u[k], run_.grid_u[l], run_.grid_grid[k][l]);
                add(run_.grid_v[k], run_.grid_v[l], run_.grid_grid[k][l]);
            }
            for (int a = 0; a < run_.shared_count; ++a) {
                add(run_.grid_u[k], run_.shared_column[a], run_.grid_u_shared[k][a]);
                add(run_.grid_v[k], run_.shared_column[a], run_.grid_v_shared[k][a]);
            }
        }
        run_.active = false;
    }
    // Adds another (flushed) set's terms.
    void add(const Normal& other) {
        A.triangularView<Eigen::Lower>() += other.A;
        g += other.g;
        cost += other.cost;
    }

private:
    GridRun run_;
};

// The device-side part of an observation's Jacobian: lens and grid.
void add_device(JacobianRow& row, const Layout& layout, const Projection& p, int lens_offset,
                int grid_offset, bool has_grid) {
    for (int k = 0; k < kLensParameters; ++k)
        row.add(layout.column(lens_offset + k), p.d_lens[0][k], p.d_lens[1][k]);
    if (!has_grid)
        return;
    for (int k = 0; k < CorrectionGrid::kSupport; ++k) {
        const int c = grid_offset + 2 * p.grid_index[k];
        row.add_grid(layout.column(c), layout.column(c + 1), p.grid_weight[k]);
    }
}

// d pixel / d (w, t) of a rigid transform X = exp([w]x) R X0 + t at its
// parameters' columns from `base`, given d pixel / d X (2 x 3) and the
// rotated point R X0: d X / d w = -[R X0]x, d X / d t = I.
void add_rigid(JacobianRow& row, const Layout& layout, int base, const double dX[2][3],
               const Vec3& rotated) {
    for (int k = 0; k < 3; ++k) {
        Vec3 e{0, 0, 0};
        e[std::size_t(k)] = 1;
        const Vec3 dXdw = cross(e, rotated); // column k of -[r]x
        row.add(layout.column(base + k),
                dX[0][0] * dXdw[0] + dX[0][1] * dXdw[1] + dX[0][2] * dXdw[2],
                dX[1][0] * dXdw[0] + dX[1][1] * dXdw[1] + dX[1][2] * dXdw[2]);
    }
    for (int k = 0; k < 3; ++k)
        row.add(layout.column(base + 3 + k), dX[0][k], dX[1][k]);
}

// The data terms of some observations: weighted squared residuals, their
// count, and whether a point fell behind a device.
struct DataTerms {
    double cost = 0;
    int rows = 0;
    bool behind = false;
};

class Problem {
public:
    Problem(const RigState& start, const std::vector<CornerObservation>& corners,
            const std::vector<DenseObservation>& dense, const std::vector<bool>& pose_used,
            const FreeParameters& free, const GridRegularisation& reg, ThreadPool* pool)
        : corners_(corners), dense_(dense), used_(pose_used), free_(free), reg_(reg),
          camera_gauge_(gauge_fields(start.camera_grid, start.camera)),
          projector_gauge_(gauge_fields(start.projector_grid, start.projector)), pool_(pool) {}

    // Cost of a state (data and regularisation); with `normal`, also the
    // normal equations. Returns +inf when a point falls behind a device.
    // Many observations (dense samples) are taken in chunks, on the pool's
    // threads when there is one, each into normal equations of its own that
    // are then added in chunk order: the chunks depend on the observations
    // alone, so the sums do not depend on the threads.
    double evaluate(const RigState& s, const Layout& layout, Normal* normal,
                    int* residual_rows = nullptr) {
        const std::size_t count =
            corners_.size() + (free_.projector_observations ? dense_.size() : 0);
        const int chunks =
            static_cast<int>(std::clamp<std::size_t>(count / kChunkObservations, 1, kMaxChunks));
        DataTerms data;
        if (chunks == 1) {
            data = evaluate_observations(s, layout, 0, count, normal);
        } else {
            chunk_normals_.resize(std::size_t(chunks));
            chunk_terms_.assign(std::size_t(chunks), {});
            const auto run = [&](int begin, int end, int) {
                for (int c = begin; c < end; ++c) {
                    Normal* part = nullptr;
                    if (normal) {
                        part = &chunk_normals_[std::size_t(c)];
                        part->reset(layout.columns());
                    }
                    chunk_terms_[std::size_t(c)] = evaluate_observations(
                        s, layout, count * std::size_t(c) / std::size_t(chunks),
                        count * std::size_t(c + 1) / std::size_t(chunks), part);
                }
            };
            if (pool_)
                pool_->parallel_for(chunks, 1, run);
            else
                run(0, chunks, 0);
            for (int c = 0; c < chunks; ++c) {
                const DataTerms& t = chunk_terms_[std::size_t(c)];
                data.cost += t.cost;
                data.rows += t.rows;
                data.behind = data.behind || t.behind;
                if (normal && !t.behind)
                    normal->add(chunk_normals_[std::size_t(c)]);
            }
        }
        if (data.behind)
            return std::numeric_limits<double>::infinity();
        double cost = data.cost;
        if (normal)
            normal->cost = cost;
        if (residual_rows)
            *residual_rows = data.rows;
        if (free_.camera_grid)
            cost += regularise(s.camera_grid, camera_gauge_, reg_.camera_smoothness, layout,
                               layout.camera_grid(), normal);
        if (free_.projector_grid)
            cost += regularise(s.projector_grid, projector_gauge_, reg_.projector_smoothness,
                               layout, layout.projector_grid(), normal);
        return cost;
    }

private:
    static constexpr std::size_t kChunkObservations = 4096;
    static constexpr std::size_t kMaxChunks = 8;

    // Observations [begin, end): the corners (each with its camera and its
    // projector observation), then the dense samples. Stops at a point
    // behind a device.
    DataTerms evaluate_observations(const RigState& s, const Layout& layout, std::size_t begin,
                                    std::size_t end, Normal* normal) const {
        DataTerms out;
        Projection p;
        Vec2 r; // residual, pixels: projected - observed
        JacobianRow row;
        const bool derivatives = normal != nullptr;
        for (std::size_t i = begin; i < std::min(end, corners_.size()); ++i) {
            const CornerObservation& o = corners_[i];
            if (!used_[std::size_t(o.pose)])
                continue;
            const RigidPose& pose = s.poses[std::size_t(o.pose)];
            const Vec3 rotated = mul(pose.R, o.board);
            const Vec3 xc = add(rotated, pose.t);
            if (free_.camera_observations) {
                if (!observe(s.camera, s.camera_grid, xc, o.camera, free_.camera_weight, p, r, out))
                    return out;
                if (derivatives) {
                    row.clear();
                    add_device(row, layout, p, layout.camera_lens(), layout.camera_grid(),
                               free_.camera_grid);
                    add_rigid(row, layout, layout.pose(o.pose), p.d_point, rotated);
                    normal->accumulate(row, r[0], r[1], free_.camera_weight);
                }
            }
            if (free_.projector_observations && std::isfinite(o.projector[0]) &&
                std::isfinite(o.projector[1])) {
                const Vec3 rc = mul(s.R, xc);
                const Vec3 xp = add(rc, s.T);
                if (!observe(s.projector, s.projector_grid, xp, o.projector, free_.projector_weight,
                             p, r, out))
                    return out;
                if (derivatives) {
                    row.clear();
                    add_device(row, layout, p, layout.projector_lens(), layout.projector_grid(),
                               free_.projector_grid);
                    add_stereo(row, layout, p, rc);
                    // d X_p / d X_c = R.
                    double dX[2][3];
                    chain_rotation(p.d_point, s.R, dX);
                    add_rigid(row, layout, layout.pose(o.pose), dX, rotated);
                    normal->accumulate(row, r[0], r[1], free_.projector_weight);
                }
            }
        }
        for (std::size_t i = std::max(begin, corners_.size()); i < end; ++i) {
            const DenseObservation& o = dense_[i - corners_.size()];
            if (o.pose >= 0 && !used_[std::size_t(o.pose)])
                continue;
            const Vec3 rc = mul(s.R, o.camera_point);
            const Vec3 xp = add(rc, s.T);
            const double weight = o.weight * free_.dense_weight;
            if (!observe(s.projector, s.projector_grid, xp, o.projector, weight, p, r, out))
                return out;
            if (derivatives) {
                row.clear();
                add_device(row, layout, p, layout.projector_lens(), layout.projector_grid(),
                           free_.projector_grid);
                add_stereo(row, layout, p, rc);
                normal->accumulate(row, r[0], r[1], weight);
            }
        }
        if (normal)
            normal->flush();
        return out;
    }

private:
    // Projects `point` (device frame, mm) through a device into `p`, sets
    // `residual` (projected - observed, pixels) and adds its weighted
    // square to `out`; false, with out.behind set, for a point behind it.
    static bool observe(const LensModel& lens, const CorrectionGrid& grid, const Vec3& point,
                        const Vec2& observed, double weight, Projection& p, Vec2& residual,
                        DataTerms& out) {
        if (!project_with_derivatives(lens, grid, point, p)) {
            out.behind = true;
            return false;
        }
        residual = {p.pixel[0] - observed[0], p.pixel[1] - observed[1]};
        out.cost += weight * (residual[0] * residual[0] + residual[1] * residual[1]);
        out.rows += 2;
        return true;
    }

    static void chain_rotation(const double d[2][3], const Mat3& R, double out[2][3]) {
        for (int r = 0; r < 2; ++r)
            for (int c = 0; c < 3; ++c)
                out[r][c] = d[r][0] * R[std::size_t(c)] + d[r][1] * R[std::size_t(3 + c)] +
                            d[r][2] * R[std::size_t(6 + c)];
    }

    void add_stereo(JacobianRow& row, const Layout& layout, const Projection& p,
                    const Vec3& rotated) const {
        if (free_.stereo)
            add_rigid(row, layout, layout.stereo(), p.d_point, rotated);
    }

    // Smoothness and ridge terms of one grid (each coordinate alone), and
    // its gauge: no component along the gauge fields.
    double regularise(const CorrectionGrid& grid, const std::vector<std::vector<Vec2>>& gauge,
                      double smoothness, const Layout& layout, int offset, Normal* normal) const {
        double cost = 0;
        const std::vector<Vec2>& v = grid.values();
        // Far above every observation's weight: a constraint, not a preference.
        const double kGaugeWeight =
            1e6 * std::max({1.0, free_.camera_weight, free_.projector_weight, free_.dense_weight});
        for (const std::vector<Vec2>& f : gauge) {
            double dot = 0;
            for (std::size_t k = 0; k < v.size(); ++k)
                dot += f[k][0] * v[k][0] + f[k][1] * v[k][1];
            cost += kGaugeWeight * dot * dot;
            if (!normal)
                continue;
            for (std::size_t a = 0; a < 2 * v.size(); ++a) {
                const double fa = f[a / 2][a % 2];
                const int ca = layout.column(offset + int(a));
                normal->g(ca) += kGaugeWeight * fa * dot;
                for (std::size_t b = 0; b <= a; ++b) {
                    const int cb = layout.column(offset + int(b));
                    const double value = kGaugeWeight * fa * f[b / 2][b % 2];
                    if (ca >= cb)
                        normal->A(ca, cb) += value;
                    else
                        normal->A(cb, ca) += value;
                }
            }
        }
        for (int axis = 0; axis < 2; ++axis) {
            for_each_smoothness_term(
                grid.columns(), grid.rows(), [&](const int* idx, const double* c, int n) {
                    double diff = 0;
                    for (int k = 0; k < n; ++k)
                        diff += c[k] * v[std::size_t(idx[k])][std::size_t(axis)];
                    cost += smoothness * diff * diff;
                    if (!normal)
                        return;
                    for (int a = 0; a < n; ++a) {
                        const int ca = layout.column(offset + 2 * idx[a] + axis);
                        normal->g(ca) += smoothness * c[a] * diff;
                        for (int b = 0; b < n; ++b) {
                            const int cb = layout.column(offset + 2 * idx[b] + axis);
                            if (ca >= cb)
                                normal->A(ca, cb) += smoothness * c[a] * c[b];
                        }
                    }
                });
            for (int k = 0; k < grid.control_points(); ++k) {
                const double value = v[std::size_t(k)][std::size_t(axis)];
                cost += reg_.ridge * value * value;
                if (normal) {
                    const int c = layout.column(offset + 2 * k + axis);
                    normal->g(c) += reg_.ridge * value;
                    normal->A(c, c) += reg_.ridge;
                }
            }
        }
        return cost;
    }

    const std::vector<CornerObservation>& corners_;
    const std::vector<DenseObservation>& dense_;
    const std::vector<bool>& used_;
    FreeParameters free_;
    GridRegularisation reg_;
    std::vector<std::vector<Vec2>> camera_gauge_, projector_gauge_;
    ThreadPool* pool_;
    // Scratch of evaluate(), kept from one evaluation to the next.
    std::vector<Normal> chunk_normals_;
    std::vector<DataTerms> chunk_terms_;
};

} // namespace

bool project_with_derivatives(const LensModel& lens, const CorrectionGrid& grid, const Vec3& X,
                              Projection& out) {
    if (!(X[2] > 0))
        return false;
    const double iz = 1 / X[2];
    const double x = X[0] * iz, y = X[1] * iz;
    const Vec2 d = lens.distort({x, y});
    const Mat2 Jd = lens.distortion_jacobian({x, y});
    const double fu = lens.fu, fv = lens.fv, s = lens.skew;
    const Vec2 model{fu * d[0] + s * d[1] + lens.cu, fv * d[1] + lens.cv};
    // d model / d (xd, yd) = K2 = [fu s; 0 fv]; d (xd, yd) / d (x, y) = Jd;
    // d (x, y) / d X = [1/Z 0 -x/Z; 0 1/Z -y/Z].
    const double KJ[2][2] = {{fu * Jd[0] + s * Jd[2], fu * Jd[1] + s * Jd[3]},
                             {fv * Jd[2], fv * Jd[3]}};
    double dp_dX[2][3];
    for (int r = 0; r < 2; ++r) {
        dp_dX[r][0] = KJ[r][0] * iz;
        dp_dX[r][1] = KJ[r][1] * iz;
        dp_dX[r][2] = -(KJ[r][0] * x + KJ[r][1] * y) * iz;
    }
    // d (xd, yd) / d (k1 k2 p1 p2 k3).
    const double r2 = x * x + y * y;
    const double dd[2][5] = {{x * r2, x * r2 * r2, 2 * x * y, r2 + 2 * x * x, x * r2 * r2 * r2},
                             {y * r2, y * r2 * r2, r2 + 2 * y * y, 2 * x * y, y * r2 * r2 * r2}};
    double dp_dl[2][kLensParameters] = {{d[0], 0, 1, 0, d[1]}, {0, d[1], 0, 1, 0}};
    for (int k = 0; k < 5; ++k) {
        dp_dl[0][5 + k] = fu * dd[0][k] + s * dd[1][k];
        dp_dl[1][5 + k] = fv * dd[1][k];
    }
    // The grid: pixel = model + delta(model); d pixel / d model = I + G.
    Mat2 G{0, 0, 0, 0};
    Vec2 delta{0, 0};
    if (!grid.empty()) {
        grid.support_and_jacobian(model, out.grid_index, out.grid_weight, G);
        for (int k = 0; k < CorrectionGrid::kSupport; ++k) {
            const Vec2& c = grid.values()[std::size_t(out.grid_index[k])];
            delta[0] += out.grid_weight[k] * c[0];
            delta[1] += out.grid_weight[k] * c[1];
        }
    }
    const double M[2][2] = {{1 + G[0], G[1]}, {G[2], 1 + G[3]}};
    out.pixel = {model[0] + delta[0], model[1] + delta[1]};
    for (int r = 0; r < 2; ++r) {
        for (int c = 0; c < 3; ++c)
            out.d_point[r][c] = M[r][0] * dp_dX[0][c] + M[r][1] * dp_dX[1][c];
        for (int c = 0; c < kLensParameters; ++c)
            out.d_lens[r][c] = M[r][0] * dp_dl[0][c] + M[r][1] * dp_dl[1][c];
    }
    return std::isfinite(out.pixel[0]) && std::isfinite(out.pixel[1]);
}

Linearisation linearise(const RigState& state, const std::vector<CornerObservation>& corners,
                        const std::vector<DenseObservation>& dense,
                        const std::vector<bool>& pose_used, const FreeParameters& free,
                        const GridRegularisation& regularisation, const RigState* start) {
    const Layout layout(state, free, pose_used);
    Problem problem(start ? *start : state, corners, dense, pose_used, free, regularisation,
                    nullptr);
    Normal normal;
    normal.reset(layout.columns());
    Linearisation out;
    out.cost = problem.evaluate(state, layout, &normal);
    out.gradient.assign(normal.g.data(), normal.g.data() + normal.g.size());
    return out;
}

NormalEquations normal_equations(const RigState& state,
                                 const std::vector<CornerObservation>& corners,
                                 const std::vector<DenseObservation>& dense,
                                 const std::vector<bool>& pose_used, const FreeParameters& free,
                                 const GridRegularisation& regularisation, ThreadPool* pool) {
    const Layout layout(state, free, pose_used);
    Problem problem(state, corners, dense, pose_used, free, regularisation, pool);
    Normal normal;
    normal.reset(layout.columns());
    NormalEquations out;
    if (!std::isfinite(problem.evaluate(state, layout, &normal, &out.residuals)))
        throw std::runtime_error("bundle adjustment: a board point lies behind a device");
    out.data_cost = normal.cost;
    out.g = std::move(normal.g);
    out.A = normal.A.selfadjointView<Eigen::Lower>();
    out.full_index.assign(std::size_t(layout.columns()), -1);
    for (int k = 0; k < layout.size(); ++k)
        if (const int c = layout.column(k); c >= 0)
            out.full_index[std::size_t(c)] = k;
    return out;
}

FullOrder full_order(const RigState& state) {
    const Layout layout(state, FreeParameters{}, std::vector<bool>(state.poses.size(), false));
    FullOrder o;
    o.camera_lens = layout.camera_lens();
    o.projector_lens = layout.projector_lens();
    o.stereo = layout.stereo();
    o.camera_grid = layout.camera_grid();
    o.projector_grid = layout.projector_grid();
    o.poses = state.poses.empty() ? layout.size() : layout.pose(0);
    o.size = layout.size();
    return o;
}

void apply_increment(RigState& state, const std::vector<bool>& pose_used,
                     const FreeParameters& free, const std::vector<double>& step) {
    const Layout layout(state, free, pose_used);
    std::vector<double> full(std::size_t(layout.size()), 0.0);
    for (int k = 0; k < layout.size(); ++k)
        if (const int c = layout.column(k); c >= 0)
            full[std::size_t(k)] = step.at(std::size_t(c));
    layout.apply(state, full);
}

AdjustmentOutcome adjust(RigState& state, const std::vector<CornerObservation>& corners,
                         const std::vector<DenseObservation>& dense,
                         const std::vector<bool>& pose_used, const FreeParameters& free,
                         const GridRegularisation& regularisation, int max_iterations,
                         const std::function<void(const std::string&)>& progress,
                         ThreadPool* pool) {
    const Layout layout(state, free, pose_used);
    Problem problem(state, corners, dense, pose_used, free, regularisation, pool);
    const int n = layout.columns();
    AdjustmentOutcome out;
    out.parameters = n;
    Normal normal, trial_normal;
    normal.reset(n);
    double cost = problem.evaluate(state, layout, &normal, &out.residuals);
    if (!std::isfinite(cost))
        throw std::runtime_error("bundle adjustment: a board point lies behind a device at the "
                                 "start (a failed initialisation)");
    // Small from the start: every adjustment here starts near its minimum
    // (OpenCV's start or the previous stage's result), where more damping
    // only slows the grids' smooth modes (measured on 30 full-size poses:
    // 8 and 14 iterations for the two dense stages instead of 14 and 21,
    // to the same result).
    double lambda = 1e-6;
    std::vector<double> full(std::size_t(layout.size()), 0.0);
    const auto full_step = [&](const Eigen::VectorXd& step) {
        std::fill(full.begin(), full.end(), 0.0);
        for (int k = 0; k < layout.size(); ++k) {
            const int c = layout.column(k);
            if (c >= 0)
                full[std::size_t(k)] = step(c);
        }
    };
    for (int it = 0; it < max_iterations; ++it) {
        // Scaled to unit diagonal: parameters span focal lengths of
        // thousands of pixels and distortion terms of 1e-4.
        const Eigen::MatrixXd A = normal.A.selfadjointView<Eigen::Lower>();
        Eigen::VectorXd d = A.diagonal().cwiseSqrt();
        for (Eigen::Index k = 0; k < d.size(); ++k)
            if (!(d(k) > 0))
                d(k) = 1;
        const Eigen::MatrixXd As = d.asDiagonal().inverse() * A * d.asDiagonal().inverse();
        const Eigen::VectorXd gs = d.asDiagonal().inverse() * normal.g;
        bool accepted = false;
        for (int attempt = 0; attempt < 20 && !accepted; ++attempt) {
            Eigen::MatrixXd M = As;
            M.diagonal().array() += lambda;
            const Eigen::LDLT<Eigen::MatrixXd> ldlt(M);
            const Eigen::VectorXd step_s = -ldlt.solve(gs);
            const Eigen::VectorXd step = d.asDiagonal().inverse() * step_s;
            if (!step.allFinite()) {
                lambda *= 10;
                continue;
            }
            RigState trial = state;
            full_step(step);
            layout.apply(trial, full);
            // The normal equations at the trial too, in the same pass: most
            // steps are accepted.
            trial_normal.reset(n);
            const double trial_cost = problem.evaluate(trial, layout, &trial_normal);
            if (trial_cost < cost) {
                const double decrease = (cost - trial_cost) / cost;
                state = std::move(trial);
                cost = trial_cost;
                lambda = std::max(lambda / 3, 1e-12);
                accepted = true;
                out.iterations = it + 1;
                std::swap(normal, trial_normal);
                if (progress && (it < 3 || it % 5 == 0)) {
                    std::ostringstream msg;
                    msg.precision(4);
                    msg << "  LM iteration " << it + 1 << ": RMS residual "
                        << std::sqrt(normal.cost / std::max(1, out.residuals))
                        << " px (per coordinate), lambda " << lambda;
                    progress(msg.str());
                }
                if (decrease < 1e-12 || step_s.norm() < 1e-10)
                    it = max_iterations; // converged
            } else {
                lambda *= 4;
            }
        }
        if (!accepted)
            break; // no decrease possible: at the minimum to rounding
    }
    out.data_cost = normal.cost;
    // Lens parameter variances per unit residual variance: the diagonal of
    // the inverse normal matrix (regularisation included, no damping).
    const Eigen::MatrixXd A = normal.A.selfadjointView<Eigen::Lower>();
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(A);
    for (int device = 0; device < 2; ++device)
        for (int k = 0; k < kLensParameters; ++k) {
            const int c =
                layout.column((device == 0 ? layout.camera_lens() : layout.projector_lens()) + k);
            if (c < 0)
                continue;
            Eigen::VectorXd e = Eigen::VectorXd::Zero(n);
            e(c) = 1;
            const Eigen::VectorXd x = ldlt.solve(e);
            out.lens_variance[std::size_t(device * kLensParameters + k)] = std::max(0.0, x(c));
        }
    return out;
}

} // namespace fpp::calib::detail
