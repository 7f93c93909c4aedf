#include "fpp/decode_accuracy.hpp"

#include "fpp/error.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace fpp {

AxisAccuracy compare_to_truth(const Image<float>& decoded, const Image<float>& truth, int channel,
                              double period) {
    if (decoded.size() != truth.size() || channel < 0 || channel >= truth.channels() ||
        decoded.channels() != 1)
        throw InputError("compare_to_truth",
                         channel < 0 || channel >= truth.channels() ? "channel" : "truth",
                         "decoded and truth images do not match");

    AxisAccuracy acc;
    std::vector<float> abs_errors;
    abs_errors.reserve(decoded.pixel_count());
    double sum_sq = 0, sum_abs = 0;
    for (int y = 0; y < decoded.height(); ++y) {
        for (int x = 0; x < decoded.width(); ++x) {
            const float d = decoded.at(x, y);
            const float t = truth.at(x, y, channel);
            const bool has_truth = std::isfinite(t), has_decoded = std::isfinite(d);
            acc.truth_valid += has_truth;
            acc.decoded_valid += has_decoded;
            if (has_decoded && !has_truth)
                ++acc.false_valid;
            if (!(has_truth && has_decoded))
                continue;
            ++acc.compared;
            const double e = std::abs(double(d) - double(t));
            if (e > period / 2) {
                ++acc.unwrap_errors;
                continue;
            }
            sum_sq += e * e;
            sum_abs += e;
            acc.max_abs_px = std::max(acc.max_abs_px, e);
            abs_errors.push_back(static_cast<float>(e));
        }
    }
    if (!abs_errors.empty()) {
        const double n = double(abs_errors.size());
        acc.rms_px = std::sqrt(sum_sq / n);
        acc.mean_abs_px = sum_abs / n;
        const auto k = static_cast<std::size_t>(0.99 * (n - 1));
        std::nth_element(abs_errors.begin(), abs_errors.begin() + static_cast<std::ptrdiff_t>(k),
                         abs_errors.end());
        acc.p99_abs_px = abs_errors[k];
    }
    return acc;
}

} // namespace fpp
