#pragma once
// The points of an organised cloud (3-channel float image, camera frame, mm,
// NaN = none) as Eigen vectors, for the artefact searches
// (artefact_search.cpp, plate_search.cpp).

#include "fpp/image.hpp"
#include "fpp/lens_model.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace fpp::calib::organised {

using Eigen::Vector3d;

inline Vector3d point_at(const Image<float>& xyz, std::size_t i) {
    const float* p = xyz.data() + 3 * i;
    return {double(p[0]), double(p[1]), double(p[2])};
}

inline bool finite_at(const Image<float>& xyz, std::size_t i) {
    const float* p = xyz.data() + 3 * i;
    return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

inline Vec3 to_vec(const Vector3d& v) {
    return {v.x(), v.y(), v.z()};
}
inline Vector3d to_eigen(const Vec3& v) {
    return {v[0], v[1], v[2]};
}

// The median of |values|; 0 for none.
inline double median_abs(std::vector<double> values) {
    if (values.empty())
        return 0;
    for (double& v : values)
        v = std::abs(v);
    std::nth_element(values.begin(), values.begin() + std::ptrdiff_t(values.size() / 2),
                     values.end());
    return values[values.size() / 2];
}

} // namespace fpp::calib::organised
