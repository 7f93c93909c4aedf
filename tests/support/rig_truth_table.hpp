#pragma once
// A rational-model coefficient table from a simulated rig's true geometry,
// for judging a scan independently of calibration error: per camera pixel,
// Z = (a0 + a1 t + a2 t^2 + a3 t^3) / (1 + d t) of the normalised projector
// column t, fitted by least squares to the true projection (projector
// distortion included) at 24 depths over 350..650 mm (camera frame, mm).
// Header-only: it needs fpp_sim, which the support library does not link.
#include "fpp/coefficient_table.hpp"
#include "fpp/lens_model.hpp"
#include "fpp/simulator/rig.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

namespace fpp::test {

// `trueness`: what the header carries (a test of its way to scan.json).
inline CoefficientTable rig_truth_table(const sim::Rig& rig, const TableTrueness& trueness = {}) {
    TableInfo info;
    info.trueness = trueness;
    info.camera = rig.camera_size;
    info.projector = rig.projector_size;
    info.model = TableModel::rational;
    info.phase_axis = Axis::x;
    CoefficientTable table(info);
    constexpr int kDepths = 24;
    for (int y = 0; y < info.camera.height; ++y) {
        for (int x = 0; x < info.camera.width; ++x) {
            Vec2 n{};
            if (!rig.camera.pixel_to_normalised({double(x), double(y)}, n))
                continue;
            std::array<double, kDepths> depth{}, column{};
            for (int k = 0; k < kDepths; ++k) {
                depth[k] = 350.0 + 300.0 * k / (kDepths - 1);
                const Vec3 p = mul(rig.R, Vec3{n[0] * depth[k], n[1] * depth[k], depth[k]});
                column[k] =
                    rig.projector.project({p[0] + rig.t[0], p[1] + rig.t[1], p[2] + rig.t[2]})[0];
            }
            const auto [lo, hi] = std::minmax_element(column.begin(), column.end());
            const double centre = 0.5 * (*lo + *hi), inv_half = 2.0 / (*hi - *lo);
            // Normal equations [A^T A | A^T z] for rows (1, t, t^2, t^3, -t z),
            // Gauss-Jordan elimination with partial pivoting.
            double m[5][6] = {};
            for (int k = 0; k < kDepths; ++k) {
                const double t = (column[k] - centre) * inv_half;
                const double row[5] = {1.0, t, t * t, t * t * t, -t * depth[k]};
                for (int i = 0; i < 5; ++i) {
                    for (int j = 0; j < 5; ++j)
                        m[i][j] += row[i] * row[j];
                    m[i][5] += row[i] * depth[k];
                }
            }
            for (int c = 0; c < 5; ++c) {
                int pivot = c;
                for (int r = c + 1; r < 5; ++r)
                    if (std::abs(m[r][c]) > std::abs(m[pivot][c]))
                        pivot = r;
                for (int j = 0; j < 6; ++j)
                    std::swap(m[c][j], m[pivot][j]);
                for (int r = 0; r < 5; ++r) {
                    if (r == c)
                        continue;
                    const double f = m[r][c] / m[c][c];
                    for (int j = c; j < 6; ++j)
                        m[r][j] -= f * m[c][j];
                }
            }
            table.set(table_plane::centre, x, y, static_cast<float>(centre));
            table.set(table_plane::inv_half_range, x, y, static_cast<float>(inv_half));
            for (int i = 0; i < 4; ++i)
                table.set(table_plane::rational_z + i, x, y, static_cast<float>(m[i][5] / m[i][i]));
            table.set(table_plane::rational_d, x, y, static_cast<float>(m[4][5] / m[4][4]));
            table.set(table_plane::rational_xn, x, y, static_cast<float>(n[0]));
            table.set(table_plane::rational_yn, x, y, static_cast<float>(n[1]));
        }
    }
    return table;
}

} // namespace fpp::test
