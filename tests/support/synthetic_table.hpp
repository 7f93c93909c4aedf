#pragma once
// A coefficient table of known, analytic coefficients for the kernel's
// tests (test_table_kernel, test_phase_noise): camera 100 x 37, so 32 x 8
// tiles leave edge tiles in both directions; every 23rd pixel or so has no
// model. Camera frame, mm; phase in projector pixels.
#include "fpp/coefficient_table.hpp"

namespace fpp::test {

inline constexpr Size kSyntheticCamera{100, 37};
inline constexpr double kSyntheticHalfRange = 150.0; // projector px each side of a centre

// The analytic surface the tables come from: pixel (x, y) sees its centre
// phase at a depth of ~800 mm; the cubics are smooth and of realistic size
// (Z spans about 240 mm over the phase range).
struct SyntheticPixel {
    double centre, ihr;
    double c[3][4]; // X, Y, Z coefficients (polynomial); Z in c[2] (ray)
    double xn, yn;
};

inline SyntheticPixel synthetic_pixel(int x, int y) {
    SyntheticPixel p{};
    p.centre = 300.0 + 7.3 * x + 0.41 * y;
    p.ihr = 1.0 / (kSyntheticHalfRange + 0.5 * (x % 5));
    p.xn = (x - 50.0) / 120.0;
    p.yn = (y - 18.0) / 120.0;
    const double z[4] = {800.0 + 0.2 * y, -120.0 + 0.1 * x, 6.0 - 0.01 * y, -1.5 + 0.003 * x};
    for (int k = 0; k < 4; ++k) {
        p.c[2][k] = z[k];
        // X and Y follow the ray with a small bend, as a distorted ray would.
        p.c[0][k] = p.xn * z[k] + (k == 2 ? 0.4 : 0.0);
        p.c[1][k] = p.yn * z[k] + (k == 3 ? -0.3 : 0.0);
    }
    return p;
}

inline bool synthetic_has_model(int x, int y) {
    return (x * 7 + y * 3) % 23 != 0;
}

// The table of `model` with tiles of tw x th; the rational model's
// denominator 1 + d t has |d| <= 0.15, a pole outside the range as the fit
// keeps it (|d| < 0.9).
inline CoefficientTable synthetic_table(TableModel model, int tw = 32, int th = 8) {
    TableInfo info;
    info.camera = kSyntheticCamera;
    info.tile_width = tw;
    info.tile_height = th;
    info.model = model;
    info.projector = {1280, 800};
    CoefficientTable table(info);
    namespace tp = table_plane;
    for (int y = 0; y < kSyntheticCamera.height; ++y) {
        for (int x = 0; x < kSyntheticCamera.width; ++x) {
            if (!synthetic_has_model(x, y))
                continue;
            const SyntheticPixel p = synthetic_pixel(x, y);
            table.set(tp::centre, x, y, float(p.centre));
            table.set(tp::inv_half_range, x, y, float(p.ihr));
            for (int k = 0; k < 4; ++k) {
                if (model == TableModel::polynomial) {
                    table.set(tp::poly_x + k, x, y, float(p.c[0][k]));
                    table.set(tp::poly_y + k, x, y, float(p.c[1][k]));
                    table.set(tp::poly_z + k, x, y, float(p.c[2][k]));
                } else {
                    table.set(tp::ray_z + k, x, y, float(p.c[2][k]));
                }
            }
            if (model == TableModel::ray) {
                table.set(tp::ray_xn, x, y, float(p.xn));
                table.set(tp::ray_yn, x, y, float(p.yn));
            } else if (model == TableModel::rational) {
                table.set(tp::rational_d, x, y, float(0.15 - 0.004 * (x % 50)));
                table.set(tp::rational_xn, x, y, float(p.xn));
                table.set(tp::rational_yn, x, y, float(p.yn));
            }
        }
    }
    return table;
}

} // namespace fpp::test
